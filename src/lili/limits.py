"""Upper bounds of the counts a user gives (interactions, seeds, parallel jobs), and the one
check of them: a value past its bound would not fail, it would run for years or fill the memory
(``lili reproduce --seeds 1000000000`` planned a billion runs before printing a line)."""

from __future__ import annotations

import numbers
from typing import Any

__all__ = ["MAX_INTERACTIONS", "MAX_SEEDS", "MAX_JOBS", "MAX_GROUP", "check_count"]

MAX_INTERACTIONS = 10_000_000
"""Most interactions of one run (the paper's longest runs are 10**4)."""
MAX_SEEDS = 1_000
"""Most seeds per run group of ``lili reproduce``."""
MAX_JOBS = 1_024
"""Most runs at a time."""
MAX_GROUP = 4_096
"""Most runs trained together in one program (``lili train --seeds``, ``lili reproduce
--group``)."""


def check_count(value: Any, flag: str, high: int, low: int = 1) -> int:
    """``value`` as an int in [low, high], or ValueError naming ``flag``, the value and the
    range."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) \
            or not low <= value <= high:
        raise ValueError(f"{flag} {value} is invalid; allowed: an integer in [{low}, {high}]")
    return int(value)
