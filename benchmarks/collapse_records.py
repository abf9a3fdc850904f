"""What the committed records show around Point Mass LILI's mid-run collapses (issue 36, item 4).

Reads only the ``metrics.csv`` of finished runs (nothing is trained or written) and prints, for
every run that collapses, its learning metrics just before and during the collapse beside the
runs that do not collapse, over the same interactions:

    python benchmarks/collapse_records.py                       # the committed Point Mass runs
    python benchmarks/collapse_records.py RUN_DIR [RUN_DIR ...]  # other run folders

A run *collapses* where, from interaction 900 on, the mean return of 100 interactions falls 1.0
or more below the best 100-interaction mean since interaction 400; the onset is the first
interaction of that window from which the 20-interaction mean is that low. Windows: *earlier*
= the 200 interactions before the 100 before the onset, *before* = the 100 before it, *during*
= the 100 from it. The references are the runs of the same group (the same code) that do not
collapse; the default groups are the Point Mass LILI runs before the core's redesign
(``bench_point_mass``, ``s9/point-mass-oldcore``) and after it (``s9/point-mass``); folders
given on the command line are one group each.

Two tables. *Levels*: each metric against the references' median over the same interactions
(``x`` a ratio, ``+`` a difference). *Changes*: each metric's change within the run from
*earlier* to *before* and to *during*, with the references' median change over the same
interactions in brackets; a cause shows a change before the return falls that the references
do not show. The target's angle (the partner's strategy, Point Mass's target on its circle)
says where the target went: its circular mean while held (*earlier*) and *during*, and the
share of the 500 interactions before the onset in which it was within 30 degrees of where it
went.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent / "results" / "runs"
DEFAULT = {"before the redesign": ("bench_point_mass/PointMass-v0/lili",
                                   "s9/point-mass-oldcore/PointMass-v0/lili"),
           "redesigned core": ("s9/point-mass/PointMass-v0/lili",)}
METRICS = ("critic_loss", "q", "alpha", "entropy", "rep_loss")
RATIO = {"critic_loss", "alpha", "rep_loss"}  # the others are shown as differences
NEAR_DEG = 30.0


def load(run: Path) -> dict[str, np.ndarray]:
    """The columns of a run's metrics.csv as float arrays (empty cells: nan)."""
    with (run / "metrics.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{run}/metrics.csv has no rows")
    return {k: np.array([float(r[k]) if r[k] else np.nan for r in rows]) for k in rows[0]}


def onset(ret: np.ndarray, drop: float = 1.0) -> int | None:
    """The interaction where the run collapses (module docstring), or None."""
    mean100 = np.convolve(ret, np.ones(100) / 100, "valid")
    mean20 = np.convolve(ret, np.ones(20) / 20, "valid")
    for i in range(900, len(mean100)):
        best = mean100[400:i - 99].max()
        if mean100[i] <= best - drop:
            return next(j for j in range(i, i + 100) if mean20[j] <= best - drop)
    return None


def angle(m: dict[str, np.ndarray]) -> np.ndarray:
    """The target's angle in degrees (Point Mass's strategy is its position on the circle)."""
    return np.degrees(np.arctan2(m["strategy_1"], m["strategy_0"]))


def circular_mean(deg: np.ndarray) -> float:
    rad = np.radians(deg)
    return float(np.degrees(np.arctan2(np.sin(rad).mean(), np.cos(rad).mean())))


def windows(start: int) -> dict[str, slice]:
    return {"earlier": slice(start - 300, start - 100), "before": slice(start - 100, start),
            "during": slice(start, start + 100)}


def _mean(values: np.ndarray, w: slice) -> float:
    return float(np.nanmean(values[w]))


def _fmt_value(metric: str, a: float, b: float) -> float:
    """``a`` against ``b``: a ratio for the metrics in RATIO, else a difference."""
    return a / b if metric in RATIO else a - b


def _shown(metric: str, value: float) -> str:
    return f"x{value:.2f}" if metric in RATIO else f"{value:+.2f}"


