"""When each training metric first leaves its early level, per run: which one goes first.

    python benchmarks/metric_departures.py RUN_GLOB [RUN_GLOB ...] [--metrics critic_loss
        rep_loss alpha] [--window 100] [--base-from 300] [--base-to 500] [--factor 2]
        [--name metric_departures]

A run that fails late (its return falling in the second half while other seeds of the same
setting still rise) leaves a trail in its logged losses; the order in which they leave their
early level says which moved first. For every run folder (committed records serve), each
metric's mean over consecutive windows of ``--window`` interactions is compared with its mean
over interactions ``--base-from`` to ``--base-to`` - 1 (after the first updates' transient,
before any seed here fails); the first window from ``--base-to`` on whose mean exceeds
``--factor`` times that level is the metric's departure (none: it never did). Also given: the
return over the run's last 200 interactions. Prints a table and writes
``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import numpy as np
from _results import records_args, write_result

from lili.report.files import load_run


def departure(values: np.ndarray, window: int, base_from: int, base_to: int,
              factor: float) -> int | None:
    """The first interaction of the first window (of ``window``, from ``base_to`` on) whose
    mean exceeds ``factor`` times the mean over ``[base_from, base_to)``; None if none does.
    NaN entries (interactions before the first update) are left out of each mean."""
    level = np.nanmean(values[base_from:base_to])
    for start in range(base_to, len(values) - window + 1, window):
        if np.nanmean(values[start:start + window]) > factor * level:
            return start
    return None


def main() -> None:
    def more(p) -> None:
        p.add_argument("--metrics", nargs="+", default=["critic_loss", "rep_loss", "alpha"])
        p.add_argument("--factor", type=float, default=2.0)
        p.add_argument("--base-from", type=int, default=300)
        p.add_argument("--base-to", type=int, default=500)

    p, args, folders = records_args(__doc__, "metric_departures", {"window": 100}, more)
    if not args.factor > 1:
        p.error(f"--factor {args.factor} is invalid; allowed: a number > 1")
    if args.base_from < 0:
        p.error(f"--base-from {args.base_from} is invalid; allowed: an integer >= 0")
    if args.base_from >= args.base_to:
        p.error(f"--base-from {args.base_from} is invalid; allowed: below --base-to "
                f"({args.base_to})")
    runs = []
    for folder in folders:
        try:
            run = load_run(folder)
        except ValueError as e:
            p.error(f"run {folder}: {e}")
        missing = [m for m in args.metrics if m not in run.metrics]
        if missing:
            p.error(f"run {folder} logs no {', '.join(missing)}; allowed: "
                    f"{', '.join(sorted(run.metrics))}")
        if len(run.metrics["return"]) < args.base_to + args.window:
            p.error(f"run {folder} has {len(run.metrics['return'])} interactions; allowed: at "
                    f"least --base-to + --window ({args.base_to + args.window})")
        runs.append((folder, run))
    out, lines = [], []
    for folder, run in runs:
        row = {"run": folder, "final_200": round(float(np.mean(run.metrics["return"][-200:])), 4),
               **{m: departure(np.asarray(run.metrics[m], float), args.window, args.base_from,
                               args.base_to, args.factor) for m in args.metrics}}
        out.append(row)
        lines.append(f"| {folder} | " + " | ".join("-" if row[m] is None else str(row[m])
                                                   for m in args.metrics)
                     + f" | {row['final_200']:.3f} |")
    table = "\n".join([
        f"First window of {args.window} interactions whose mean exceeds {args.factor:g} times the "
        f"metric's mean over interactions {args.base_from}-{args.base_to - 1} ('-': never)", "",
        "| run | " + " | ".join(args.metrics) + " | return, last 200 |",
        "|---|" + "---:|" * (len(args.metrics) + 1), *lines])
    write_result(args.name, table, runs=out, metrics=args.metrics, window=args.window,
                 base=[args.base_from, args.base_to], factor=args.factor)


if __name__ == "__main__":
    main()
