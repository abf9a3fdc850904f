"""Agents. Every agent is the SAC core of :mod:`lili.agents.core` plus, for some, a latent.

Each name here is a Stable-Baselines3-style facade (``SAC(env).learn(n).save(p)``) over a core
of pure functions (``agent.core``); see :mod:`lili.agents.base` for the shared types and
:mod:`lili.agents.registry` for the one ordered list of algos. The names are imported on first
use, so that reading the registry (the report, ``lili reproduce --dry-run``) imports no JAX.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["SAC", "Oracle", "LILI", "LILAC", "ALGOS", "make_agent", "load_agent", "check_config",
           "CheckpointError", "ActingState", "AgentState", "LatentState", "SLAC", "RandomPolicy",
           "check_seed", "check_extra"]

_HOME = {
    "SAC": "lili.agents.sac", "Oracle": "lili.agents.oracle", "LILI": "lili.agents.lili",
    "LILAC": "lili.agents.lilac", "SLAC": "lili.agents.slac",
    "RandomPolicy": "lili.agents.random_policy",
    **dict.fromkeys(("ALGOS", "make_agent", "load_agent", "check_config", "check_extra"),
                    "lili.agents.registry"),
    **dict.fromkeys(("CheckpointError", "ActingState", "AgentState", "check_seed"),
                    "lili.agents.base"),
}


def __getattr__(name: str) -> Any:
    if name == "LatentState":  # the name of earlier releases
        name = "ActingState"
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_HOME[name]), name)


def __dir__() -> list[str]:
    return sorted(__all__)
