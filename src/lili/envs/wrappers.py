"""Wrappers over repeated-interaction envs."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

__all__ = ["OracleObservation"]


class OracleObservation(gym.ObservationWrapper):
    """Append the partner's true strategy (``info["strategy"]``) to the observation.

    SAC on this wrapper is the paper's Oracle. Because the first observation of interaction
    i + 1 carries z^{i+1}, an Oracle that bootstraps across interactions can learn to influence.
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        inner = env.unwrapped
        strat = getattr(inner, "strategy_space", None)
        if not isinstance(strat, spaces.Box) or len(strat.shape) != 1:
            raise ValueError(
                f"the Oracle needs the partner's true strategy, and env {type(inner).__name__} "
                f"has no flat Box `strategy_space` (got {strat!r}); allowed: an env that defines "
                "strategy_space and info['strategy'] (every RepeatedInteractionEnv does)"
            )
        obs_space = env.observation_space
        if not isinstance(obs_space, spaces.Box) or len(obs_space.shape) != 1:
            raise ValueError(f"OracleObservation needs a flat Box observation; got {obs_space}")
        self.observation_space = spaces.Box(
            np.concatenate([obs_space.low, strat.low]).astype(np.float32),
            np.concatenate([obs_space.high, strat.high]).astype(np.float32),
            dtype=np.float32,
        )
        self._strategy = np.zeros(strat.shape, dtype=np.float32)

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        if "strategy" not in info:
            raise ValueError(f"the Oracle needs info['strategy'] from reset(); env "
                             f"{type(self.env.unwrapped).__name__} gave keys {sorted(info)}")
        self._strategy = np.asarray(info["strategy"], dtype=np.float32)
        return self.observation(obs), info

    def step(self, action: Any):
        obs, reward, terminated, truncated, info = self.env.step(action)
        # Within an interaction the strategy is fixed; the info of the last step already shows
        # the next one, which belongs to the next reset's observation, not to this one.
        return self.observation(obs), reward, terminated, truncated, info

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return np.concatenate([np.asarray(observation, dtype=np.float32), self._strategy])
