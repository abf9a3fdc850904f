"""``lili/InfluenceFlee-v0``: a partner that flees from where the ego stopped, and stays home
once the ego chases it there.

Rules. The partner sits on one of nine slots, g = 0.25 k for k in -4..4 (strategy id k + 4;
k = 0, g = 0, is its *home*). The ego starts at x = 0, moves by ``0.25 * a`` per step (``a``
in [-1, 1], x clipped to [-1, 1]) for H = 4 steps and pays ``-|x - g|`` per step. Where the
ego stopped is read to the nearest slot, k_e = round(x_H / 0.25) (halves round up). The
partner then moves one slot *away from k_e*:

- k_e beyond it (further from home, on its side): one slot toward home (from k = +-1, home);
- k_e on it, or between it and home, or on the other side: one slot away from home; from an
  outermost slot (k = +-4), where it cannot, it slips past to the first slot of the other
  side (k = -+1);
- at home (k = 0): it stays if k_e = 0, else moves to the first slot away from the ego's side
  (k = -1 if k_e > 0, k = +1 if k_e < 0).

The first slot is drawn uniformly from the eight slots away from home. The next slot is a
known function of the slot and of where the ego stopped, so the last interaction tells it:
its rewards give g (``|x_t - g|`` at two different x; at home they are 0) and its last
observation k_e.

Known optima (long-run return per interaction at H = 4; derivations, then
``benchmarks/influence.py`` measures them). Reaching g = 0.25 k from x = 0 at 0.25 per step
costs 0, 0.25, 0.75, 1.5 for |k| = 1..4.

- **greedy** (told g, best for this interaction): run to g and stay. It stops on the partner,
  so the partner steps away from home every time and cycles through all eight slots away from
  home (+1 .. +4, -1 .. -4, +1 ...): (0 + 0.25 + 0.75 + 1.5) / 4 = **-0.625**.
- **no information** (not told g; a fixed trajectory, as a deterministic policy of x and the
  step is here, e.g. SAC's): with k_e fixed the partner never stays home (that needs k_e = 0,
  and reaching home from +-1 needs |k_e| >= 2). For |k_e| <= 1 it cycles through the eight
  slots away from home, where a step anywhere in [-0.25, 0.25] costs their mean distance
  0.625, 2.5 per interaction. For k_e >= 2 (and mirrored) it cycles through g = 0.25, 0, -0.25,
  -0.5, -0.75, -1 (from +1 the ego's end sends it home, from home to -1, from -4 it slips to
  +1), whose mean distance is 0.375 in [-0.5, -0.25] but x + 0.375 at x >= 0.25; the best
  trajectory goes left first and ends on the boundary, x = -0.25, -0.125, 0.125, 0.375:
  0.375 + 0.417 + 0.542 + 0.75 = 2.083 (a supremum; an exhaustive search over trajectories on
  a 1/16 grid finds nothing better). The scripted one ends 0.0625 inside the boundary, x =
  -0.25, -0.0625, 0.1875, 0.4375: 0.375 + 0.4375 + 0.583 + 0.8125 = 53/24, **-2.208**. (A
  stochastic policy can do a little better: staying at 0 and flipping a coin each
  interaction for a last step to +0.4375 or to -0.4375 earns -1.97.)
- **influencer** (told g): stop one slot beyond the partner, so it steps toward home (from
  +-4 it cannot, and slips to -+1), then, at home, stay on it. Once home it costs nothing:
  **0** (every other slot costs more than 0 to stay at or return to), worth 0.625 per
  interaction over greedy. The scripted influencer runs to g and steps one slot beyond it on
  the last step (one step off greedy: at k = +-1 it pays 0.25 once, and the partner is home
  the next interaction), so its influencing action is a consistent end position, k_e = k + 1
  on the right, k - 1 on the left, with half a slot of margin either side.

So influence pays in the very next interaction, and only the last step differs from greedy:
no long chain of credit assignment. Greedy beats no information by 1.58 and the influencer
beats greedy by 0.625, the same shares of the gap as in Switch (greedy closes 0.72 of the gap
from no information to the influencer here, 0.70 there).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from lili.envs.influence.line import LineEnv, check_horizon, move_to

__all__ = ["InfluenceFleeEnv", "FleePartner", "SLOT", "SPEED", "SLOTS", "HOME", "end_slot",
           "fled", "SCRIPTED", "KNOWN_RETURNS"]

SLOT = 0.25  # the distance between slots
SPEED = SLOT  # one slot per step: four steps reach the outermost slots
SLOTS = 4  # slots on each side of home: k in -SLOTS..SLOTS
HOME = SLOTS  # the strategy id of home (k = 0)
# The scripted no-information trajectory's x after each of the last three steps (module
# docstring); before them it goes to -0.25.
NO_INFORMATION_END = (-0.0625, 0.1875, 0.4375)


def end_slot(x: float) -> int:
    """The slot nearest ``x`` (halves round up), what the partner reads of where the ego
    stopped: an integer in -SLOTS..SLOTS."""
    return int(np.clip(np.floor(x / SLOT + 0.5), -SLOTS, SLOTS))


def fled(k: int, k_end: int) -> int:
    """The partner's next slot from slot ``k`` after the ego stopped at slot ``k_end``."""
    if k == 0:
        return 0 if k_end == 0 else (-1 if k_end > 0 else 1)
    side = 1 if k > 0 else -1
    if side * k_end > side * k:  # beyond it: it flees toward home
        return k - side
    if abs(k) == SLOTS:  # cornered: it slips past to the other side
        return -side
    return k + side


