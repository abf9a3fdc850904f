"""Reusable pieces of strategy dynamics: a majority vote over the last N outcomes and a noisy step.

These implement the appendix's partner variants once, for every env: strategies that depend on
the last N interactions (majority rule) and Gaussian noise on the size of a strategy step
(sigma given as a fraction of the nominal step).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Hashable
from typing import Any

import numpy as np

__all__ = ["MajorityHistory", "noisy_step", "check_partner_options", "check_probability"]


def check_partner_options(step_noise: float, history: int) -> None:
    """Validate the common partner options; raise ``ValueError`` naming the bad value."""
    if isinstance(step_noise, bool) or not isinstance(step_noise, (int, float, np.integer,
                                                                  np.floating)) \
            or not np.isfinite(step_noise) or step_noise < 0:
        raise ValueError(f"step_noise={step_noise!r} is invalid; allowed: a finite number >= 0")
    if isinstance(history, bool) or not isinstance(history, (int, np.integer)) or history < 1:
        raise ValueError(f"history={history!r} is invalid; allowed: an integer >= 1")


def check_probability(value: Any, name: str) -> float:
    """Validate a probability in [0, 1]; raise ``ValueError`` naming the value."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not 0.0 <= float(value) <= 1.0:
        raise ValueError(f"{name}={value!r} is invalid; allowed: a number in [0, 1]")
    return float(value)


class MajorityHistory:
    """The most frequent of the last ``n`` outcomes; ties go to the most recent tied outcome.

    With ``n = 1`` it returns the last outcome, so the history variant of a partner reduces to
    the original rule.
    """

    def __init__(self, n: int) -> None:
        self.n = int(n)
        self._items: deque[Hashable] = deque(maxlen=self.n)

    def clear(self) -> None:
        self._items.clear()

    def recent(self) -> tuple[Hashable, ...]:
        """The outcomes in the window, most recent first."""
        return tuple(reversed(self._items))

    def push(self, outcome: Hashable) -> Hashable:
        """Record ``outcome`` and return the current majority."""
        self._items.append(outcome)
        counts: dict[Hashable, int] = {}
        for item in self._items:
            counts[item] = counts.get(item, 0) + 1
        best = max(counts.values())
        for item in reversed(self._items):
            if counts[item] == best:
                return item
        raise AssertionError("unreachable")


def noisy_step(step: float, noise: float, rng: np.random.Generator) -> float:
    """``step`` plus Gaussian noise with standard deviation ``noise * |step|``."""
    if noise == 0:
        return float(step)
    return float(step + rng.normal(0.0, noise * abs(step)))
