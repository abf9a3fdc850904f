"""Variants of the core agents kept out of the core: those that were measured and gave no gain,
kept runnable (:mod:`lili.contrib.latents`), candidates waiting on their measurement
(:mod:`lili.contrib.critics`), and diagnoses of a baseline (:mod:`lili.contrib.slac`).

As Stable-Baselines3 keeps such work in sb3-contrib "to maintain a stable and compact core",
each variant here subclasses a core agent (:mod:`lili.agents.lili`, :mod:`lili.agents.slac`;
``Algo.variant_of`` in the registry names which), is registered under its own
algo name in :data:`lili.agents.registry.TABLE` (``lili train --algo lili-categorical``), and
takes its options from ``AgentConfig.extra[<algo>]`` as a small frozen dataclass
(:mod:`lili.contrib.variant`). README.md "Contrib variants" lists each with the measurement that
put it here, or says it is not yet measured.
"""
