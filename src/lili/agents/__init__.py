"""Agents. Every agent is the SAC core of :mod:`lili.agents.sac` plus, for some, a latent.

Each name here is a Stable-Baselines3-style facade (``SAC(env).learn(n).save(p)``) over a core
of pure functions (``agent.core``); see :mod:`lili.agents.base` for the shared types.
"""

from __future__ import annotations

import math

from lili.agents.base import ActingState, AgentState, CheckpointError, check_seed
from lili.agents.lilac import LILAC
from lili.agents.lili import LILI
from lili.agents.random_policy import RandomPolicy
from lili.agents.sac import AGENTS, SAC, Oracle, load_agent, make_agent
from lili.agents.slac import SLAC
from lili.config import AgentConfig

__all__ = ["SAC", "Oracle", "LILI", "LILAC", "ALGOS", "make_agent", "load_agent", "CheckpointError",
           "ActingState", "AgentState", "LatentState", "SLAC", "RandomPolicy", "check_seed"]

LatentState = ActingState  # the name of earlier releases

ALGOS = ("sac", "oracle", "lili", "lili-no-influence", "lilac", "slac", "random")
"""Every algo name (``lili train --algo``), in the order reports list them."""
assert set(ALGOS) == set(AGENTS), "every agent module registers its algo names"


def check_extra(config: AgentConfig) -> None:
    """ValueError unless every entry of ``config.extra`` is an agent with options and its
    options are valid, whichever algo the config is for: an entry no agent reads (``extra:
    {slac: {bogus: 1}}`` with ``--algo lili``) would otherwise be ignored silently."""
    from lili.agents import lilac, slac

    checks = {"slac": slac._options, "lilac": lilac._options}
    for key in config.extra:
        if key not in checks:
            raise ValueError(f"config extra.{key} is invalid: {key!r} is not an agent with "
                             f"options; allowed: {', '.join(checks)}")
        for name, value in config.extra[key].items():
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(f"config extra.{key}.{name}={value!r} is invalid; allowed: a "
                                 "finite number")
        checks[key](config)
