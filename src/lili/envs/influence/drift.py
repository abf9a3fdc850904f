"""``lili/InfluenceDrift-v0``: a goal that drifts toward the side where the ego ended.

Rules. The ego starts at x = 0, moves by ``0.5 * a`` per step (``a`` in [-1, 1], x clipped to
[-1, 1]) for H = 4 steps and pays ``-|x - g|`` per step. The partner's goal g lies on the grid
{+-0.125, +-0.375, +-0.625, +-0.875}. After each interaction g moves one grid step (0.25)
toward the side of 0 where the ego ended (right when ``x_end >= 0``, left otherwise),
clipped to the outermost points; the first g is drawn uniformly from the grid.

Known optima (long-run return per interaction; derivations, then ``benchmarks/influence.py``
measures them):

- **greedy** (told g, best for this interaction): run to g (one step of 0.5 reaches |g| <=
  0.5, two steps the rest) and stay; it ends on g's side, so g drifts out to the wall on that
  side and stays at +-0.875: the first step pays 0.375, the rest 0. **-0.375**.
- **no information** (not told g; a fixed trajectory, which is all a deterministic policy of
  x alone can be here, e.g. SAC's): it ends on one fixed side, so g drifts to that wall; the
  best such trajectory runs to that wall and stays: **-0.375**, the greedy value. Knowing the
  strategy is worth nothing in the long run; only influence pays.
- **influencer** (told g): hold g at +-0.125, one step from the start, by ending each
  interaction just across 0 from g, so g flips between +0.125 and -0.125. Every interaction
  then costs only its last step, ``|x_end - g|`` > 0.125, so the optimum is -0.125 (a
  supremum: ending exactly on 0 counts as right). Any other cycle must visit |g| >= 0.375 and
  end there on the far side of 0, costing >= 0.375 every other interaction (>= 0.1875 on
  average). The scripted influencer ends 0.05 across 0 (a margin a learned policy needs too):
  **-0.175**, worth 0.2 per interaction over greedy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from lili.envs.influence.line import LineEnv, check_horizon, move_to

__all__ = ["InfluenceDriftEnv", "DriftPartner", "GOALS", "SCRIPTED", "KNOWN_RETURNS"]

GOALS = np.array([-0.875, -0.625, -0.375, -0.125, 0.125, 0.375, 0.625, 0.875])
SPEED = 0.5
MARGIN = 0.05  # how far across 0 the scripted influencer ends


class DriftPartner:
    """A goal on :data:`GOALS` that moves one point toward the side where the ego ended."""

    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self) -> None:
        self.index = 0

    def reset(self, rng: np.random.Generator) -> None:
        self.index = int(rng.integers(0, len(GOALS)))

    def goal(self) -> float:
        return float(GOALS[self.index])

    def strategy(self) -> np.ndarray:
        return np.array([self.goal()], np.float32)

    def strategy_id(self) -> int | None:
        return self.index

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is the side of 0 where the ego ended: -1 left, +1 right."""
        self.index = int(np.clip(self.index + outcome, 0, len(GOALS) - 1))


class InfluenceDriftEnv(LineEnv):
    """``lili/InfluenceDrift-v0`` (see the module docstring). ``horizon``: an integer >= 3."""

    def __init__(self, horizon: int = 4, render_mode: str | None = None) -> None:
        # Two steps reach every goal; the influencer needs one more to cross back.
        super().__init__(check_horizon(horizon, 3), SPEED, render_mode)
        self.partner = DriftPartner()

    def goal(self) -> float:
        return self.partner.goal()

    def _outcome(self) -> int:
        return -1 if self.x < 0 else 1


def greedy(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Told g: run to it and stay."""
    return move_to(float(obs[0]), float(info["strategy"][0]), SPEED)


def no_information(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Not told g: run to the right wall's goal and stay (the best fixed trajectory)."""
    return move_to(float(obs[0]), float(GOALS[-1]), SPEED)


def influencer(obs: np.ndarray, info: dict[str, Any], horizon: int = 4) -> np.ndarray:
    """Told g: stay as near g as it can while still ending ``MARGIN`` across 0 from it."""
    g = float(info["strategy"][0])
    end = -np.sign(g) * MARGIN
    reach = SPEED * (horizon - info["t"] - 1)  # how far the end may be after this step
    return move_to(float(obs[0]), float(np.clip(g, end - reach, end + reach)), SPEED)


# name -> factory(seed) -> policy(obs, info) (these three are deterministic: seed unused)
SCRIPTED = {"no-information": lambda seed: no_information, "greedy": lambda seed: greedy,
            "influencer": lambda seed: influencer}
# Long-run return per interaction of each scripted policy, derived in the module docstring.
KNOWN_RETURNS = {"no-information": -0.375, "greedy": -0.375, "influencer": -0.175}
