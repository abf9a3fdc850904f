"""How runs' return moves with their budget, window by window, beside the paper's number.

    python benchmarks/budget_windows.py RUN_GLOB [RUN_GLOB ...] [--paper noise]
        [--window 400] [--best 200] [--late 300] [--name budget_windows]

Runs are grouped by algo, env options and budget (so the same seeds at 2000 and at 4000
interactions are two groups). Per group: the final return (mean over the last 10% of each run's
interactions, as every table of the library scores it), mean +- s.e. and IQM [bootstrap 95% CI]
over seeds; with ``--paper TABLE`` (a table of :data:`lili.report.paper.PAPER_TABLES` with a
``parameter``, e.g. ``noise`` or ``history``), the paper's row for the group's parameter value
and the gap to it in combined standard errors; and how many seeds are still rising: their best
``--best``-interaction mean ends within the last ``--late`` interactions. A second table gives
the mean over seeds of every ``--window`` interactions, so a longer budget can be read against a
shorter one at the same interactions (the first 2000 interactions of a 4000-interaction run are
the 2000-interaction run of the same seed where the code did not change between them). A third
table gives each run's critic loss and mean Q in the same windows, which tell a critic that
diverges (its loss growing by orders of magnitude, its Q climbing while the return falls) from
one that learns. Prints the tables and writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import math

import numpy as np
from _results import records_args, write_result

from lili.experiments.presets import get_preset
from lili.report.files import load_run
from lili.report.paper import PAPER_TABLES
from lili.report.stats import final_performance, iqm_ci, mean_se
from lili.report.tables import fmt_interval, fmt_mean_se

CRITIC = ("critic_loss", "q")
"""The learning metrics the per-run table reads, window by window."""


def best_window_end(returns: np.ndarray, width: int) -> int:
    """The interaction (exclusive end) at which the run's best ``width``-interaction mean ends."""
    if len(returns) < width:
        raise ValueError(f"the run has {len(returns)} interactions; --best {width} needs as many")
    means = np.convolve(returns, np.ones(width) / width, mode="valid")
    return int(np.argmax(means)) + width


def _windows(values: np.ndarray, width: int) -> list[np.ndarray]:
    """Each whole ``width``-interaction window of ``values`` from the start."""
    return [values[i:i + width] for i in range(0, len(values) - width + 1, width)]


def window_means(returns: np.ndarray, width: int) -> list[float]:
    """The mean return of each whole ``width``-interaction window from the start."""
    return [float(part.mean()) for part in _windows(returns, width)]


def column_windows(values: np.ndarray, width: int) -> list[float | None]:
    """The mean of a learning metric over each whole ``width``-interaction window from the
    start, leaving out the rows without an update (empty cells); None for a window without."""
    kept = (part[~np.isnan(part)] for part in _windows(values, width))
    return [float(part.mean()) if part.size else None for part in kept]


def _num(v: float | None) -> str:
    """A critic loss or Q, three significant digits (losses span orders of magnitude)."""
    return "—" if v is None else f"{v:.3g}"


def paper_row(table: str | None, env_kwargs: dict) -> tuple[float, float] | None:
    """The paper's (mean, s.e.) for the group's parameter value, or None (no table, no row)."""
    if table is None:
        return None
    spec = PAPER_TABLES[table]
    # A run without the option is the table's plain row: the preset's group without env kwargs.
    default = next(g.value for g in get_preset(table).groups
                   if not g.env_kwargs and g.value is not None)
    value = env_kwargs.get(spec["parameter"], default)
    return next((row for key, row in spec["rows"].items() if math.isclose(key, value)), None)


