"""Figures and tables from run folders (and nothing else).

A run folder is ``<anything>/<env_name>/<algo>/seed_<k>/`` holding ``config.yaml`` (keys ``env``,
``algo``, ``seed`` and ``interactions``), ``metrics.csv`` (one row per interaction) and, once the
run has finished, ``summary.json`` (not needed here). Runs are identified by their
``config.yaml``, not by the folder names, and grouped by ``(env, algo)``; every run of a group
counts as one seed.

Typical use::

    from lili.report import write_report
    result = write_report(["runs/"], "runs/report")   # curves.png, results.md, results.json, ...

The reference numbers of the paper live in :data:`PAPER`.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import textwrap
import zlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

__all__ = [
    "ALGO_COLORS",
    "PAPER",
    "Run",
    "algo_color",
    "algo_label",
    "final_performance",
    "find_runs",
    "load_run",
    "markdown_table",
    "moving_average",
    "plot_learning_curves",
    "plot_strategy_heatmap",
    "plot_strategy_frequencies",
    "strategy_frequencies",
    "summarize",
    "write_report",
]

METRICS_FILE = "metrics.csv"
CONFIG_FILE = "config.yaml"
REQUIRED_COLUMNS = ("interaction", "return")
REQUIRED_CONFIG_KEYS = ("env", "algo", "seed")
_STRATEGY_RE = re.compile(r"^strategy_(\d+)$")

# Point Mass geometry (lili.envs.point_mass), repeated here so that reporting needs no env import.
PM_CENTER = (0.0, -0.05)
PM_RADIUS = 0.1
PM_BOUND = 0.15

PAPER: dict[str, dict[str, Any]] = {
    "lili/PointMass-v0": {
        "return": {"sac": -5.05, "lili": -0.72, "oracle": -0.54},
        "seeds": 3,
        "source": "Xie et al., CoRL 2020 (LILI), Point Mass results table: final return",
    },
    "lili/Driving2D-v0": {
        "text": "LILI and Oracle near 100% success, SAC about 50% or below",
        "success_text": {
            "sac": "about 50% or below",
            "lili": "near 100%",
            "oracle": "near 100%",
        },
        "source": "Xie et al., CoRL 2020 (LILI), appendix (Driving 2D): no numbers given",
    },
    "lili/LunarLander-v0": {
        "text": "LILI close to the Oracle; SAC about 50% (lands on one pad)",
        "success_text": {"sac": "about 50%", "lili": "close to the Oracle"},
        "source": "Xie et al., CoRL 2020 (LILI), results figure (Lunar Lander): no table",
    },
    "lili/DrivingSteer-v0": {
        "text": "Oracle and LILI (no influence) converge to always passing; SAC about 50% "
                "(mixes lanes); SLAC and LILAC keep choosing the same lane and collide",
        "success_text": {"sac": "about 50%", "oracle": "near 100%",
                         "lili-no-influence": "near 100% (slowly)"},
        "source": "Xie et al., CoRL 2020 (LILI), appendix (Driving CARLA): no numbers given",
    },
    "lili/AirHockey-v0": {
        "success": {"random": 0.18, "sac": 0.44, "lili": 0.91},
        "return": {"lili": 1.15, "lili-no-influence": 1.0},
        "return_se": {"lili": 0.05, "lili-no-influence": 0.05},
        "strategy_freq": {"lili": {"left": 0.41}, "lili-no-influence": "uniform"},
        "strategy_names": ["left", "middle", "right"],
        "text": "block rate over the last 100 interactions: random 18%, SAC 44%, LILI 91%; "
                "striker over the last 200: LILI 41% left, LILI (no influence) uniform",
        "source": "Xie et al., CoRL 2020 (LILI), air hockey figure (two Panda arms)",
    },
}
"""Reference results of the paper, keyed by registered env id.

