"""Point Mass benchmark: SAC, Oracle, LILI and LILI (no influence), 3 seeds, beside the paper.

    python benchmarks/point_mass.py [--interactions 2000] [--seeds 3] [--jobs 2]

Prints final performance (mean +- s.e. over seeds of the mean return over the last 10% of
interactions) beside the paper's Table (SAC -5.05, LILI -0.72, Oracle -0.54), writes
``benchmarks/results/point_mass.{json,md}`` and the curves and target heatmap in
``<out>/report/``.
"""

from pathlib import Path

from _common import ROOT, parse_args, report, run_grid

ALGOS = ["sac", "oracle", "lili", "lili-no-influence"]

if __name__ == "__main__":
    args = parse_args(__doc__.splitlines()[0], ALGOS, interactions=2000)
    out = Path(args.out) if args.out else ROOT / "runs" / "bench_point_mass"
    run_grid("point-mass", args.algos, args.seeds, args.interactions, out, args.jobs, args.config)
    report(out, "point_mass")
