"""Variants of the core agents that were measured and gave no gain, kept runnable.

As Stable-Baselines3 keeps such work in sb3-contrib "to maintain a stable and compact core",
each variant here subclasses a core agent (:mod:`lili.agents.lili`), is registered under its own
algo name in :data:`lili.agents.registry.TABLE` (``lili train --algo lili-categorical``), and
takes its options from ``AgentConfig.extra[<algo>]`` as a small frozen dataclass. README.md
"Contrib variants" lists each with the measurement that put it here.
"""