``return`` maps algo -> final return (mean over the paper's ``seeds`` seeds). ``text`` is a
qualitative description where the paper gives no numbers; ``success_text`` is the per-algo part
of it that the markdown table shows. ``success`` maps algo -> success rate where the paper gives
one; ``strategy_names`` names the partner's discrete strategies (``strategy_id`` 0, 1, ...).
"""

ALGO_ORDER = ("random", "sac", "slac", "lili-no-influence", "lili", "lilac", "oracle")
ALGO_LABELS = {
    "random": "Random",
    "sac": "SAC",
    "slac": "SLAC",
    "lili-no-influence": "LILI (no influence)",
    "lili": "LILI",
    "lilac": "LILAC",
    "oracle": "Oracle",
}
ALGO_COLORS = {
    "random": "#7f7f7f",
    "sac": "#1f77b4",
    "slac": "#9467bd",
    "lili-no-influence": "#ff7f0e",
    "lili": "#d62728",
    "lilac": "#8c564b",
    "oracle": "#2ca02c",
}
_EXTRA_COLORS = ("#e377c2", "#bcbd22", "#17becf", "#7f7f7f", "#000000", "#aec7e8")
_ENV_TITLES = {"pointmass": "Point Mass", "driving2d": "Driving (2D)",
               "lunarlander": "Lunar Lander", "drivingsteer": "Driving (steering)",
               "airhockey": "Air hockey"}
_ENV_ORDER = ("pointmass", "lunarlander", "driving2d", "drivingsteer", "airhockey")
STRATEGY_WINDOW = 200
DPI = 120


# --------------------------------------------------------------------------------------- runs


@dataclass(eq=False)
class Run:
    """One training run read from its folder.

    ``metrics`` maps every column of ``metrics.csv`` to a 1-D array with one entry per
    interaction (rows sorted by ``interaction``): ``interaction`` is int64, every other column
    float64 with NaN where the file has an empty cell (e.g. ``success`` in an env without
    success, losses before the first update).
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
            f"{path}: line {line}, column {column!r}: {text!r} is not a number"
        ) from None


def _read_metrics(path: Path) -> dict[str, np.ndarray]:
    """Parse ``metrics.csv`` into columns (see :class:`Run`). Raises ValueError when malformed."""
    try:
        raw = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read metrics file ({exc})") from exc
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
    order = np.argsort(interaction, kind="stable")
    metrics = {name: col[order] for name, col in metrics.items()}
    metrics["interaction"] = metrics["interaction"].astype(np.int64)
    return metrics


