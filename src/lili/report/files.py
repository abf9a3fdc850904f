"""Run folders on disk: find them, read ``config.yaml`` and ``metrics.csv``, check them.

A run folder is ``<anything>/<env_name>/<algo>/seed_<k>/`` holding ``config.yaml`` (keys ``env``,
``algo``, ``seed`` and ``interactions``), ``metrics.csv`` (one row per interaction) and, once the
run has finished, ``summary.json``. Runs are identified by their ``config.yaml``, not by the folder
names. A file that was edited by hand so that the numbers would silently mislead (a column or rows
deleted, fewer rows than ``summary.json`` says were run) is an error naming the file.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from lili.errors import shown
from lili.metrics_file import RANDOM, left_out_of_policy, metric_columns, random_column, warmup_of
from lili.report.style import algo_sort_key
from lili.yaml_bounds import YAMLTooLarge, safe_load, yaml_problem

__all__ = ["Run", "load_run", "find_runs", "METRICS_FILE", "CONFIG_FILE"]

METRICS_FILE = "metrics.csv"
CONFIG_FILE = "config.yaml"
SUMMARY_FILE = "summary.json"
REQUIRED_COLUMNS = ("interaction", "return")
REQUIRED_CONFIG_KEYS = ("env", "algo", "seed")
_STRATEGY_RE = re.compile(r"^strategy_(\d+)$")


@dataclass(eq=False)
class Run:
    """One training run read from its folder.

    ``metrics`` maps every column of ``metrics.csv`` to a 1-D array with one entry per
    interaction (rows in order 0, 1, ..., which loading checks): ``interaction`` is int64,
    every other column float64 with NaN where the file has an empty cell (e.g. ``success`` in
    an env without success, losses before the first update).
    """

    path: Path
    env: str
    algo: str
    seed: int
    config: dict[str, Any]
    metrics: dict[str, np.ndarray] = field(repr=False)

    @property
    def n_interactions(self) -> int:
        """Number of interactions logged so far."""
        return int(self.metrics["interaction"].shape[0])

    @property
    def budget(self) -> int | None:
        """The interaction budget from ``config.yaml`` (None when absent)."""
        value = self.config.get("interactions")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return None
        return int(value)

    def has_metric(self, metric: str) -> bool:
        """True when ``metric`` is a column with at least one non-empty value."""
        values = self.metrics.get(metric)
        return values is not None and values.size > 0 and bool(np.any(~np.isnan(values)))

    @property
    def has_success(self) -> bool:
        """True when the env defines success (the ``success`` column is not empty)."""
        return self.has_metric("success")

    @property
    def strategy(self) -> np.ndarray | None:
        """The partner's true strategy per interaction, shape (n, k), or None without columns."""
        cols = sorted(
            (int(m.group(1)), name)
            for name in self.metrics
            if (m := _STRATEGY_RE.match(name)) is not None
        )
        if not cols:
            return None
        return np.stack([self.metrics[name] for _, name in cols], axis=1)

    @property
    def played_at_random(self) -> np.ndarray:
        """Per interaction, whether training played it with uniform random actions (the
        warm-up, and the draws of ``AgentConfig.random_interactions``): the ``random`` column of
        ``metrics.csv``, or for a file written before that column existed, the draws
        recomputed from ``config.yaml`` (:func:`lili.metrics_file.random_column`)."""
        column = self.metrics.get(RANDOM)
        if column is None:
            return random_column(self.config, self.n_interactions)
        return column == 1

    @property
    def random_draws(self) -> np.ndarray:
        """Per interaction, whether training played it at random *after* the warm-up: what
        :meth:`policy_only` leaves out (:func:`lili.metrics_file.left_out_of_policy`). All
        False without ``random_interactions``."""
        return left_out_of_policy(self.played_at_random, warmup_of(self.config))

    def policy_only(self) -> Run:
        """This run with the interactions played at random after the warm-up
        (:attr:`random_draws`) left out of its statistics: their return, success and strategy
        cells are empty (NaN), so final performance, success and the partner's strategies are
        the policy's own. The warm-up stays (it is the start of every run's curve)."""
        drawn = self.random_draws
        if not drawn.any():
            return self
        metrics = dict(self.metrics)
        for name, col in self.metrics.items():
            if name in ("return", "success", "strategy_id") or _STRATEGY_RE.match(name):
                metrics[name] = np.where(drawn, np.nan, col)
        return Run(path=self.path, env=self.env, algo=self.algo, seed=self.seed,
                   config=self.config, metrics=metrics)

    def truncated(self, upto: int) -> Run:
        """This run as it stood after its first ``upto`` interactions.

        Training does not depend on the budget, so these are the numbers a run with budget
        ``upto`` would have logged; this is how runs of different lengths are compared at one
        budget. The budget in the copy's config is capped at ``upto``.
        """
        config = dict(self.config)
        if self.budget is not None:
            config["interactions"] = min(self.budget, upto)
        metrics = {name: col[:upto].copy() for name, col in self.metrics.items()}
        return Run(path=self.path, env=self.env, algo=self.algo, seed=self.seed, config=config,
                   metrics=metrics)