def main() -> None:
    tables = sorted(k for k, v in PAPER_TABLES.items() if "parameter" in v)
    p, args, folders = records_args(
        __doc__, "budget_windows", {"window": 400, "best": 200, "late": 300},
        lambda q: q.add_argument("--paper", choices=tables,
                                 help="the paper's table to set beside each group"))
    groups: dict[tuple, list] = {}
    for folder in folders:
        run = load_run(folder)
        kwargs = run.config.get("env_kwargs") or {}
        key = (run.algo, tuple(sorted(kwargs.items())), len(run.metrics["return"]))
        groups.setdefault(key, []).append((folder, run))
    out, lines, wlines, clines = [], [], [], []
    widest = max(n for _, _, n in groups) // args.window
    for (algo, kwargs, n), runs in sorted(groups.items()):
        setting = ", ".join(f"{k}={v}" for k, v in kwargs) or "-"
        per_run = []
        for folder, run in runs:
            returns = np.asarray(run.metrics["return"], dtype=float)
            try:
                end = best_window_end(returns, args.best)
            except ValueError as e:
                p.error(f"{folder}: {e}")
            per_run.append({"run": folder, "seed": run.seed, "final": final_performance(run),
                            "best_window_end": end, "windows": window_means(returns, args.window),
                            **{f"{k}_windows": column_windows(
                                np.asarray(run.metrics[k], dtype=float), args.window)
                               for k in CRITIC}})
            r = per_run[-1]
            cells = [f"{_num(c)} / {_num(q)}" for c, q in zip(
                r["critic_loss_windows"], r["q_windows"], strict=True)]
            cells += [""] * (widest - len(cells))
            clines.append(f"| {algo} | {setting} | {run.seed} | {r['final']:.2f} | "
                          + " | ".join(cells) + " |")
        finals = [r["final"] for r in per_run]
        mean, se = mean_se(finals)
        centre, low, high = iqm_ci(finals)
        rising = sum(r["best_window_end"] > n - args.late for r in per_run)
        paper = paper_row(args.paper, dict(kwargs))
        gap = (None if paper is None
               else (mean - paper[0]) / math.sqrt(se ** 2 + paper[1] ** 2))
        windows = np.array([r["windows"] for r in per_run])
        w_mean = windows.mean(axis=0).tolist()
        out.append({"algo": algo, "env_kwargs": dict(kwargs), "interactions": n,
                    "seeds": len(per_run), "final_mean": mean, "final_se": se,
                    "final_iqm": centre, "final_iqm_ci": [low, high], "rising": rising,
                    "paper": paper, "gap_combined_se": gap, "window_means": w_mean,
                    "runs": per_run})
        paper_text = fmt_mean_se(*(paper or (None, None)), ".3f")
        gap_text = "—" if gap is None else f"{gap:+.1f}"
        lines.append(f"| {algo} | {setting} | {n} | {len(per_run)} | "
                     f"{fmt_mean_se(mean, se, '.3f', n=len(per_run))} | "
                     f"{fmt_interval(centre, low, high)} | {paper_text} | {gap_text} | "
                     f"{rising} of {len(per_run)} |")
        cells = [f"{m:.2f}" for m in w_mean] + [""] * (widest - len(w_mean))
        wlines.append(f"| {algo} | {setting} | {n} | " + " | ".join(cells) + " |")
    heads = [f"{(i + 1) * args.window}" for i in range(widest)]
    table = "\n".join([
        "final: mean return over the last 10% of each run's interactions; gap: (ours - paper) / "
        f"combined s.e.; rising: seeds whose best {args.best}-interaction mean ends in their "
        f"last {args.late} interactions", "",
        "| algo | partner | interactions | seeds | final (mean ± s.e.) | final IQM [95% CI] | "
        "paper | gap | rising |", "|---|---|---:|---:|---:|---:|---:|---:|---|", *lines, "",
        f"mean return over seeds of each {args.window} interactions, by the window's end", "",
        "| algo | partner | interactions | " + " | ".join(heads) + " |",
        "|---|---|---:|" + "---:|" * widest, *wlines, "",
        f"per run: final return, and critic loss / mean Q over each {args.window} interactions "
        "(rows with an update), by the window's end", "",
        "| algo | partner | seed | final | " + " | ".join(heads) + " |",
        "|---|---|---:|---:|" + "---:|" * widest, *clines])
    write_result(args.name, table, paper_table=args.paper, window=args.window, best=args.best,
                 late=args.late, groups=out)


if __name__ == "__main__":
    main()
