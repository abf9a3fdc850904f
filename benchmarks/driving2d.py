"""Driving (2D) benchmark: SAC, Oracle, LILI and LILI (no influence), 3 seeds.

    python benchmarks/driving2d.py [--interactions 1000] [--seeds 3] [--jobs 2]

Prints final return and success rate over the last 10% of interactions (mean +- s.e. over seeds)
beside the paper's description (LILI and Oracle near 100% success, SAC about 50% or below),
writes ``benchmarks/results/driving2d.{json,md}`` and curves in ``<out>/report/``.
"""

from pathlib import Path

from _common import ROOT, parse_args, report, run_grid

ALGOS = ["sac", "oracle", "lili", "lili-no-influence"]

if __name__ == "__main__":
    args = parse_args(__doc__.splitlines()[0], ALGOS, interactions=1000)
    out = Path(args.out) if args.out else ROOT / "runs" / "bench_driving2d"
    run_grid("driving-2d", args.algos, args.seeds, args.interactions, out, args.jobs, args.config)
    report(out, "driving2d")
