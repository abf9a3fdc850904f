"""Where a Point Mass partner's target went, and what each target cost, from run folders.

    python benchmarks/target_spread.py RUN_GLOB [RUN_GLOB ...] [--last 200] [--history 800]
        [--name target_spread]

For every run (an env whose partner strategy is a point on a circle, as Point Mass's target):
over its last ``--last`` interactions, the mean return, how many 10-degree sectors of the
circle the target visited, and the mean return on targets in sectors the run met often against
those it met seldom, "often" meaning more often than the median target in the ``--history``
interactions before. An agent that parks the target on a few spots only has to be precise there;
one whose partner is walked around the circle by noise meets targets it has seldom trained on.
Prints a table and writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import numpy as np
from _results import records_args, write_result

from lili.report.files import load_run

SECTOR_DEG = 10.0


def sectors(run_metrics: dict[str, np.ndarray]) -> np.ndarray:
    """The 10-degree sector (0-35) of the target at every interaction."""
    if "strategy_0" not in run_metrics or "strategy_1" not in run_metrics:
        raise ValueError("the run logs no two-dimensional partner strategy (strategy_0/1)")
    angle = np.degrees(np.arctan2(run_metrics["strategy_1"], run_metrics["strategy_0"])) % 360
    return (angle // SECTOR_DEG).astype(int)


def spread(returns: np.ndarray, sector: np.ndarray, last: int, history: int) -> dict[str, float]:
    """The figures of one run (see the module docstring); ValueError when it is too short."""
    n = len(returns)
    if n < last + history:
        raise ValueError(f"the run has {n} interactions; --last {last} and --history {history} "
                         f"need {last + history}")
    seen = np.bincount(sector[n - last - history:n - last], minlength=36)
    recent = slice(n - last, n)
    count = seen[sector[recent]]
    often = count > np.median(count)
    ret = returns[recent]
    return {"return": float(ret.mean()),
            "sectors": int(len(np.unique(sector[recent]))),
            "return_often": float(ret[often].mean()) if often.any() else float("nan"),
            "return_seldom": float(ret[~often].mean()) if (~often).any() else float("nan"),
            "n_often": int(often.sum()), "n_seldom": int((~often).sum())}


def partner_setting(config: dict) -> tuple[dict, str]:
    """A run's env options (its config's ``env_kwargs``) and how the tables print them."""
    kwargs = config.get("env_kwargs") or {}
    return kwargs, ", ".join(f"{k}={v}" for k, v in sorted(kwargs.items())) or "-"


def main() -> None:
    p, args, folders = records_args(__doc__, "target_spread", {"last": 200, "history": 800})
    out, lines = [], []
    for folder in folders:
        run = load_run(folder)
        try:
            row = spread(run.metrics["return"], sectors(run.metrics), args.last, args.history)
        except ValueError as e:
            p.error(f"{folder}: {e}")
        kwargs, setting = partner_setting(run.config)
        out.append({"run": folder, "env": run.env, "algo": run.algo, "seed": run.seed,
                    "env_kwargs": kwargs, **row})
        lines.append(f"| {folder} | {setting} | {row['return']:.3f} | {row['sectors']} | "
                     f"{row['return_often']:.3f} ({row['n_often']}) | "
                     f"{row['return_seldom']:.3f} ({row['n_seldom']}) |")
    table = "\n".join([
        f"last {args.last} interactions; often/seldom: the target's sector met more / not more "
        f"often than the median target in the {args.history} interactions before", "",
        "| run | partner | return | sectors visited | return, often-met target (n) | "
        "return, seldom-met target (n) |", "|---|---|---:|---:|---:|---:|", *lines])
    write_result(args.name, table, last=args.last, history=args.history, runs=out)


if __name__ == "__main__":
    main()
