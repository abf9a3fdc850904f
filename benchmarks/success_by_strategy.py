"""Success per partner strategy over training, from run folders (no training, no checkpoints).

    python benchmarks/success_by_strategy.py RUN_GLOB [RUN_GLOB ...] [--window 400]
        [--name success_by_strategy]

For every run: its success rate against each of the partner's discrete strategies
(``strategy_id``) in consecutive windows of ``--window`` interactions. In air hockey that is
the blocker's block rate per striker mode (left / middle / right) as it trains, which tells a
mode that is never learned from one that is never fired. Prints a table (``-`` where a window
holds fewer than 5 interactions of that strategy) and writes
``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

from _results import records_args, window_table, write_result

from lili.report.files import load_run
from lili.report.stats import strategy_names, success_by_strategy

MIN_SHOTS = 5


def main() -> None:
    p, args, folders = records_args(__doc__, "success_by_strategy", {"window": 400})
    out, rows = [], []
    for folder in folders:
        run = load_run(folder)
        try:
            counts = success_by_strategy(run, args.window)
        except ValueError as e:
            p.error(str(e))
        names = strategy_names(run.env, counts.shape[1])
        cells = [" / ".join(f"{100 * ok / n:3.0f}" if n >= MIN_SHOTS else "  -"
                            for ok, n in w) for w in counts]
        rows.append((folder, cells))
        out.append({"run": folder, "env": run.env, "algo": run.algo, "seed": run.seed,
                    "strategies": names, "window": args.window, "counts": counts.tolist()})
    table = window_table(f"success % per strategy ({' / '.join(out[0]['strategies'])})",
                         args.window, rows)
    write_result(args.name, table, runs=out)


if __name__ == "__main__":
    main()