def _parse_cell(text: str, path: Path, line: int, column: str) -> float:
    text = text.strip()
    if text == "":
        return math.nan
    lowered = text.lower()
    if lowered == "true":
        return 1.0
    if lowered == "false":
        return 0.0
    try:
        return float(text)
    except ValueError:
        raise ValueError(
            f"{path}: line {line}, column {shown(column)}: {shown(text)} is not a number"
        ) from None


_SPECIAL_CELLS = {"": math.nan, "true": 1.0, "false": 0.0, "True": 1.0, "False": 0.0}


def _fast_values(body: list[list[str]], width: int) -> np.ndarray | None:
    """The cells as floats in one pass (what :func:`_parse_cell` gives for these cells, several
    times faster), or None when a row or cell needs :func:`_parse_cell`'s checks and error
    message (a short row, a cell ``float`` does not read)."""
    if not body or any(len(row) != width for row in body):
        return None
    special = _SPECIAL_CELLS
    try:
        return np.array([[special[c] if c in special else float(c) for c in row]
                         for row in body], dtype=np.float64)
    except ValueError:
        return None


def _read_metrics(path: Path) -> dict[str, np.ndarray]:
    """Parse ``metrics.csv`` into columns (see :class:`Run`). Raises ValueError when malformed."""
    try:
        raw = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read metrics file ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: metrics file is not UTF-8 text (byte {exc.start}); allowed: "
                         "the CSV `lili train` writes") from None
    rows = list(csv.reader(raw.splitlines()))
    if not rows or not any(cell.strip() for cell in rows[0]):
        raise ValueError(f"{path}: metrics file is empty (no header)")
    header = [cell.strip() for cell in rows[0]]
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise ValueError(
            f"{path}: malformed metrics file, missing column(s) {', '.join(missing)}; "
            f"header is {','.join(header)}"
        )
    dupes = sorted({c for c in header if header.count(c) > 1})
    if dupes:
        raise ValueError(f"{path}: malformed metrics file, duplicate column(s) {', '.join(dupes)}")
    body = rows[1:]
    # A run that is still being written may end in a half-written line: drop it, but only then.
    if body and len(body[-1]) != len(header) and not raw.endswith(("\n", "\r")):
        body = body[:-1]
    values = _fast_values(body, len(header))
    if values is None:
        values = np.empty((len(body), len(header)), dtype=np.float64)
        for i, row in enumerate(body):
            line = i + 2
            if len(row) != len(header):
                raise ValueError(
                    f"{path}: malformed metrics file, line {line} has {len(row)} fields, "
                    f"the header has {len(header)}"
                )
            for j, (cell, column) in enumerate(zip(row, header, strict=True)):
                values[i, j] = _parse_cell(cell, path, line, column)
    metrics = {name: values[:, j].copy() for j, name in enumerate(header)}
    interaction = metrics["interaction"]
    if np.any(np.isnan(interaction)) or np.any(interaction != np.round(interaction)):
        raise ValueError(
            f"{path}: malformed metrics file, 'interaction' must be an integer on every row"
        )
    _check_rows(path, interaction.astype(np.int64))
    metrics["interaction"] = metrics["interaction"].astype(np.int64)
    return metrics