def _fmt(metric: str, a: float, b: float) -> str:
    return _shown(metric, _fmt_value(metric, a, b))


def level(metric: str, run: np.ndarray, refs: list[np.ndarray], start: int) -> str:
    """``earlier / before / during`` of ``metric`` against the reference runs' median."""
    return " / ".join(_fmt(metric, _mean(run, w), float(np.median([_mean(r, w) for r in refs])))
                      for w in windows(start).values())


def change(metric: str, run: np.ndarray, refs: list[np.ndarray], start: int) -> str:
    """``metric``'s change from *earlier* to *before* and to *during*, the references' median
    change in brackets."""
    w = windows(start)
    out = []
    for name in ("before", "during"):
        mine = _fmt(metric, _mean(run, w[name]), _mean(run, w["earlier"]))
        theirs = float(np.median([_fmt_value(metric, _mean(r, w[name]), _mean(r, w["earlier"]))
                                  for r in refs]))
        out.append(f"{mine} ({_shown(metric, theirs)})")
    return " / ".join(out)


def table(groups: dict[str, list[Path]]) -> list[str]:
    """The two tables (module docstring) for runs in ``groups`` (name -> run folders)."""
    levels = ["| group | run | onset | return: earlier / before / during | "
              + " | ".join(METRICS) + " | target angle: held / during | near it in the 500 "
              "before |", "|---|---|---:|---|" + "---|" * len(METRICS) + "---|---:|"]
    changes = ["| run | " + " | ".join(f"{m}: to before / to during" for m in METRICS) + " |",
               "|---|" + "---|" * len(METRICS)]
    notes = []
    for group, runs in groups.items():
        data = {run: load(run) for run in runs}
        starts = {run: onset(m["return"]) for run, m in data.items()}
        steady = [run for run, s in starts.items() if s is None]
        notes.append(f"- {group}: {len(runs)} runs, references (no collapse): "
                     f"{', '.join(_name(r) for r in steady) or 'none'}")
        for run, start in starts.items():
            if start is None:
                continue
            if not steady:
                raise SystemExit(f"group {group}: every run collapses, no reference runs")
            m, w = data[run], windows(start)
            refs = {k: [data[r][k] for r in steady] for k in METRICS}
            ret = " / ".join(f"{np.mean(m['return'][s]):.2f}" for s in w.values())
            deg = angle(m)
            went = circular_mean(deg[w["during"]])
            gap = np.abs((deg[max(0, start - 500):start] - went + 180) % 360 - 180)
            levels.append(f"| {group} | {_name(run)} | {start} | {ret} | "
                          + " | ".join(level(k, m[k], refs[k], start) for k in METRICS)
                          + f" | {circular_mean(deg[w['earlier']]):.0f} / {went:.0f} | "
                          f"{100 * np.mean(gap <= NEAR_DEG):.0f}% |")
            changes.append(f"| {_name(run)} | "
                           + " | ".join(change(k, m[k], refs[k], start) for k in METRICS) + " |")
    return [*notes, "", "Levels against the references:", "", *levels, "",
            "Changes within the run (the references' median change in brackets):", "",
            *changes]


def _name(run: Path) -> str:
    try:
        return str(run.relative_to(ROOT))
    except ValueError:
        return str(run)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="*", help="run folders (seed_*) or folders holding them")
    args = p.parse_args()
    roots = ({r: [Path(r)] for r in args.runs} if args.runs
             else {g: [ROOT / d for d in ds] for g, ds in DEFAULT.items()})
    groups: dict[str, list[Path]] = {}
    for group, folders in roots.items():
        for root in folders:
            found = [root] if (root / "metrics.csv").exists() else sorted(root.glob("seed_*"))
            if not found:
                raise SystemExit(f"{root}: no metrics.csv there or in its seed_* folders")
            groups.setdefault(group, []).extend(found)
    print("\n".join(table(groups)))


if __name__ == "__main__":
    main()
