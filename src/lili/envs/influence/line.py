"""The shared body of the suite's envs: an ego on a line that chases its partner's goal.

The ego starts every interaction at x = 0 and moves ``x <- clip(x + speed * a, -1, 1)`` with
``a`` in [-1, 1]; each step pays ``-|x - goal|`` (after the move), where ``goal`` is what the
partner's current strategy asks for. It observes only ``x``. Subclasses give the partner, the
speed and the horizon; the partner reacts to :meth:`LineEnv._outcome`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from lili.envs.core import RepeatedInteractionEnv
from lili.envs.partners import check_probability

__all__ = ["LineEnv", "check_horizon", "check_probability", "move_to", "moved"]


def check_horizon(horizon: Any, low: int) -> int:
    """Validate an integer horizon >= ``low``; raise ``ValueError`` naming the value."""
    if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or horizon < low:
        raise ValueError(f"horizon={horizon!r} is invalid; allowed: an integer >= {low}")
    return int(horizon)


def move_to(x: float, target: float, speed: float) -> np.ndarray:
    """The action that moves from ``x`` toward ``target`` as fast as allowed, stopping on it."""
    return np.array([np.clip((target - x) / speed, -1.0, 1.0)], np.float32)


def moved(x: float, action: float, speed: float) -> float:
    """Where one step of ``action`` (clipped to [-1, 1]) takes the ego from ``x``: the line's
    dynamics, which scripts that replay an interaction read here too."""
    return float(np.clip(x + speed * float(np.clip(action, -1.0, 1.0)), -1.0, 1.0))


class LineEnv(RepeatedInteractionEnv):
    """Base of the suite's envs (see the module docstring); one float32 observation, ``[x]``."""

    speed: float

    def __init__(self, horizon: int, speed: float, render_mode: str | None = None) -> None:
        super().__init__(render_mode)
        self.horizon, self.speed = horizon, float(speed)
        self.observation_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.x = 0.0
        self.last_action = 0.0

    def goal(self) -> float:
        """Where the partner's current strategy wants the ego."""
        raise NotImplementedError

    def _begin(self) -> np.ndarray:
        self.x, self.last_action = 0.0, 0.0
        return np.array([self.x], np.float32)

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        self.last_action = float(np.clip(action[0], -1.0, 1.0))
        self.x = moved(self.x, self.last_action, self.speed)
        return np.array([self.x], np.float32), -abs(self.x - self.goal()), False

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        from lili.envs.rendering import Canvas

        canvas = Canvas(200, 40, (-1.05, 1.05), (-0.2, 0.2))
        canvas.vline(0.0, (200, 200, 200))
        canvas.circle((self.goal(), 0.0), 0.06, (220, 60, 60))
        canvas.circle((self.x, 0.0), 0.04, (40, 90, 220))
        return canvas.image