def _check_rows(path: Path, interaction: np.ndarray) -> None:
    """One row per interaction 0, 1, 2, ... in order: a deleted row would be a silent gap."""
    expected = np.arange(interaction.size)
    if np.array_equal(interaction, expected):
        return
    bad = int(np.flatnonzero(interaction != expected)[0])
    line = bad + 2
    if bad == 0:
        what = f"the first row is interaction {interaction[0]}, not 0"
    elif interaction[bad] > interaction[bad - 1] + 1:
        what = (f"interactions {interaction[bad - 1] + 1} to {interaction[bad] - 1} are missing "
                f"(line {line} jumps from {interaction[bad - 1]} to {interaction[bad]})")
    else:
        what = (f"line {line} is interaction {interaction[bad]} after {interaction[bad - 1]} "
                "(duplicated or out of order)")
    raise ValueError(f"{path}: rows were deleted or edited: {what}; allowed: one row per "
                     "interaction 0, 1, 2, ... in order, as `lili train` writes it")


def _expected_columns(header: list[str]) -> list[str]:
    """The columns `lili train` writes (``lili.runs.RunLogger``), for this run's strategy size:
    as many ``strategy_<j>`` columns as the header has, none for an env that reports no
    strategy (Pendulum-v1); without ``random`` for a file written before that column existed."""
    columns = metric_columns(sum(1 for c in header if _STRATEGY_RE.match(c)))
    return columns if RANDOM in header else [c for c in columns if c != RANDOM]


def _check_against_run(run: Run) -> None:
    """A run written by `lili train` has all its columns and as many rows as it reports done."""
    path = run.path / METRICS_FILE
    if "agent" not in run.config:  # not written by `lili train` (a hand-made record)
        return
    expected = _expected_columns(list(run.metrics))
    missing = [c for c in expected if c not in run.metrics]
    if missing:
        raise ValueError(f"{path}: column(s) {', '.join(missing)} were deleted; a run written "
                         f"by `lili train` has the columns {','.join(expected)}")
    summary = run.path / SUMMARY_FILE
    if not summary.is_file():
        return
    try:
        done = json.loads(summary.read_text(encoding="utf-8"))["interactions"]
    except (OSError, ValueError, KeyError, TypeError):
        raise ValueError(f"{summary}: unreadable (expected JSON with 'interactions', as "
                         "`lili train` writes it)") from None
    if isinstance(done, int) and run.n_interactions < done:
        raise ValueError(f"{path}: has {run.n_interactions} rows but {summary.name} says the "
                         f"run did {done} interactions: rows were deleted; allowed: one row per "
                         "interaction")


