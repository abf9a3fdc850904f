"""Rollouts without learning: per-interaction metrics of a trained agent."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import jax
import numpy as np

from lili.agents.base import Agent, check_seed
from lili.buffer import InteractionBuffer
from lili.env_calls import env_reset, where
from lili.train import Interaction, rollout

__all__ = ["evaluate", "Episodes"]


class Episodes:
    """Plays consecutive interactions of a trained agent on an env, without learning.

    The acting state is carried exactly as in training: z^1 from ``initial_state()``, then
    after each interaction ``next_state`` of a small buffer holding the last N + 1
    interactions, and within an interaction the state each step returns. The agent's own
    observation wrapper is applied to ``env`` (the Oracle's, which appends the partner's
    strategy; without it an Oracle would act on observations it never trained on). Used by
    :func:`evaluate` and by step-by-step drivers (the play page, videos).
    """

    def __init__(self, agent: Any, env: gym.Env, seed: int, deterministic: bool = True,
                 key_seed: int | None = None) -> None:
        """``seed`` starts the env's sequence; ``key_seed`` (default ``seed``) the actions'
        noise when ``deterministic`` is False."""
        self.agent, self.env, self.deterministic = agent, agent.wrap_env(env), deterministic
        self.buffer = InteractionBuffer(max(2, agent.history + 1), agent.horizon, agent.obs_dim,
                                        agent.act_dim)
        self.key = jax.random.PRNGKey(seed if key_seed is None else key_seed)
        self.obs, self.info = env_reset(self.env, where(0), seed=seed)
        self.acting = agent.initial_state()
        self.index = 0

    def play(self, on_step: Any = None) -> Interaction:
        """Play the next interaction; ``on_step(obs, t)`` is called before every step."""
        agent, k = self.agent, jax.random.fold_in(self.key, self.index)

        def act(o, s):
            if on_step is not None:
                on_step(o, int(s.t))
            return agent.act(o, s, k, self.deterministic)

        done = rollout(self.env, self.obs, self.info, act, self.acting, agent.scale_action,
                       agent.horizon, self.index)
        self.obs, self.info = env_reset(self.env, where(self.index + 1))
        self.buffer.add(done["traj"], self.obs)
        self.acting = agent.next_state(self.buffer)
        self.index += 1
        return done


def evaluate(
    agent: Agent,
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
    env = agent.env if env is None else env
    episodes = Episodes(agent, env, agent.seed if seed is None else check_seed(seed),
                        deterministic, key_seed=0 if seed is None else seed)
    on_step = None if frames is None else (lambda o, t: frames.append(env.render()))
    out: dict[str, list] = {"returns": [], "successes": [], "strategies": [], "strategy_ids": []}
    for _ in range(n_interactions):
        done = episodes.play(on_step)
        out["returns"].append(done["ret"])
        out["successes"].append(done["success"])
        out["strategies"].append(done["strategy"].tolist())
        out["strategy_ids"].append(done["strategy_id"])
    succ = [s for s in out["successes"] if s is not None]
    return {**out, "mean_return": float(np.mean(out["returns"])),
            "success_rate": float(np.mean(succ)) if succ else None}