class FleePartner:
    """A slot that moves by :func:`fled`; the strategy is ``[g]``, its id ``k + SLOTS``."""

    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self) -> None:
        self.k = 1

    def reset(self, rng: np.random.Generator) -> None:
        # Uniform over the slots away from home: a run that started at home would be held
        # there by an ego that never moves, the no-information policy included.
        k = int(rng.integers(0, 2 * SLOTS)) - SLOTS
        self.k = k + 1 if k >= 0 else k

    def goal(self) -> float:
        return SLOT * self.k

    def strategy(self) -> np.ndarray:
        return np.array([self.goal()], np.float32)

    def strategy_id(self) -> int | None:
        return self.k + SLOTS

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is the slot where the ego stopped (:func:`end_slot`)."""
        self.k = fled(self.k, int(outcome))


class InfluenceFleeEnv(LineEnv):
    """``lili/InfluenceFlee-v0`` (see the module docstring). ``horizon``: an integer >= 4."""

    def __init__(self, horizon: int = 4, render_mode: str | None = None) -> None:
        # Four steps reach the outermost slots.
        super().__init__(check_horizon(horizon, 4), SPEED, render_mode)
        self.partner = FleePartner()

    def goal(self) -> float:
        return self.partner.goal()

    def _outcome(self) -> int:
        return end_slot(self.x)


def greedy(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Told g: run to it and stay."""
    return move_to(float(obs[0]), float(info["strategy"][0]), SPEED)


def no_information(obs: np.ndarray, info: dict[str, Any], horizon: int = 4) -> np.ndarray:
    """Not told g: a fixed trajectory, left to -0.25, then right to end at +0.4375 (k_e = 2)."""
    left = horizon - int(info["t"])  # steps left, this one included
    target = NO_INFORMATION_END[-left] if left <= len(NO_INFORMATION_END) else -SLOT
    return move_to(float(obs[0]), target, SPEED)


def influencer(obs: np.ndarray, info: dict[str, Any], horizon: int = 4) -> np.ndarray:
    """Told g: run to it and on the last step step one slot beyond it; at home, stay."""
    g = float(info["strategy"][0])
    target = g
    if int(info["t"]) == horizon - 1:
        target = float(np.clip(g + SLOT * np.sign(g), -1.0, 1.0))
    return move_to(float(obs[0]), target, SPEED)


# name -> factory(seed) -> policy(obs, info) (these three are deterministic: seed unused)
SCRIPTED = {"no-information": lambda seed: no_information, "greedy": lambda seed: greedy,
            "influencer": lambda seed: influencer}
# Long-run return per interaction of each scripted policy, derived in the module docstring.
KNOWN_RETURNS = {"no-information": -53 / 24, "greedy": -0.625, "influencer": 0.0}
