"""Agents. Every agent shares the SAC core of :mod:`lili.agents.sac`."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym

from lili.agents.lilac import LILAC
from lili.agents.lili import LILI
from lili.agents.random_policy import RandomPolicy
from lili.agents.sac import SAC, CheckpointError, LatentState, Oracle, read_agent_file
from lili.agents.slac import SLAC
from lili.config import AgentConfig

__all__ = ["SAC", "Oracle", "LILI", "LILAC", "ALGOS", "make_agent", "load_agent", "CheckpointError",
           "LatentState", "SLAC", "RandomPolicy"]

ALGOS = ("sac", "oracle", "lili", "lili-no-influence", "lilac", "slac", "random")


def make_agent(algo: str, env: gym.Env, config: AgentConfig | dict | None = None,
               seed: int = 0) -> SAC:
    """Construct the agent named ``algo`` (one of :data:`ALGOS`)."""
    if algo == "sac":
        return SAC(env, config, seed)
    if algo == "oracle":
        return Oracle(env, config, seed)
    if algo in ("lili", "lili-no-influence"):
        return LILI(env, config, seed, influence=algo == "lili")
    if algo == "lilac":
        return LILAC(env, config, seed)
    if algo == "slac":
        return SLAC(env, config, seed)
    if algo == "random":
        return RandomPolicy(env, config, seed)
    raise ValueError(f"unknown algo {algo!r}; allowed: {', '.join(ALGOS)}")


def load_agent(path: str | Path, env: gym.Env) -> SAC:
    """Load any saved agent; its class comes from the file."""
    meta, state = read_agent_file(path)
    if meta.get("algo") not in ALGOS:
        raise CheckpointError(f"{path} holds an unknown algo {meta.get('algo')!r}")
    agent = make_agent(meta["algo"], env, AgentConfig.from_dict(meta["config"]), meta["seed"])
    agent._check_meta(meta, str(path))
    agent.load_state_bytes(state, str(path))
    agent.num_interactions = int(meta["num_interactions"])
    return agent