def _read_config(path: Path) -> dict[str, Any]:
    try:
        config = safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValueError(f"{path}: cannot read config ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: config is not UTF-8 text; allowed: the YAML `lili train` "
                         "writes") from None
    except YAMLTooLarge as exc:
        raise ValueError(f"{path}: config is refused: {exc}") from None
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: config is not valid YAML ({yaml_problem(exc)})") from None
    if not isinstance(config, dict):
        raise ValueError(f"{path}: config must be a mapping, got {type(config).__name__}")
    missing = [k for k in REQUIRED_CONFIG_KEYS if k not in config]
    if missing:
        raise ValueError(f"{path}: config is missing key(s) {', '.join(missing)}")
    seed = config["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"{path}: config 'seed' must be an integer, got {shown(seed)}")
    for key in ("env", "algo"):
        if not isinstance(config[key], str) or not config[key]:
            raise ValueError(
                f"{path}: config {key!r} must be a non-empty string, got {shown(config[key])}"
            )
    return config


def load_run(folder: str | Path) -> Run:
    """Read one run folder (``config.yaml`` + ``metrics.csv``). Raises ValueError on bad files."""
    folder = Path(folder)
    config = _read_config(folder / CONFIG_FILE)
    metrics = _read_metrics(folder / METRICS_FILE)
    run = Run(
        path=folder,
        env=config["env"],
        algo=config["algo"],
        seed=int(config["seed"]),
        config=config,
        metrics=metrics,
    )
    _check_against_run(run)
    return run


def _is_run_dir(folder: Path) -> bool:
    return (folder / METRICS_FILE).is_file() and (folder / CONFIG_FILE).is_file()


def find_runs(paths: Sequence[str | Path], upto: int | None = None,
              policy_only: bool = False) -> list[Run]:
    """Find and load every run folder at or below each of ``paths``.

    With ``upto``, every run is cut to its first ``upto`` interactions (:meth:`Run.truncated`);
    with ``policy_only``, its interactions played at random are left out
    (:meth:`Run.policy_only`).

    A path may be a run folder, any parent of run folders, or a run's ``metrics.csv`` /
    ``config.yaml``. Runs are returned sorted by (env, algo, seed, path); a folder reached from
    two paths is loaded once.

    Raises ValueError naming the path when a path does not exist or holds no run folder, when a
    run's files are malformed, or when two different folders are the same (env, algo, seed) run
    (they would be counted twice as seeds; pass only one of them).
    """
    if isinstance(paths, (str, Path)):
        paths = [paths]
    if upto is not None and (isinstance(upto, bool) or not isinstance(upto, int) or upto < 1):
        raise ValueError(f"upto must be a positive number of interactions, got {upto!r}")
    folders: dict[Path, None] = {}
    for given in paths:
        path = Path(given)
        if not path.exists():
            raise ValueError(f"{path}: no such file or directory")
        if path.is_file():
            if path.name in (METRICS_FILE, CONFIG_FILE) and _is_run_dir(path.parent):
                folders[path.parent.resolve()] = None
                continue
            raise ValueError(f"{path}: not a run folder (expected a directory with {METRICS_FILE} "
                             f"and {CONFIG_FILE})")
        found = []
        for root, dirs, _files in os.walk(path):
            here = Path(root)
            if _is_run_dir(here):
                found.append(here.resolve())
                dirs[:] = []  # a run folder does not contain other runs
            else:
                dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        if not found:
            raise ValueError(
                f"{path}: contains no run folder "
                f"(a directory with {METRICS_FILE} and {CONFIG_FILE})"
            )
        folders.update(dict.fromkeys(found))
    runs = [load_run(folder) for folder in folders]
    if upto is not None:
        short = [r for r in runs if r.n_interactions < upto]
        if short:
            worst = min(short, key=lambda r: r.n_interactions)
            raise ValueError(
                f"--upto {upto} is more than {worst.path} has ({worst.n_interactions} "
                f"interactions{f', {len(short)} runs are that short' if len(short) > 1 else ''});"
                f" allowed: 1 to {min(r.n_interactions for r in runs)}, so that every run is "
                "compared at the same budget")
        runs = [run.truncated(upto) for run in runs]
    if policy_only:
        runs = [run.policy_only() for run in runs]
    seen: dict[tuple[str, str, int], Path] = {}
    for run in runs:
        key = (run.env, run.algo, run.seed)
        if key in seen:
            raise ValueError(
                f"{run.path}: same env/algo/seed ({run.env}, {run.algo}, seed {run.seed}) as "
                f"{seen[key]}; pass only one of them"
            )
        seen[key] = run.path
    runs.sort(key=lambda r: (r.env, algo_sort_key(r.algo), r.seed, str(r.path)))
    return runs
