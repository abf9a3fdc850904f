"""``lili/InfluenceSwitch-v0``: the partner's next mode is a known function of its mode and of
the direction of the ego's last action.

Rules. The partner has three modes, left (0), middle (1) and right (2), whose goals are
x = -0.75, 0 and +0.75. The ego starts at x = 0, moves by ``0.25 * a`` per step (``a`` in
[-1, 1]) for H = 4 steps and pays ``-|x - goal|`` per step. The outcome of an interaction is
the direction of the ego's *last* action: left if ``a_H < -0.1``, right if ``a_H > 0.1``, still
otherwise. The next mode (the first is drawn uniformly):

  ========  ========  ========  ========
  mode      still     left      right
  ========  ========  ========  ========
  left      middle    right     middle
  middle    right     middle    left
  right     left      left      middle
  ========  ========  ========  ========

Known optima (long-run return per interaction; derivations, then ``benchmarks/influence.py``
measures them):

- **greedy** (told the mode, best for this interaction): run to the goal (three steps to
  +-0.75, paying 0.5 + 0.25) and hold still, so the last action is "still" and the modes cycle
  left -> middle -> right: (0.75 + 0 + 0.75) / 3 = **-0.5**.
- **no information** (not told the mode; a fixed trajectory, as a deterministic policy of x
  alone is here): a fixed last action makes a fixed cycle: "still" left/middle/right, "right"
  left/middle, "left" left/right (or middle for ever, if it starts there, 1 in 3). The best
  fixed trajectory for the left/middle cycle stays in [-0.75, 0], where each step pays
  |x + 0.75| + |x| = 0.75 over the two modes: 4 x 0.75 / 2 = 1.5 per interaction, plus the
  last step's move; the scripted one stays at 0 and moves right at the end, paying 3.05 in
  left's interactions and 0.05 in middle's: **-1.55**.
- **influencer** (told the mode): reach the middle and hold it with a small left move at the
  end (middle + left -> middle): that costs only the last step's displacement, 0.25 * |a_H| >
  0.025, so the optimum is -0.025 (a supremum; the deadband is open). Every left or right
  interaction costs >= 0.75, so no cycle through them is cheaper. From left it ends with a
  right move (-> middle), from right with a right move (-> middle). The scripted influencer
  uses |a_H| = 0.2 (twice the deadband, a margin a learned policy needs too): **-0.05**, worth
  0.45 per interaction over greedy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from lili.envs.influence.line import LineEnv, check_horizon, move_to

__all__ = ["InfluenceSwitchEnv", "SwitchPartner", "GOALS", "NEXT_MODE", "SCRIPTED",
           "KNOWN_RETURNS"]

LEFT, MIDDLE, RIGHT = 0, 1, 2
STILL = 0
GOALS = (-0.75, 0.0, 0.75)
SPEED = 0.25
DEADBAND = 0.1  # |a_H| at or below this is "still"
NUDGE = 0.2  # the scripted influencer's last action
# (mode, direction of the last action: -1 left, 0 still, +1 right) -> next mode
NEXT_MODE: dict[tuple[int, int], int] = {
    (LEFT, 0): MIDDLE, (LEFT, -1): RIGHT, (LEFT, 1): MIDDLE,
    (MIDDLE, 0): RIGHT, (MIDDLE, -1): MIDDLE, (MIDDLE, 1): LEFT,
    (RIGHT, 0): LEFT, (RIGHT, -1): LEFT, (RIGHT, 1): MIDDLE,
}


class SwitchPartner:
    """Three modes switched by :data:`NEXT_MODE`; the strategy is the mode one-hot."""

    strategy_space = spaces.Box(0.0, 1.0, shape=(3,), dtype=np.float32)

    def __init__(self) -> None:
        self.mode = MIDDLE

    def reset(self, rng: np.random.Generator) -> None:
        self.mode = int(rng.integers(0, 3))

    def strategy(self) -> np.ndarray:
        one_hot = np.zeros(3, np.float32)
        one_hot[self.mode] = 1.0
        return one_hot

    def strategy_id(self) -> int | None:
        return self.mode

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is the direction of the ego's last action: -1, 0 (still) or +1."""
        self.mode = NEXT_MODE[(self.mode, int(outcome))]


class InfluenceSwitchEnv(LineEnv):
    """``lili/InfluenceSwitch-v0`` (see the module docstring). ``horizon``: an integer >= 4."""

    def __init__(self, horizon: int = 4, render_mode: str | None = None) -> None:
        # Three steps reach a side goal; the fourth is the last action the partner reads.
        super().__init__(check_horizon(horizon, 4), SPEED, render_mode)
        self.partner = SwitchPartner()

    def goal(self) -> float:
        return GOALS[self.partner.mode]

    def _outcome(self) -> int:
        if abs(self.last_action) <= DEADBAND:
            return STILL
        return -1 if self.last_action < 0 else 1


def greedy(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Told the mode: run to its goal and hold still."""
    return move_to(float(obs[0]), GOALS[int(info["strategy_id"])], SPEED)


def no_information(obs: np.ndarray, info: dict[str, Any], horizon: int = 4) -> np.ndarray:
    """Not told the mode: stay at 0, move right on the last step (the left/middle cycle)."""
    return np.array([NUDGE if info["t"] == horizon - 1 else 0.0], np.float32)


def influencer(obs: np.ndarray, info: dict[str, Any], horizon: int = 4) -> np.ndarray:
    """Told the mode: run to its goal, then end with the move that leads to (or keeps) middle."""
    mode = int(info["strategy_id"])
    if info["t"] == horizon - 1:
        return np.array([-NUDGE if mode == MIDDLE else NUDGE], np.float32)
    return move_to(float(obs[0]), GOALS[mode], SPEED)


# name -> factory(seed) -> policy(obs, info) (these three are deterministic: seed unused)
SCRIPTED = {"no-information": lambda seed: no_information, "greedy": lambda seed: greedy,
            "influencer": lambda seed: influencer}
# Long-run return per interaction of each scripted policy, derived in the module docstring.
KNOWN_RETURNS = {"no-information": -1.55, "greedy": -0.5, "influencer": -0.05}
