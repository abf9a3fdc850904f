"""The environment contract: one Gymnasium episode is one interaction with a partner.

A :class:`RepeatedInteractionEnv` owns a :class:`Partner`. The partner's strategy is fixed during
an interaction; when the interaction ends (terminated or truncated) the env hands the partner an
``outcome`` of that interaction and the partner picks its next strategy. ``reset(seed=s)`` restarts
the whole sequence (interaction 0, fresh partner, everything drawn from ``s``); ``reset()`` without
a seed continues it with interaction ``i + 1``.

Subclasses implement four small hooks (``_begin``, ``_step``, ``_outcome`` and optionally
``_success``) and never touch the bookkeeping: interaction index, horizon, ``info`` keys and the
partner's update all live here, so that every env honours the contract the same way.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np
from gymnasium import spaces

__all__ = ["Partner", "RepeatedInteractionEnv", "register_envs", "ENV_ALIASES", "resolve_env_id",
           "env_horizon"]


@runtime_checkable
class Partner(Protocol):
    """The other agent's strategy dynamics, z^{i+1} ~ f(z^i, tau^i).

    A partner is plain Python state driven by a NumPy generator that the env passes in, so that
    ``reset(seed)`` replays the same sequence of strategies.
    """

    strategy_space: spaces.Box

    def reset(self, rng: np.random.Generator) -> None:
        """Start a fresh sequence: draw the first strategy from ``rng``."""

    def strategy(self) -> np.ndarray:
        """The current strategy as a float32 vector in ``strategy_space``."""

    def strategy_id(self) -> int | None:
        """A discrete label of the current strategy (lane, mode), or None."""

    def update(self, outcome: Any, rng: np.random.Generator) -> None:
        """Choose the next strategy after an interaction that ended with ``outcome``."""


class RepeatedInteractionEnv(gym.Env):
    """Base class for repeated-interaction environments (one episode = one interaction).

    Subclasses set ``observation_space``, ``action_space``, ``horizon`` and ``partner`` in
    ``__init__`` and implement:

    - ``_begin() -> obs``: set up a new interaction under ``self.partner``'s current strategy.
    - ``_step(action) -> (obs, reward, terminated)``: advance one step.
    - ``_outcome() -> Any``: what the partner reacts to (e.g. "ended inside the circle").
    - ``_success() -> bool | None``: optional success flag for the last step.

    ``info`` on every step and reset carries ``strategy`` (float32 vector), ``strategy_id``
    (where defined; -1 otherwise), ``interaction`` (0-based index) and ``t`` (steps taken in this
    interaction); the last step of an interaction also carries ``success`` where defined and
    ``outcome``, what the partner reacts to (``_outcome()``).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 10}
    strategy_names: tuple[str, ...] = ()
    """Names of the partner's discrete strategies, ``strategy_id`` 0, 1, ... (reports label
    them so); empty where they have none."""
    horizon: int
    partner: Partner

    def __init__(self, render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode={render_mode!r} is not supported; allowed: "
                f"{self.metadata['render_modes']} or None"
            )
        self.render_mode = render_mode
        self.interaction = -1
        self.t = 0
        self._done = True
        self._partner_rng = np.random.default_rng()

    @property
    def strategy_space(self) -> spaces.Box:
        """Space of ``info["strategy"]`` (the partner's true strategy)."""
        return self.partner.strategy_space

    # -- hooks for subclasses -------------------------------------------------------------
    def _begin(self) -> np.ndarray:
        raise NotImplementedError

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        raise NotImplementedError

    def _outcome(self) -> Any:
        raise NotImplementedError

    def _success(self) -> bool | None:
        return None

    # -- Gymnasium API -----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start the next interaction, or with ``seed`` restart the whole sequence."""
        super().reset(seed=seed)
        if seed is not None or self.interaction < 0:
            # The partner's randomness is its own stream so that the ego's env randomness (e.g.
            # initial states) and the partner's choices cannot shift each other.
            self._partner_rng = np.random.default_rng(self.np_random.integers(2**63))
            self.partner.reset(self._partner_rng)
            self.interaction = 0
        else:
            # An interaction abandoned before its end does not update the partner: the contract
            # is that strategies change only between finished interactions.
            self.interaction += 1
        self.t = 0
        self._done = False
        obs = self._begin()
        return obs, self._info()

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance one step; on the last step the partner updates for the next interaction."""
        if self._done:
            raise RuntimeError("step() called after the interaction ended; call reset() first")
        action = np.asarray(action, dtype=np.float32)
        if action.shape != self.action_space.shape:
            raise ValueError(
                f"action has shape {action.shape}; expected {self.action_space.shape}"
            )
        obs, reward, terminated = self._step(action)
        self.t += 1
        truncated = (not terminated) and self.t >= self.horizon
        info = self._info()
        if terminated or truncated:
            success = self._success()
            if success is not None:
                info["success"] = bool(success)
            outcome = self._outcome()
            info["outcome"] = outcome
            self.partner.update(outcome, self._partner_rng)
            self._done = True
        return obs, float(reward), bool(terminated), bool(truncated), info

    def _info(self) -> dict[str, Any]:
        sid = self.partner.strategy_id()
        return {
            "strategy": np.asarray(self.partner.strategy(), dtype=np.float32),
            "strategy_id": -1 if sid is None else int(sid),
            "interaction": self.interaction,
            "t": self.t,
        }


ENV_ALIASES: dict[str, str] = {
    "point-mass": "lili/PointMass-v0",
    "driving-2d": "lili/Driving2D-v0",
    "lunar-lander": "lili/LunarLander-v0",
    "driving-steer": "lili/DrivingSteer-v0",
    "air-hockey": "lili/AirHockey-v0",
    "influence-drift": "lili/InfluenceDrift-v0",
    "influence-switch": "lili/InfluenceSwitch-v0",
    "influence-flee": "lili/InfluenceFlee-v0",
}


def resolve_env_id(name: str) -> str:
    """Map a short alias (``point-mass``) or a registered id to the registered id.

    Raises ``ValueError`` naming the bad value and the allowed ones.
    """
    register_envs()
    if name in ENV_ALIASES:
        return ENV_ALIASES[name]
    if name in gym.registry:
        return name
    allowed = sorted(ENV_ALIASES) + sorted(ENV_ALIASES.values())
    raise ValueError(f"unknown env {name!r}; allowed: {', '.join(allowed)}")


def register_envs() -> None:
    """Register the library's envs with Gymnasium (idempotent)."""
    specs = {
        "lili/PointMass-v0": "lili.envs.point_mass:PointMassEnv",
        "lili/Driving2D-v0": "lili.envs.driving2d:Driving2DEnv",
        "lili/LunarLander-v0": "lili.envs.lunar_lander:LunarLanderEnv",
        "lili/DrivingSteer-v0": "lili.envs.driving_steer:DrivingSteerEnv",
        "lili/AirHockey-v0": "lili.envs.air_hockey:AirHockeyEnv",
        "lili/InfluenceDrift-v0": "lili.envs.influence:InfluenceDriftEnv",
        "lili/InfluenceSwitch-v0": "lili.envs.influence:InfluenceSwitchEnv",
        "lili/InfluenceFlee-v0": "lili.envs.influence:InfluenceFleeEnv",
    }
    for env_id, entry in specs.items():
        if env_id not in gym.registry:
            # No max_episode_steps: the env ends its own interactions at its horizon, so that the
            # partner update happens inside the env and not in a wrapper.
            gym.register(id=env_id, entry_point=entry)


def env_horizon(env: gym.Env) -> int:
    """The interaction length H of ``env``.

    ``env.unwrapped.horizon`` where the env defines it (every ``RepeatedInteractionEnv`` does),
    else the ``max_episode_steps`` of its spec, else that of a ``TimeLimit`` wrapper; otherwise
    one ValueError that says how to give one.
    """
    h = getattr(env.unwrapped, "horizon", None)
    if h is None and env.spec is not None:
        h = env.spec.max_episode_steps
    inner = env
    while h is None and isinstance(inner, gym.Wrapper):
        if isinstance(inner, gym.wrappers.TimeLimit):
            h = inner._max_episode_steps
        inner = inner.env
    if isinstance(h, bool) or not isinstance(h, (int, np.integer)) or h < 1:
        raise ValueError(
            f"env {type(env.unwrapped).__name__} has no interaction length (horizon={h!r}); "
            "allowed: an integer `horizon` >= 1 on the env (a RepeatedInteractionEnv has one), "
            "or register it with max_episode_steps, or wrap it in gymnasium's TimeLimit"
        )
    return int(h)
