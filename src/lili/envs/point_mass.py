"""Point Mass (the paper's Section 5 and appendix): reach a hidden target that moves on a circle.

Geometry (the paper's): the ego starts every interaction at the origin, moves by ``0.01 * a`` per
step with ``a`` in [-1, 1]^2, and its position is clipped to [-0.15, 0.15]^2. The target lies on a
circle of radius 0.1 centred at (0, -0.05), at angle theta. Reward per step = -||pos - target||.
An interaction lasts H = 50 steps. Afterwards theta moves 0.2 rad clockwise if the ego's final
position is inside the circle and 0.2 rad counter-clockwise otherwise. The origin is inside the
circle, 0.05 below its top, so targets near the top are cheaper to reach: that is what an
influencing agent exploits.

The history experiment (Appendix E.2) words its majority rule the other way round ("moves
counterclockwise if, in the majority of the last N interactions, the ego agent's final position
is inside of the circle"), while the same table's N = 1 row is the original setting (its
number, -0.7206, is the noise table's sigma = 0 row). The default (``inside_turn="clockwise"``)
keeps the original rule for every N, so that N = 1 is the original task;
``inside_turn="counterclockwise"`` is the history text's reading. The two are mirror images
(reflect x: the circle and the start are symmetric, clockwise and counter-clockwise swap,
inside and outside do not; only the grid of initial angles is not mirrored), so an agent's
expected return is the same under either; the preset ``history-text-rule`` measures it.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from lili.envs.core import RepeatedInteractionEnv
from lili.envs.partners import MajorityHistory, check_partner_options, noisy_step

__all__ = ["PointMassEnv", "CirclePartner", "INSIDE_TURNS"]

CENTER = np.array([0.0, -0.05], dtype=np.float64)
RADIUS = 0.1
STEP = 0.2
BOUND = 0.15
SPEED = 0.01
INSIDE_TURNS = ("clockwise", "counterclockwise")


class CirclePartner:
    """Target on a circle; moves clockwise after the ego ends inside, counter-clockwise otherwise.

    ``step_noise`` adds Gaussian noise to the step (sigma = ``step_noise * 0.2``); ``history``
    = N takes the direction from the majority of the last N outcomes (the paper's history
    experiment; N = 1 is the original rule). ``inside_turn`` is where the target moves when
    the ego (the majority of the last N outcomes) ended inside: ``"clockwise"`` (the appendix's
    Point Mass rule, the default) or ``"counterclockwise"`` (the history section's wording; see
    the module docstring). The initial angle is drawn on the 0.2 grid.
    """

    strategy_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)

    def __init__(self, step_noise: float = 0.0, history: int = 1,
                 inside_turn: str = "clockwise", strategy_votes: bool = False) -> None:
        check_partner_options(step_noise, history)
        if inside_turn not in INSIDE_TURNS:
            raise ValueError(f"inside_turn={inside_turn!r} is invalid; allowed: "
                             f"{', '.join(INSIDE_TURNS)}")
        if not isinstance(strategy_votes, (bool, np.bool_)):
            raise ValueError(f"strategy_votes={strategy_votes!r} is invalid; "
                             "allowed: true or false")
        self.strategy_votes = bool(strategy_votes)
        if self.strategy_votes:
            self.strategy_space = spaces.Box(-1.0, 1.0, shape=(2 + int(history),),
                                             dtype=np.float32)
        self.inside_sign = -1.0 if inside_turn == "clockwise" else 1.0
        self.step_noise = float(step_noise)
        self.votes = MajorityHistory(history)
        self.theta = 0.0

    def reset(self, rng: np.random.Generator) -> None:
        self.votes.clear()
        self.theta = STEP * int(rng.integers(0, int(2 * np.pi / STEP) + 1))

    def target(self) -> np.ndarray:
        return CENTER + RADIUS * np.array([np.cos(self.theta), np.sin(self.theta)])

    def strategy(self) -> np.ndarray:
        if not self.strategy_votes:
            return self.target().astype(np.float32)
        votes = np.zeros(self.votes.n)
        recent = self.votes.recent()
        votes[:len(recent)] = [1.0 if inside else -1.0 for inside in recent]
        return np.concatenate([self.target(), votes]).astype(np.float32)

    def strategy_id(self) -> int | None:
        return None

    def update(self, outcome: bool, rng: np.random.Generator) -> None:
        """``outcome`` is True when the ego ended the interaction inside the circle."""
        inside = bool(self.votes.push(bool(outcome)))
        step = noisy_step(STEP, self.step_noise, rng)
        sign = self.inside_sign if inside else -self.inside_sign
        self.theta = float(np.mod(self.theta + sign * step, 2 * np.pi))


class PointMassEnv(RepeatedInteractionEnv):
    """``lili/PointMass-v0``. Observation: the ego's (x, y). Action: velocity in [-1, 1]^2.

    ``info["strategy"]`` is the target's (x, y), followed by the partner's votes with
    ``strategy_votes=True`` (see :class:`CirclePartner`). Success is not defined; the figure of
    merit is the return (the paper: SAC -5.05, LILI -0.72, Oracle -0.54).
    """

    def __init__(
        self,
        step_noise: float = 0.0,
        history: int = 1,
        horizon: int = 50,
        render_mode: str | None = None,
        inside_turn: str = "clockwise",
        strategy_votes: bool = False,
    ) -> None:
        super().__init__(render_mode)
        if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or horizon < 1:
            raise ValueError(f"horizon={horizon!r} is invalid; allowed: an integer >= 1")
        self.horizon = int(horizon)
        self.partner = CirclePartner(step_noise, history, inside_turn, strategy_votes)
        self.observation_space = spaces.Box(-BOUND, BOUND, shape=(2,), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.pos = np.zeros(2)

    def _begin(self) -> np.ndarray:
        self.pos = np.zeros(2)
        self._target = self.partner.target()
        return self.pos.astype(np.float32)

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        a = np.clip(action.astype(np.float64), -1.0, 1.0)
        self.pos = np.clip(self.pos + SPEED * a, -BOUND, BOUND)
        reward = -float(np.linalg.norm(self.pos - self._target))
        return self.pos.astype(np.float32), reward, False

    def _outcome(self) -> bool:
        return bool(np.linalg.norm(self.pos - CENTER) < RADIUS)

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        from lili.envs.rendering import Canvas

        canvas = Canvas(200, 200, (-BOUND, BOUND), (-BOUND, BOUND))
        canvas.circle(CENTER, RADIUS, (180, 180, 180), fill=False)
        canvas.circle(self._target, 0.01, (220, 60, 60))
        canvas.circle(self.pos, 0.008, (40, 90, 220))
        return canvas.image
