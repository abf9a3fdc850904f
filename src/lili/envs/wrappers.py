"""Wrappers over repeated-interaction envs."""

from __future__ import annotations

import inspect
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

__all__ = ["OracleObservation", "LastInteractionObservation"]


def strategy_box(env: gym.Env, who: str) -> spaces.Box:
    """The env's flat Box ``strategy_space``, or a ValueError saying that ``who`` needs it."""
    inner = env.unwrapped
    strat = getattr(inner, "strategy_space", None)
    if not isinstance(strat, spaces.Box) or len(strat.shape) != 1:
        raise ValueError(
            f"{who} needs the partner's true strategy, and env {type(inner).__name__} has no "
            f"flat Box `strategy_space` (got {strat!r}); allowed: an env that defines "
            "strategy_space and info['strategy'] (every RepeatedInteractionEnv does)"
        )
    return strat


def reset_strategy(env: gym.Env, info: dict[str, Any], who: str) -> np.ndarray:
    """``info["strategy"]`` of a reset as float32, or a ValueError saying that ``who`` needs it."""
    if "strategy" not in info:
        raise ValueError(f"{who} needs info['strategy'] from reset(); env "
                         f"{type(env.unwrapped).__name__} gave keys {sorted(info)}")
    return np.asarray(info["strategy"], dtype=np.float32)


class OracleObservation(gym.ObservationWrapper):
    """Append the partner's true strategy (``info["strategy"]``) to the observation.

    SAC on this wrapper is the paper's Oracle. Because the first observation of interaction
    i + 1 carries z^{i+1}, an Oracle that bootstraps across interactions can learn to influence.
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        strat = strategy_box(env, "the Oracle")
        obs_space = env.observation_space
        if not isinstance(obs_space, spaces.Box) or len(obs_space.shape) != 1:
            raise ValueError(f"OracleObservation needs a flat Box observation; got {obs_space}")
        self.observation_space = spaces.Box(
            np.concatenate([obs_space.low, strat.low]).astype(np.float32),
            np.concatenate([obs_space.high, strat.high]).astype(np.float32),
            dtype=np.float32,
        )
        self._strategy = np.zeros(strat.shape, dtype=np.float32)

    def reset(self, **kwargs: Any) -> tuple[np.ndarray, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self._strategy = reset_strategy(self.env, info, "the Oracle")
        return self.observation(obs), info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        # Within an interaction the strategy is fixed; the info of the last step already shows
        # the next one, which belongs to the next reset's observation, not to this one.
        return self.observation(obs), reward, terminated, truncated, info

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return np.concatenate([np.asarray(observation, dtype=np.float32), self._strategy])


class LastInteractionObservation(gym.Wrapper):
    """Append what a perfect encoder of the last interaction could report: the partner's
    strategy during it (``info["strategy"]``) and how it ended (its last observation and last
    action); zeros before the first interaction of a sequence.

    SAC on this wrapper is the "Oracle (last interaction)": told everything about tau^{i-1}
    that the partner's next move depends on in the suite's envs, and nothing about interaction
    i itself. It bounds from above what LILI, whose encoder reads only tau^{i-1}, can get from
    its latent. Where it falls short of the Oracle, the last interaction does not determine the
    partner's next strategy or acting on it is harder to learn (in Drift both, see
    ``docs/journal/2026-11-to-12.md``, "Drift with a returning partner").

    With ``outcome=True`` it also appends the last interaction's ``info["outcome"]`` (what the
    partner reacts to, a number), for envs whose last observation leaves it out: in air hockey
    the side of the paddle where the puck ended, which the blocker never observes. Told the
    last strategy and outcome, it is told everything the partner's next strategy depends on
    except the partner's own randomness.
    """

    def __init__(self, env: gym.Env, outcome: bool = False) -> None:
        if not isinstance(outcome, bool):
            raise ValueError(f"outcome={outcome!r} is invalid; allowed: True or False")
        super().__init__(env)
        self.with_outcome = outcome
        declared = getattr(type(env.unwrapped), "_outcome", None)
        returns = "" if declared is None else str(inspect.signature(declared).return_annotation)
        if outcome and "ndarray" in returns:
            # Checked here, when the agent is built, so that a run fails before its folder is
            # written; an env that declares nothing is checked at its first outcome.
            raise ValueError(
                f"the last-interaction Oracle with outcome=True needs an outcome that is one "
                f"number; env {type(env.unwrapped).__name__} declares _outcome() -> {returns}; "
                "allowed: an env whose outcome is a number (not Lunar Lander's vector)")
        strat = strategy_box(env, "the last-interaction Oracle")
        obs_space, act_space = env.observation_space, env.action_space
        for name, space in (("observation", obs_space), ("action", act_space)):
            if not isinstance(space, spaces.Box) or len(space.shape) != 1:
                raise ValueError(f"LastInteractionObservation needs a flat Box {name} space; "
                                 f"got {space}")
        parts = [obs_space, strat, obs_space, act_space]
        if outcome:
            parts.append(spaces.Box(-np.inf, np.inf, shape=(1,), dtype=np.float32))
        self.observation_space = spaces.Box(
            np.concatenate([p.low for p in parts]).astype(np.float32),
            np.concatenate([p.high for p in parts]).astype(np.float32), dtype=np.float32)
        self._sizes = (strat.shape[0], obs_space.shape[0], act_space.shape[0], int(outcome))
        self._clear()

    def _clear(self) -> None:
        self._last = np.zeros(sum(self._sizes), np.float32)
        self._strategy = np.zeros(self._sizes[0], np.float32)
        self._obs = np.zeros(self._sizes[1], np.float32)
        self._act = np.zeros(self._sizes[2], np.float32)
        self._outcome = np.zeros(self._sizes[3], np.float32)
        self._started = False

    def reset(self, **kwargs: Any) -> tuple[np.ndarray, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        strategy = reset_strategy(self.env, info, "the last-interaction Oracle")
        if kwargs.get("seed") is not None or not self._started:
            # A seeded reset starts a new sequence: nothing came before it.
            self._clear()
        else:
            self._last = np.concatenate([self._strategy, self._obs, self._act, self._outcome])
        self._started = True
        self._strategy = strategy
        self._obs = np.asarray(obs, np.float32)
        return self._observation(obs), info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._obs = np.asarray(obs, np.float32)
        self._act = np.asarray(action, np.float32).reshape(self._sizes[2])
        if self.with_outcome and (terminated or truncated):
            self._outcome = np.array([_scalar_outcome(self.env, info)], np.float32)
        return self._observation(obs), reward, terminated, truncated, info

    def _observation(self, observation: np.ndarray) -> np.ndarray:
        return np.concatenate([np.asarray(observation, np.float32), self._last])


def _scalar_outcome(env: gym.Env, info: dict[str, Any]) -> float:
    """The last step's ``info["outcome"]`` as a float, or a ValueError naming what it was."""
    value = info.get("outcome")
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.item()
    if not isinstance(value, (bool, int, float, np.bool_, np.integer, np.floating)) \
            or not np.isfinite(float(value)):
        raise ValueError(
            f"the last-interaction Oracle with outcome=True needs info['outcome'] on the last "
            f"step as one finite number; env {type(env.unwrapped).__name__} gave {value!r}; "
            "allowed: an env whose outcome is a number (not Lunar Lander's vector)")
    return float(value)
