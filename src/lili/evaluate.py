"""Rollouts without learning: per-interaction metrics of a trained agent."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import jax
import numpy as np

from lili.agents.sac import SAC, LatentState
from lili.buffer import InteractionBuffer
from lili.train import rollout

__all__ = ["evaluate"]


def evaluate(
    agent: SAC,
    env: gym.Env | None = None,
    n_interactions: int = 100,
    seed: int | None = None,
    deterministic: bool = True,
    frames: list | None = None,
) -> dict[str, Any]:
    """Play ``n_interactions`` consecutive interactions with ``agent`` and no learning.

    The latent is updated between interactions exactly as in training (z^1 = 0, then
    z^{i+1} = E(tau^i)). ``env`` defaults to a fresh sequence of ``agent.env``; the Oracle's
    wrapper is applied when needed. With ``frames`` (a list) and an env made with
    ``render_mode="rgb_array"``, every step's frame is appended to it.

    Returns ``returns``, ``successes`` (None where undefined), ``strategies``,
    ``strategy_ids``, and their means ``mean_return`` and ``success_rate``.
    """
    if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
            or n_interactions < 1:
        raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an integer >= 1")
    env = agent.env if env is None else agent._wrap(env)
    buf = InteractionBuffer(max(2, agent.history + 1), agent.horizon, agent.obs_dim,
                            agent.act_dim)
    obs, info = env.reset(seed=agent.seed if seed is None else seed)
    state = agent.initial_state()
    key = jax.random.PRNGKey(0 if seed is None else seed)
    out: dict[str, list] = {"returns": [], "successes": [], "strategies": [], "strategy_ids": []}
    for i in range(n_interactions):
        k = jax.random.fold_in(key, i)

        def act(o, t, k=k, z=state.z):
            a = agent.policy_action(o, LatentState(z, t), jax.random.fold_in(k, t), deterministic)
            if frames is not None:
                frames.append(env.render())
            return a

        done = rollout(env, obs, info, act, agent.scale_action, agent.horizon)
        obs, info = env.reset()
        buf.add(done["traj"], obs)
        state = agent.next_latent_state(buf)
        out["returns"].append(done["ret"])
        out["successes"].append(done["success"])
        out["strategies"].append(done["strategy"].tolist())
        out["strategy_ids"].append(done["strategy_id"])
    succ = [s for s in out["successes"] if s is not None]
    return {**out, "mean_return": float(np.mean(out["returns"])),
            "success_rate": float(np.mean(succ)) if succ else None}
