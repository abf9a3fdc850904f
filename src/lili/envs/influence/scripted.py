"""Play scripted policies on a repeated-interaction env and summarise what they earned.

A scripted policy is any callable ``policy(obs, info) -> action``. It is handed the ``info`` of
the reset or step that produced ``obs``, so a policy that is *told* the partner's strategy reads
``info["strategy"]`` (or ``info["strategy_id"]``); a no-information policy ignores ``info``.
These are the reference points of the influence suite (no information, greedy, influencing)
and of the scripted tables in ``benchmarks/``; no learning agent uses them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["ScriptedPolicy", "Rollout", "play"]

ScriptedPolicy = Callable[[np.ndarray, dict[str, Any]], np.ndarray]


@dataclass
class Rollout:
    """Per-interaction records of one scripted run (arrays of length ``n_interactions``)."""

    returns: np.ndarray
    successes: np.ndarray  # float: 1 / 0, or nan where the env defines no success
    strategy_ids: np.ndarray
    lengths: np.ndarray

    def last(self, n: int) -> Rollout:
        """The records of the last ``n`` interactions."""
        return Rollout(self.returns[-n:], self.successes[-n:], self.strategy_ids[-n:],
                       self.lengths[-n:])

    def mean_return(self) -> float:
        return float(np.mean(self.returns))

    def success_rate(self) -> float:
        return float(np.mean(self.successes))

    def strategy_frequencies(self, n_strategies: int) -> np.ndarray:
        """How often each strategy id was played (fractions summing to 1)."""
        ids = self.strategy_ids[self.strategy_ids >= 0].astype(int)
        return np.bincount(ids, minlength=n_strategies)[:n_strategies] / max(1, len(ids))


def play(env: gym.Env, policy: ScriptedPolicy, n_interactions: int, seed: int) -> Rollout:
    """Play ``n_interactions`` interactions from ``env.reset(seed=seed)`` with ``policy``.

    Deterministic for a deterministic policy (or one with its own seeded generator): the env's
    whole sequence comes from ``seed``.
    """
    if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
            or n_interactions < 1:
        raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an integer >= 1")
    returns, successes, sids, lengths = [], [], [], []
    obs, info = env.reset(seed=seed)
    for i in range(n_interactions):
        if i:
            obs, info = env.reset()
        sid, ret, steps = info["strategy_id"], 0.0, 0
        while True:
            obs, r, term, trunc, info = env.step(policy(obs, info))
            ret, steps = ret + r, steps + 1
            if term or trunc:
                break
        returns.append(ret)
        successes.append(float(info["success"]) if "success" in info else np.nan)
        sids.append(sid)
        lengths.append(steps)
    return Rollout(np.array(returns), np.array(successes), np.array(sids), np.array(lengths))