def _read_config(path: Path) -> dict[str, Any]:
    try:
        config = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"{path}: cannot read config ({exc})") from exc
    if not isinstance(config, dict):
        raise ValueError(f"{path}: config must be a mapping, got {type(config).__name__}")
    missing = [k for k in REQUIRED_CONFIG_KEYS if k not in config]
    if missing:
        raise ValueError(f"{path}: config is missing key(s) {', '.join(missing)}")
    seed = config["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"{path}: config 'seed' must be an integer, got {seed!r}")
    for key in ("env", "algo"):
        if not isinstance(config[key], str) or not config[key]:
            raise ValueError(
                f"{path}: config {key!r} must be a non-empty string, got {config[key]!r}"
            )
    return config


def load_run(folder: str | Path) -> Run:
    """Read one run folder (``config.yaml`` + ``metrics.csv``). Raises ValueError on bad files."""
    folder = Path(folder)
    config = _read_config(folder / CONFIG_FILE)
    metrics = _read_metrics(folder / METRICS_FILE)
    return Run(
        path=folder,
        env=config["env"],
        algo=config["algo"],
        seed=int(config["seed"]),
        config=config,
        metrics=metrics,
    )


def _is_run_dir(folder: Path) -> bool:
    return (folder / METRICS_FILE).is_file() and (folder / CONFIG_FILE).is_file()


def find_runs(paths: Sequence[str | Path], upto: int | None = None) -> list[Run]:
    """Find and load every run folder at or below each of ``paths``.

    With ``upto``, every run is cut to its first ``upto`` interactions (:meth:`Run.truncated`).

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
        runs = [run.truncated(upto) for run in runs]
    seen: dict[tuple[str, str, int], Path] = {}
    for run in runs:
        key = (run.env, run.algo, run.seed)
        if key in seen:
            raise ValueError(
                f"{run.path}: same env/algo/seed ({run.env}, {run.algo}, seed {run.seed}) as "
                f"{seen[key]}; pass only one of them"
            )
        seen[key] = run.path
    runs.sort(key=lambda r: (r.env, _algo_sort_key(r.algo), r.seed, str(r.path)))
    return runs


# -------------------------------------------------------------------------------- statistics


def _window(n: int, frac: float) -> int:
    return max(1, int(math.floor(frac * n + 1e-9)))


def final_performance(run: Run, metric: str = "return", frac: float = 0.1) -> float:
    """Mean of ``metric`` over the last ``frac`` of the run's interactions (at least one).

    Empty cells are ignored; NaN when the metric is empty over the whole window (e.g.
    ``success`` in an env that defines none). Raises ValueError for an unknown metric, a
    ``frac`` outside (0, 1] or a run without interactions.
    """
    if not 0.0 < frac <= 1.0:
        raise ValueError(f"frac={frac!r} is invalid; allowed: 0 < frac <= 1")
    if metric not in run.metrics:
        raise ValueError(
            f"{run.path}: no metric {metric!r}; available: {', '.join(run.metrics)}"
        )
    n = run.n_interactions
    if n == 0:
        raise ValueError(f"{run.path}: no interactions logged yet")
    tail = run.metrics[metric][-_window(n, frac):]
    tail = tail[~np.isnan(tail)]
    return float(tail.mean()) if tail.size else math.nan


def _mean_se(values: Sequence[float]) -> tuple[float | None, float | None]:
    arr = np.asarray(values, dtype=np.float64)
    if arr.size == 0:
        return None, None
    mean = float(arr.mean())
    se = float(arr.std(ddof=1) / math.sqrt(arr.size)) if arr.size > 1 else 0.0
    return mean, se


def _env_key(env: str) -> str:
    """Normalise ``lili/PointMass-v0`` / ``point-mass`` / ``PointMass`` to ``pointmass``."""
    name = env.rsplit("/", 1)[-1]
    name = re.sub(r"-v\d+$", "", name)
    return re.sub(r"[^0-9a-z]", "", name.lower())


def paper_reference(env: str) -> dict[str, Any] | None:
    """The :data:`PAPER` entry for ``env`` (registered id or alias), or None."""
    key = _env_key(env)
    for env_id, entry in PAPER.items():
        if _env_key(env_id) == key:
            return entry
    return None


def _algo_sort_key(algo: str) -> tuple[int, str]:
    return (ALGO_ORDER.index(algo) if algo in ALGO_ORDER else len(ALGO_ORDER), algo)


def algo_label(algo: str) -> str:
    """Display name of an algo (``lili-no-influence`` -> ``LILI (no influence)``)."""
    return ALGO_LABELS.get(algo, algo)


def algo_color(algo: str) -> str:
    """A fixed colour per algo, the same in every figure."""
    if algo in ALGO_COLORS:
        return ALGO_COLORS[algo]
    return _EXTRA_COLORS[zlib.crc32(algo.encode()) % len(_EXTRA_COLORS)]


def _env_sort_key(env: str) -> tuple[int, str]:
    key = _env_key(env)
    return (_ENV_ORDER.index(key) if key in _ENV_ORDER else len(_ENV_ORDER), env)


def _env_title(env: str) -> str:
    pretty = _ENV_TITLES.get(_env_key(env))
    return f"{pretty} ({env})" if pretty else env


def _group(runs: Iterable[Run]) -> dict[str, dict[str, list[Run]]]:
    """env -> algo -> runs (with at least one interaction), envs and algos in display order."""
    groups: dict[str, dict[str, list[Run]]] = {}
    for run in runs:
        if run.n_interactions == 0:
            continue
        groups.setdefault(run.env, {}).setdefault(run.algo, []).append(run)
    return {
        env: {algo: sorted(by_algo[algo], key=lambda r: r.seed)
              for algo in sorted(by_algo, key=_algo_sort_key)}
        for env, by_algo in sorted(groups.items(), key=lambda kv: _env_sort_key(kv[0]))
    }


def summarize(runs: Iterable[Run], frac: float = 0.1) -> list[dict[str, Any]]:
    """One dict per (env, algo), envs sorted and algos in a fixed order.

    Keys: ``env``, ``algo``, ``n`` (seeds), ``seeds``, ``interactions_min`` /
    ``interactions_max`` (interactions logged), ``budget`` (largest configured budget or None),
    ``return_mean`` / ``return_se`` / ``returns`` (final return per seed, see
    :func:`final_performance`), ``success_mean`` / ``success_se`` / ``successes`` (None when the
    env defines no success), ``gap_closed`` = (R - R_sac) / (R_oracle - R_sac) on the mean final
    returns (None unless SAC and Oracle both ran on the env and differ), ``paper_return`` and
    ``paper_gap_closed`` (None when the paper gives no number) and ``paper_text`` (None or the
    paper's qualitative statement), ``wall_time_mean`` (seconds per run, None without a
    ``wall_time`` column), ``paper_success`` (None or the paper's success rate) and
    ``strategy_freq`` (see :func:`strategy_frequencies`; None without strategy ids).
    s.e. = std(ddof=1) / sqrt(n), 0 with one seed. Runs with no
    interaction logged yet are left out.
    """
    rows: list[dict[str, Any]] = []
    for env, by_algo in _group(runs).items():
        paper = paper_reference(env) or {}
        paper_returns = paper.get("return", {})
        env_rows = []
        for algo, group in by_algo.items():
            returns = [final_performance(r, "return", frac) for r in group]
            successes = [final_performance(r, "success", frac) for r in group if r.has_success]
            successes = [s for s in successes if not math.isnan(s)]
            r_mean, r_se = _mean_se(returns)
            s_mean, s_se = _mean_se(successes)
            budgets = [r.budget for r in group if r.budget is not None]
            walls = [float(r.metrics["wall_time"][-1]) for r in group
                     if r.has_metric("wall_time")]
            freq = strategy_frequencies(group)
            env_rows.append({
                "env": env,
                "algo": algo,
                "n": len(group),
                "seeds": [r.seed for r in group],
                "interactions_min": min(r.n_interactions for r in group),
                "interactions_max": max(r.n_interactions for r in group),
                "budget": max(budgets) if budgets else None,
                "return_mean": r_mean,
                "return_se": r_se,
                "returns": returns,
                "success_mean": s_mean,
                "success_se": s_se,
                "successes": successes if successes else None,
                "gap_closed": None,
                "paper_return": paper_returns.get(algo),
                "paper_gap_closed": _gap(paper_returns, algo),
                "paper_text": paper.get("success_text", {}).get(algo),
                "wall_time_mean": float(np.mean(walls)) if walls else None,
                "paper_success": paper.get("success", {}).get(algo),
                "strategy_freq": None if freq is None else freq.tolist(),
            })
        means = {row["algo"]: row["return_mean"] for row in env_rows}
        for row in env_rows:
            row["gap_closed"] = _gap(means, row["algo"])
        rows.extend(env_rows)
    return rows


def _gap(returns: dict[str, float], algo: str) -> float | None:
    if algo not in returns or "sac" not in returns or "oracle" not in returns:
        return None
    denom = returns["oracle"] - returns["sac"]
    if denom == 0:
        return None
    return float((returns[algo] - returns["sac"]) / denom)


# -------------------------------------------------------------------------------- markdown


def _fmt(value: float | None, se: float | None, spec: str = ".2f", pct: bool = False) -> str:
    if value is None:
        return "—"
    if pct:
        return f"{100 * value:.1f}% ± {100 * (se or 0.0):.1f}%"
    return f"{value:{spec}} ± {(se or 0.0):{spec}}"


def _fmt_duration(seconds: float | None) -> str:
    if seconds is None:
        return "—"
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min"


def markdown_table(summary: Sequence[dict[str, Any]] | dict[str, Any]) -> str:
    """Markdown with one table per env.

    ``summary`` is the list from :func:`summarize` or the dict that :func:`write_report`
    returns (its ``"summary"`` is used). Columns: algo | seeds | final return (mean ± s.e.) |
    success (mean ± s.e. or —) | gap closed | paper | wall time per run. Below each table: the
    paper's source, or its statement where it gives no numbers.
    """
    if isinstance(summary, dict):
        if "summary" not in summary:
            raise ValueError("markdown_table needs summarize(...) or write_report(...)'s result")
        summary = summary["summary"]
    by_env: dict[str, list[dict[str, Any]]] = {}
    for row in summary:
        by_env.setdefault(row["env"], []).append(row)
    parts: list[str] = []
    for env, rows in by_env.items():
        lines = [
            f"### {_env_title(env)}",
            "",
            "| algo | seeds | final return (mean ± s.e.) | success (mean ± s.e.) "
            "| gap closed | paper | wall time / run |",
            "|---|---:|---:|---:|---:|---|---:|",
        ]
        for row in rows:
            gap = "—" if row["gap_closed"] is None else f"{row['gap_closed']:.2f}"
            cited = []
            if row.get("paper_return") is not None:
                cited.append(f"{row['paper_return']:.2f}")
                if row.get("paper_gap_closed") is not None and row["algo"] not in ("sac", "oracle"):
                    cited[-1] += f" (gap {row['paper_gap_closed']:.2f})"
            if row.get("paper_success") is not None:
                cited.append(f"success {100 * row['paper_success']:.0f}%")
            elif row.get("paper_text"):
                cited.append(f"success {row['paper_text']}")
            paper = ", ".join(cited) or "—"
            interactions = row.get("interactions_min")
            seeds = f"{row['n']}"
            if interactions is not None and row.get("budget") and interactions < row["budget"]:
                seeds += f" ({interactions}/{row['budget']} int.)"
            lines.append(
                f"| {algo_label(row['algo'])} | {seeds} "
                f"| {_fmt(row['return_mean'], row['return_se'])} "
                f"| {_fmt(row['success_mean'], row['success_se'], pct=True)} "
                f"| {gap} | {paper} | {_fmt_duration(row.get('wall_time_mean'))} |"
            )
        ref = paper_reference(env) or {}
        notes = []
        if "strategy_names" in ref:
            for row in rows:
                if row.get("strategy_freq"):
                    names = strategy_names(env, len(row["strategy_freq"]))
                    shares = ", ".join(f"{name} {100 * f:.0f}%"
                                       for name, f in zip(names, row["strategy_freq"], strict=True))
                    notes.append(f"{algo_label(row['algo'])}: partner played {shares} over the "
                                 f"last {STRATEGY_WINDOW} interactions.")
        if "return" in ref:
            over = f" over {ref['seeds']} seeds" if "seeds" in ref else ""
            notes.append(f"Paper: final return{over} ({ref['source']}).")
        if "text" in ref:
            notes.append(f"Paper: {ref['text']}.")
        upto = rows[0].get("upto")
        window = f"the first {upto} interactions" if upto else "interactions"
        notes.append(
            f"Final = mean over the last 10% of {window} per seed; s.e. over seeds; "
            "gap closed = (R − R_SAC) / (R_Oracle − R_SAC)."
        )
        lines += ["", *notes]
        parts.append("\n".join(lines))
    return "\n\n".join(parts) + "\n"


# ---------------------------------------------------------------------------------- figures


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """Trailing moving average; the window is shortened at the start; NaNs are skipped."""
    if window < 1:
        raise ValueError(f"window={window!r} is invalid; allowed: an integer >= 1")
    values = np.asarray(values, dtype=np.float64)
    valid = ~np.isnan(values)
    csum = np.concatenate([[0.0], np.cumsum(np.where(valid, values, 0.0))])
    ccount = np.concatenate([[0], np.cumsum(valid)])
    idx = np.arange(values.size)
    lo = np.maximum(0, idx - window + 1)
    total = csum[idx + 1] - csum[lo]
    count = ccount[idx + 1] - ccount[lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _seed_band(group: list[Run], metric: str, window: int):
    """x, mean over seeds, s.e. over seeds and seed count per x of the smoothed metric."""
    xs = np.unique(np.concatenate([r.metrics["interaction"] for r in group]))
    table = np.full((len(group), xs.size), np.nan)
    for i, run in enumerate(group):
        cols = np.searchsorted(xs, run.metrics["interaction"])
        table[i, cols] = moving_average(run.metrics[metric], window)
    count = np.sum(~np.isnan(table), axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.nansum(table, axis=0) / np.maximum(count, 1)
        dev = np.where(np.isnan(table), 0.0, table - mean) ** 2
        sd = np.sqrt(dev.sum(axis=0) / np.maximum(count - 1, 1))
        se = np.where(count > 1, sd / np.sqrt(np.maximum(count, 1)), 0.0)
    mean = np.where(count > 0, mean, np.nan)
    return xs, mean, se, count


def _grid(n: int, max_cols: int = 3) -> tuple[int, int]:
    cols = min(n, max_cols)
    return math.ceil(n / cols), cols


def plot_learning_curves(
    runs: Iterable[Run], out_png: str | Path, metric: str = "return", window: int = 50
) -> Path:
    """Learning curves: one subplot per env, one line per algo (mean over seeds ± s.e.).

    Each seed's ``metric`` is smoothed by a trailing moving average over ``window``
    interactions before averaging over seeds. Envs where ``metric`` is empty for every run are
    skipped. The paper's numbers are dashed horizontal lines (return on Point Mass); where the
    paper gives only a description it is printed in the subplot. Raises ValueError when no run
    has the metric. Returns the path written.
    """
    groups = {
        env: {algo: [r for r in group if r.has_metric(metric)] for algo, group in by_algo.items()}
        for env, by_algo in _group(runs).items()
    }
    groups = {
        env: {algo: g for algo, g in by_algo.items() if g}
        for env, by_algo in groups.items()
        if any(by_algo.values())
    }
    if not groups:
        raise ValueError(f"no run with metric {metric!r} to plot")
    plt = _pyplot()
    from matplotlib.lines import Line2D

    nrows, ncols = _grid(len(groups))
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.6 * ncols, 4.0 * nrows), squeeze=False)
    ylabel = {"return": "return per interaction", "success": "success rate"}.get(metric, metric)
    for ax, (env, by_algo) in zip(axes.flat, groups.items(), strict=False):
        handles = []
        for algo, group in by_algo.items():
            xs, mean, se, _ = _seed_band(group, metric, window)
            color = algo_color(algo)
            n = len(group)
            label = f"{algo_label(algo)} ({n} seed{'s' * (n > 1)})"
            (line,) = ax.plot(xs, mean, color=color, lw=1.6, label=label)
            ax.fill_between(xs, mean - se, mean + se, color=color, alpha=0.2, lw=0)
            handles.append(line)
        ref = paper_reference(env) or {}
        if metric in ref and isinstance(ref[metric], dict):
            for algo, value in sorted(ref[metric].items(), key=lambda kv: _algo_sort_key(kv[0])):
                ax.axhline(value, color=algo_color(algo), ls="--", lw=1.1, alpha=0.85)
                handles.append(Line2D([], [], color=algo_color(algo), ls="--", lw=1.1,
                                      label=f"paper {algo_label(algo)} ({value:g})"))
        title = _env_title(env)
        if metric == "success" and "text" in ref:
            title += "\n" + textwrap.fill(f"paper: {ref['text']}", width=50)
        if metric == "success":
            ax.set_ylim(-0.03, 1.03)
        ax.set_title(title, fontsize=11)
        ax.set_xlabel("interaction")
        ax.set_ylabel(f"{ylabel} (moving avg. {window})")
        ax.grid(True, alpha=0.3)
        ax.legend(handles=handles, fontsize=8, loc="best", framealpha=0.85)
    for ax in list(axes.flat)[len(groups):]:
        ax.set_visible(False)
    fig.suptitle(f"Learning curves: {ylabel} (mean over seeds ± s.e.)", fontsize=12)
    fig.tight_layout()
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png


def plot_strategy_heatmap(runs: Iterable[Run], out_png: str | Path, last: int = 500) -> Path:
    """Where the Point Mass target ends up: a 2-D histogram of (strategy_0, strategy_1).

    One panel per (Point Mass env, algo), pooling the last ``last`` interactions of every
    seed; colour = fraction of those interactions in the cell (square-root scale, shared by
    all panels). The circle the target moves on and the ego's start (0, 0) are drawn. Raises
    ValueError when no Point Mass run with strategy columns is given. Returns the path written.
    """
    if last < 1:
        raise ValueError(f"last={last!r} is invalid; allowed: an integer >= 1")
    panels: list[tuple[str, str, np.ndarray, int, int]] = []
    for env, by_algo in _group(runs).items():
        if "pointmass" not in _env_key(env):
            continue
        for algo, group in by_algo.items():
            points, used = [], 0
            for run in group:
                strat = run.strategy
                if strat is None or strat.shape[1] < 2:
                    continue
                xy = strat[-last:, :2]
                used = max(used, len(xy))
                points.append(xy[~np.isnan(xy).any(axis=1)])
            if points:
                panels.append((env, algo, np.concatenate(points), len(points), used))
    if not panels:
        raise ValueError("no Point Mass run with strategy_0/strategy_1 columns to plot")
    plt = _pyplot()
    from matplotlib.colors import PowerNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle

    edges = np.linspace(-PM_BOUND, PM_BOUND, 41)
    hists = []
    for _, _, xy, _, _ in panels:
        h, _, _ = np.histogram2d(xy[:, 0], xy[:, 1], bins=[edges, edges])
        hists.append(h / max(len(xy), 1))
    vmax = max(float(h.max()) for h in hists) or 1.0
    norm = PowerNorm(gamma=0.5, vmin=0.0, vmax=vmax)
    cmap = plt.get_cmap("magma_r").with_extremes(bad="white")
    ncols = 2 if len(panels) == 4 else min(len(panels), 3)
    nrows = math.ceil(len(panels) / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.7 * ncols + 1.0, 3.9 * nrows + 0.5),
                             squeeze=False, layout="constrained")
    multi_env = len({env for env, *_ in panels}) > 1
    mesh = None
    for ax, (env, algo, _xy, n_seeds, used), h in zip(axes.flat, panels, hists, strict=False):
        mesh = ax.pcolormesh(edges, edges, np.ma.masked_equal(h.T, 0.0), cmap=cmap, norm=norm)
        ax.add_patch(Circle(PM_CENTER, PM_RADIUS, fill=False, ec="0.35", lw=1.0, ls="--"))
        ax.plot([0.0], [0.0], marker="*", ms=13, color="#1f9bde", mec="black", mew=0.6, ls="")
        ax.set_xlim(-PM_BOUND, PM_BOUND)
        ax.set_ylim(-PM_BOUND, PM_BOUND)
        ax.set_aspect("equal")
        title = f"{algo_label(algo)}\n{n_seeds} seed{'s' * (n_seeds > 1)}, last {used} interactions"
        if multi_env:
            title = f"{env}: {title}"
        ax.set_title(title, fontsize=10, color=algo_color(algo))
        ax.set_xlabel("target x")
        ax.set_ylabel("target y")
        ax.tick_params(labelsize=8)
        ax.grid(True, alpha=0.2)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    legend = [
        Line2D([], [], marker="*", ms=11, color="#1f9bde", mec="black", ls="", label="ego start"),
        Line2D([], [], color="0.35", ls="--", label="circle the target moves on"),
    ]
    fig.legend(handles=legend, loc="outside lower center", ncol=2, fontsize=9, frameon=False)
    fig.suptitle("Point Mass: target position (partner's strategy) at the end of training",
                 fontsize=12)
    cbar = fig.colorbar(mesh, ax=axes.ravel().tolist(), shrink=0.8, pad=0.02)
    cbar.set_ticks(np.unique(np.round(np.linspace(0.0, 1.0, 6) ** 2 * vmax, 3)))
    cbar.set_label("fraction of interactions (sqrt scale)", fontsize=9)
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png


def strategy_frequencies(runs: Iterable[Run], last: int = STRATEGY_WINDOW) -> np.ndarray | None:
    """How often the partner played each discrete strategy over the last ``last`` interactions.

    Pools the runs given (e.g. the seeds of one algo); returns fractions indexed by
    ``strategy_id`` (length = largest id seen + 1), or None when no run logs an id >= 0.
    """
    counts: list[np.ndarray] = []
    for run in runs:
        ids = run.metrics.get("strategy_id")
        if ids is None:
            continue
        ids = ids[-last:]
        ids = ids[~np.isnan(ids) & (ids >= 0)].astype(int)
        if ids.size:
            counts.append(np.bincount(ids))
    if not counts:
        return None
    total = np.zeros(max(len(c) for c in counts))
    for c in counts:
        total[: len(c)] += c
    return total / total.sum()


def strategy_names(env: str, n: int) -> list[str]:
    """Names of strategies 0..n-1 (the paper's where known, else ``id k``)."""
    names = (paper_reference(env) or {}).get("strategy_names", [])
    return [names[k] if k < len(names) else f"id {k}" for k in range(n)]


def plot_strategy_frequencies(runs: Iterable[Run], out_png: str | Path,
                              last: int = STRATEGY_WINDOW) -> Path:
    """Bars of how often the partner played each strategy at the end, per env and algo.

    Like the paper's air hockey figure (how often the striker fired left, middle, right over
    the final 200 interactions): one subplot per env with discrete strategy ids, one group of
    bars per strategy, one bar per algo (seeds pooled). Raises ValueError when no run logs a
    strategy id. Returns the path written.
    """
    panels = []
    for env, by_algo in _group(runs).items():
        freqs = {algo: f for algo, group in by_algo.items()
                 if (f := strategy_frequencies(group, last)) is not None}
        if freqs:
            panels.append((env, freqs, {a: len(by_algo[a]) for a in freqs}))
    if not panels:
        raise ValueError("no run with a strategy_id column to plot")
    plt = _pyplot()
    nrows, ncols = _grid(len(panels))
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.6 * ncols, 3.8 * nrows), squeeze=False)
    for ax, (env, freqs, seeds) in zip(axes.flat, panels, strict=False):
        k = max(len(f) for f in freqs.values())
        width = 0.8 / len(freqs)
        for j, (algo, f) in enumerate(freqs.items()):
            f = np.pad(f, (0, k - len(f)))
            xs = np.arange(k) + (j - (len(freqs) - 1) / 2) * width
            n = seeds[algo]
            ax.bar(xs, f, width, color=algo_color(algo),
                   label=f"{algo_label(algo)} ({n} seed{'s' * (n > 1)})")
        ax.axhline(1.0 / k, color="0.4", ls=":", lw=1.0, label="uniform")
        ax.set_xticks(np.arange(k), strategy_names(env, k))
        ax.set_ylim(0, 1)
        ax.set_ylabel(f"fraction of the last {last} interactions")
        ax.set_title(_env_title(env), fontsize=11)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=8, framealpha=0.85)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle("Partner's strategy at the end of training", fontsize=12)
    fig.tight_layout()
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png


