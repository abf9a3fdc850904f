"""Scripted policies for Point Mass (``lili/PointMass-v0``; the rules are in its module).

Each is told the target (``info["strategy"]``) except the no-information one:

- **greedy**: run straight to the target at full speed (0.01 per axis per step) and stay on it.
  Whether it then ends inside or outside the circle is worth nothing to this interaction, so it
  tosses a coin (its own seeded generator) and ends 0.005 inside or outside on the last step:
  the target takes a fair random walk round the circle (2 pi is no multiple of the 0.2 step,
  so in the long run it visits the whole circle evenly), and the return is the average over
  the circle of the cost of reaching it: **-0.494** (720 angles, each rolled out once). The
  walk is slow (it needs thousands of interactions to average out; over 200 interactions one
  seed can sit near the top and earn -0.2, another near the bottom and earn -0.6).
- **influencer**: the same run, but on the last step it ends 0.005 inside when the target is
  on the left half of the circle (angle in (pi/2, 3 pi/2]: inside turns it clockwise, toward
  the top) and outside otherwise, so the target climbs to the top and then alternates between
  the grid angles 1.4 and 1.6 next to it, about 0.05 from the start: **-0.102** (the run to
  those two targets, rolled out, plus 0.005 on the last step). The top is the cheapest target
  there is, so no policy can do much better; the paper's Oracle: -0.54, LILI -0.72.
- **no information**: go to the circle's centre and stay, which is always 0.1 from the target
  (the best fixed point when the target goes round the whole circle, which it does: ending
  inside every time turns it clockwise every time): **-5.01** (the paper's SAC: -5.05).

:class:`LastInteractionInfluencer` is the influencer handed instead the target that the last
interaction predicts (its target moved one noise-free step by the side where the ego ended),
everything an agent reading only the last interaction (LILI) can know; under the noisy
partner (``step_noise``) the prediction is off by the noise, and its return is the bound of
such an agent (``benchmarks/partner_scripted.py --table noise``). With ``history=N`` it reads
the last N interactions (LILI's encoder in the history experiment) and predicts the partner
that takes its direction from the majority of the last N outcomes exactly; with ``history=1``
against such a partner it is an agent that reads one interaction too few
(``benchmarks/partner_scripted.py --table history``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lili.envs.point_mass import BOUND, CENTER, RADIUS, SPEED, CirclePartner

__all__ = ["SCRIPTED", "KNOWN_RETURNS", "GreedyCoin", "influencer", "no_information",
           "LastInteractionInfluencer"]

HORIZON = 50
MARGIN = 0.005  # how far inside or outside the circle the last step ends


def _move_to(pos: np.ndarray, target: np.ndarray) -> np.ndarray:
    return np.clip((target - pos) / SPEED, -1.0, 1.0).astype(np.float32)


def _end_point(target: np.ndarray, inside: bool) -> np.ndarray:
    radial = (target - CENTER) / np.linalg.norm(target - CENTER)
    return np.clip(target + (-MARGIN if inside else MARGIN) * radial, -BOUND, BOUND)


class GreedyCoin:
    """Greedy for this interaction; a fair coin decides which side of the circle it ends on."""

    def __init__(self, seed: int = 0) -> None:
        self.rng = np.random.default_rng(seed)
        self.inside = True

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        target = np.asarray(info["strategy"], np.float64)
        pos = np.asarray(obs, np.float64)
        if info["t"] == 0:
            self.inside = bool(self.rng.integers(0, 2))
        if info["t"] == HORIZON - 1:
            return _move_to(pos, _end_point(target, self.inside))
        return _move_to(pos, target)


def influencer(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Told the target: run to it; end on the side that turns it toward the top."""
    target = np.asarray(info["strategy"], np.float64)
    pos = np.asarray(obs, np.float64)
    if info["t"] == HORIZON - 1:
        # Left half of the circle (x < centre's x): inside turns it clockwise, i.e. up.
        return _move_to(pos, _end_point(target, inside=target[0] < CENTER[0]))
    return _move_to(pos, target)


def no_information(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Not told the target: sit at the circle's centre."""
    return _move_to(np.asarray(obs, np.float64), CENTER)


class LastInteractionInfluencer:
    """The influencer told the target the last ``history`` interactions predict (see the module
    docs); before any interaction it plays :func:`no_information`. ``inside_turn`` is the env's
    rule. Stateful: one instance per rollout."""

    def __init__(self, inside_turn: str = "clockwise", history: int = 1) -> None:
        # The partner's own (noise-free) update predicts the next target: one rule, one place.
        # It is kept across interactions, so its vote holds this policy's last `history` ends.
        self.partner = CirclePartner(0.0, history, inside_turn)
        self.predicted: np.ndarray | None = None
        self.last_target: np.ndarray | None = None
        self.ended_inside = False

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if info["t"] == 0:
            self.predicted = None
            if self.last_target is not None:
                rel = self.last_target - CENTER
                self.partner.theta = float(np.arctan2(rel[1], rel[0]))
                self.partner.update(self.ended_inside, np.random.default_rng(0))
                self.predicted = self.partner.target()
            # Kept for the next interaction only: this one's rewards reveal it after the fact.
            self.last_target = np.asarray(info["strategy"], np.float64)
        if self.predicted is None:
            action = no_information(obs, info)
        else:
            action = influencer(obs, {**info, "strategy": self.predicted})
        if info["t"] == HORIZON - 1:
            end = np.clip(np.asarray(obs, np.float64) + SPEED * action, -BOUND, BOUND)
            self.ended_inside = bool(np.linalg.norm(end - CENTER) < RADIUS)
        return action


# name -> factory(seed) -> policy(obs, info)
SCRIPTED = {"no-information": lambda seed: no_information, "greedy": GreedyCoin,
            "influencer": lambda seed: influencer}
# Long-run return per interaction of each scripted policy (module docstring; measured).
KNOWN_RETURNS = {"no-information": -5.01, "greedy": -0.494, "influencer": -0.102}
