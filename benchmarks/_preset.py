"""The learning benchmarks are presets of ``lili reproduce`` (``lili.experiments``).

Each script runs its preset into ``runs/bench_<name>/`` (finished runs are skipped, killed
ones resumed) and copies the report's table, JSON and figures to ``benchmarks/results/``.
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from lili.experiments import reproduce

ROOT = Path(__file__).resolve().parent.parent


def benchmark(preset: str, name: str, doc: str) -> dict:
    """Parse the flags, run ``lili reproduce <preset>`` and copy its report to results/."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--algos", nargs="+")
    p.add_argument("--seeds", type=int)
    p.add_argument("--interactions", type=int)
    p.add_argument("--jobs", type=int, default=2, help="runs in parallel (default 2 = cores)")
    p.add_argument("--out", default=None, help="folder of the runs (default runs/bench_<name>)")
    args = p.parse_args()
    out = Path(args.out) if args.out else ROOT / "runs" / f"bench_{name}"
    result = reproduce(preset, out, seeds=args.seeds, interactions=args.interactions,
                       jobs=args.jobs, algos=tuple(args.algos) if args.algos else None)
    report = Path(result["report"]["dir"])
    results = ROOT / "benchmarks" / "results"
    results.mkdir(exist_ok=True)
    shutil.copy(report / "results.json", results / f"{name}.json")
    shutil.copy(report / "results.md", results / f"{name}.md")
    for png in report.glob("*.png"):
        shutil.copy(png, results / f"{name}_{png.name}")
    return result