# ------------------------------------------------------------------------------------ report


def _json_safe(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return None if math.isnan(value) or math.isinf(value) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def write_report(paths: Sequence[str | Path], out_dir: str | Path,
                 upto: int | None = None) -> dict[str, Any]:
    """Find runs under ``paths`` and write the report into ``out_dir`` (created if needed).

    ``upto`` compares every run at one budget: only its first ``upto`` interactions count.

    Files: ``curves.png`` (return), ``success.png`` (only if some env defines success),
    ``heatmap.png`` (only if there are Point Mass runs), ``strategies.png`` (only if some run
    logs discrete strategy ids, :func:`plot_strategy_frequencies`), ``results.md``
    (:func:`markdown_table`) and ``results.json`` (``{"summary", "runs", "paper"}``). An optional
    PNG left by an earlier report in ``out_dir`` is removed when not produced this
    time. Prints nothing.

    Returns ``{"summary": summarize(...), "markdown": str, "runs": [run folders],
    "files": {name: path}}``. Raises ValueError as :func:`find_runs` does, or when no run has
    logged an interaction yet.
    """
    runs = find_runs(paths, upto)
    if not any(r.n_interactions for r in runs):
        raise ValueError(
            f"{', '.join(str(p) for p in paths)}: no run has logged an interaction yet"
        )
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    summary = summarize(runs)
    for row in summary:
        row["upto"] = upto
    markdown = markdown_table(summary)
    files: dict[str, str] = {}
    files["curves.png"] = str(plot_learning_curves(runs, out_dir / "curves.png", "return"))
    optional = {
        "success.png": (any(r.has_success for r in runs),
                        lambda p: plot_learning_curves(runs, p, "success")),
        "heatmap.png": (any("pointmass" in _env_key(r.env) and r.strategy is not None
                            and r.n_interactions for r in runs),
                        lambda p: plot_strategy_heatmap(runs, p)),
        "strategies.png": (any(strategy_frequencies([r]) is not None for r in runs),
                           lambda p: plot_strategy_frequencies(runs, p)),
    }
    for name, (wanted, plot) in optional.items():
        target = out_dir / name
        if wanted:
            files[name] = str(plot(target))
        elif target.is_file():
            target.unlink()
    (out_dir / "results.md").write_text(markdown, encoding="utf-8")
    files["results.md"] = str(out_dir / "results.md")
    run_paths = [str(r.path) for r in runs]
    payload = {"summary": summary, "runs": run_paths, "paper": PAPER}
    (out_dir / "results.json").write_text(
        json.dumps(_json_safe(payload), indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    files["results.json"] = str(out_dir / "results.json")
    return {"summary": _json_safe(summary), "markdown": markdown, "runs": run_paths, "files": files}
