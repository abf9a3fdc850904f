"""A run's ``metrics.csv``: its columns, and which interactions were played at random.

The training loop decides per interaction whether to play it with uniform random actions
(:func:`plays_at_random`) and the run logger writes the answer to the ``random`` column, so that
reports read it from the run folder instead of recomputing it. Files written before that column
existed are read with :func:`random_column`, the one place where the draw is recomputed from the
run's ``config.yaml``.

A block of updates may also report statistics that are no column because only one agent has
them (SLAC's ELBO terms ``kl``, ``obs_nll``, ``rew_nll``) or they come once (SLAC's pretraining
losses ``pretrain_first`` / ``pretrain_last``, with the run's first block): those go to
``block_extras.jsonl`` (:data:`EXTRAS`), one JSON line per interaction that reported any, read
back by :func:`read_extras`.

Only NumPy here: training (:mod:`lili.train`, :mod:`lili.runs`) and the report reader
(:mod:`lili.report`) both import it, and reading run folders must not pull in the agents.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["EXTRAS", "METRIC_COLUMNS", "RANDOM", "read_extras", "metric_columns",
           "plays_at_random", "random_column", "left_out_of_policy", "warmup_of"]

METRIC_COLUMNS = ("critic_loss", "actor_loss", "alpha", "rep_loss", "q", "entropy")
"""The statistics of an interaction's block of updates (empty before the first update)."""

EXTRAS = "block_extras.jsonl"
"""The run folder's file of the statistics a block reports beyond :data:`METRIC_COLUMNS`: one
JSON object per line, ``{"interaction": i, name: value, ...}``."""

RANDOM = "random"
"""The column that says whether an interaction was played with uniform random actions (1: the
warm-up, and with ``AgentConfig.random_interactions`` the draws after it) or by the policy (0)."""


def metric_columns(strategy_dim: int) -> list[str]:
    """The header of ``metrics.csv`` for an env whose strategy has ``strategy_dim`` entries.
    Files written before the ``random`` column existed have the same header without it."""
    return (["interaction", "return", "length", "success", RANDOM]
            + [f"strategy_{j}" for j in range(strategy_dim)]
            + ["strategy_id", *METRIC_COLUMNS, "wall_time"])


def plays_at_random(seed: int, i: int, warmup: int, share: float) -> bool:
    """Whether interaction ``i`` is played with uniform random actions: every warm-up
    interaction, and after it each with probability ``share`` (``AgentConfig.
    random_interactions``), decided from (seed, i) alone so that a resumed run draws the same
    interactions as an uninterrupted one."""
    if i < warmup:
        return True
    return share > 0 and np.random.default_rng([seed, i, 1]).random() < share


def warmup_of(config: Mapping[str, Any]) -> int:
    """The warm-up (interactions) of a run from its ``config.yaml`` mapping; 0 without one."""
    agent = config.get("agent")
    warmup = agent.get("warmup_interactions") if isinstance(agent, Mapping) else None
    return int(warmup) if isinstance(warmup, (int, float)) and not isinstance(warmup, bool) else 0


def random_column(config: Mapping[str, Any], n: int) -> np.ndarray:
    """The ``random`` column (bool, ``n`` interactions) of a ``metrics.csv`` written before the
    column existed, recomputed as training drew it from the run's ``config.yaml`` (its ``seed``
    and the agent's ``warmup_interactions`` and ``random_interactions``). A record without an
    agent config (not written by ``lili train``) played nothing at random as far as anyone can
    tell: all False."""
    agent = config.get("agent")
    seed = config.get("seed")
    if not isinstance(agent, Mapping) or isinstance(seed, bool) or not isinstance(seed, int):
        return np.zeros(n, bool)
    share = agent.get("random_interactions") or 0.0
    if isinstance(share, bool) or not isinstance(share, (int, float)):
        share = 0.0
    warmup = warmup_of(config)
    return np.array([plays_at_random(seed, i, warmup, float(share)) for i in range(n)], bool)


def left_out_of_policy(random: np.ndarray, warmup: int) -> np.ndarray:
    """The interactions a report of the policy's own play leaves out (``lili report
    --policy-only``, ``summary.json``'s ``final_*_policy``): those played at random after the
    warm-up. The warm-up stays in, since it starts every run's curve."""
    random = np.asarray(random, bool)
    return random & (np.arange(random.size) >= warmup)


def read_extras(path: str | Path, before: int | None = None) -> list[dict[str, float]]:
    """The lines of a ``block_extras.jsonl`` (none if the file does not exist), those of
    interactions below ``before`` only when it is given. Raises ``ValueError`` naming the line
    when one is not an object of an integer ``interaction`` and finite numbers."""
    path = Path(path)
    if not path.exists():
        return []
    lines = []
    for n, text in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        try:
            line = json.loads(text)
        except json.JSONDecodeError:
            line = None
        ok = (isinstance(line, dict) and type(line.get("interaction")) is int
              and all(type(v) in (int, float) and math.isfinite(v) for v in line.values()))
        if not ok:
            raise ValueError(f"{path} line {n} is {text[:80]!r}; expected a JSON object of an "
                             "integer 'interaction' and finite numbers (was it edited?)")
        if before is None or line["interaction"] < before:
            lines.append(line)
    return lines
