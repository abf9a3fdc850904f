"""Agents. Every agent is the SAC core of :mod:`lili.agents.sac` plus, for some, a latent.

Each name here is a Stable-Baselines3-style facade (``SAC(env).learn(n).save(p)``) over a core
of pure functions (``agent.core``); see :mod:`lili.agents.base` for the shared types.
"""

from __future__ import annotations

from lili.agents.base import ActingState, AgentState, CheckpointError, check_seed
from lili.agents.lilac import LILAC
from lili.agents.lili import LILI
from lili.agents.random_policy import RandomPolicy
from lili.agents.sac import AGENTS, SAC, Oracle, check_config, check_extra, load_agent, make_agent
from lili.agents.slac import SLAC

__all__ = ["SAC", "Oracle", "LILI", "LILAC", "ALGOS", "make_agent", "load_agent", "check_config",
           "CheckpointError",
           "ActingState", "AgentState", "LatentState", "SLAC", "RandomPolicy", "check_seed",
           "check_extra"]

LatentState = ActingState  # the name of earlier releases

ALGOS = ("sac", "oracle", "lili", "lili-no-influence", "lilac", "slac", "random",
         "oracle-last")
"""Every algo name (``lili train --algo``), in the order reports list them."""
assert set(ALGOS) == set(AGENTS), "every agent module registers its algo names"
