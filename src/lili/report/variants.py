"""The appendix tables whose rows are partner variants (noise level, history length).

Each row is one variant's LILI runs (and SAC's or the Oracle's where they ran at that variant);
SAC and the Oracle of the plain task are the bounds. Ours (mean +- s.e. over
seeds of :func:`~lili.report.stats.final_performance`) sit beside
:data:`~lili.report.paper.PAPER_TABLES`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lili.report.files import Run
from lili.report.paper import PAPER_TABLES
from lili.report.stats import final_performance, iqm_ci, mean_se
from lili.report.style import DPI, algo_color, algo_label
from lili.report.tables import fmt_interval, fmt_mean_se

__all__ = ["variant_rows", "variant_markdown", "plot_variants"]

Variant = tuple[str, Any, Sequence[Run]]


def variant_rows(variants: Sequence[Variant], bounds: Sequence[Run], table: str,
                 frac: float = 0.1) -> list[dict[str, Any]]:
    """One dict per variant (``label``, ``value``, runs) and algo in its runs (the table's
    own algo, LILI, first; SAC or the Oracle where they ran at that variant), and per bound
    algo (SAC, Oracle) of ``bounds``.

    Keys: ``label``, ``value`` (None for a bound), ``algo``, ``n``, ``seeds``, ``returns``,
    ``return_mean``, ``return_se``, ``return_iqm`` and ``return_iqm_ci`` (the IQM over seeds
    and its bootstrap 95% interval ``[low, high]``, :func:`~lili.report.stats.iqm_ci`; None
    without runs, the interval None with one seed), ``interactions`` (fewest logged),
    ``paper_mean`` and
    ``paper_se`` (None where the paper has no such row). Raises ValueError for an unknown
    ``table``.
    """
    if table not in PAPER_TABLES:
        raise ValueError(f"unknown paper table {table!r}; allowed: {', '.join(PAPER_TABLES)}")
    ref = PAPER_TABLES[table]
    rows = []

    def row(label: str, value: Any, algo: str, runs: Sequence[Run], paper) -> dict[str, Any]:
        runs = [r for r in runs if r.n_interactions]
        returns = [final_performance(r, "return", frac) for r in runs]
        mean, se = mean_se(returns)
        point, low, high = iqm_ci(returns) if returns else (None, None, None)
        return {"label": label, "value": value, "algo": algo, "n": len(runs),
                "seeds": sorted(r.seed for r in runs), "returns": returns,
                "return_mean": mean, "return_se": se, "return_iqm": point,
                "return_iqm_ci": None if low is None else [low, high],
                "interactions": min((r.n_interactions for r in runs), default=0),
                "paper_mean": None if paper is None else paper[0],
                "paper_se": None if paper is None else paper[1]}

    for label, value, runs in variants:
        # A variant's own algo first; SAC and the Oracle measured at that variant after it
        # (the paper aggregates them over all variants: its bound is their paper number).
        algos = dict.fromkeys([ref["algo"]] + [r.algo for r in runs])
        for algo in algos:
            mine = [r for r in runs if r.algo == algo]
            if mine or algo == ref["algo"]:
                paper = ref["rows"].get(value) if algo == ref["algo"] else ref["bounds"].get(algo)
                rows.append(row(label, value, algo, mine, paper))
    for algo in ("sac", "oracle"):
        runs = [r for r in bounds if r.algo == algo]
        if runs:
            rows.append(row(algo_label(algo), None, algo, runs, ref["bounds"].get(algo)))
    return rows


def variant_markdown(rows: Sequence[dict[str, Any]], table: str, bounds_from: str) -> str:
    """A markdown table of :func:`variant_rows`, with the paper's source and what differs."""
    ref = PAPER_TABLES[table]
    lines = [f"### {ref['title']}", "",
             f"| {ref['parameter_label']} | algo | seeds | final return (mean ± s.e.) "
             "| paper (mean ± s.e.) | IQM [95% CI] |",
             "|---|---|---:|---:|---:|---:|"]
    for r in rows:
        value = "—" if r["value"] is None else f"{r['value']:g}"
        lines.append(f"| {value} | {algo_label(r['algo'])} | {r['n']} "
                     f"| {fmt_mean_se(r['return_mean'], r['return_se'], n=r['n'])} "
                     f"| {fmt_mean_se(r['paper_mean'], r['paper_se'], '.4g')} "
                     f"| {fmt_interval(r['return_iqm'], *(r['return_iqm_ci'] or (None, None)))} |")
    lines += ["", f"Paper: {ref['source']}. Bounds: {ref['bounds_note']}; ours are {bounds_from}.",
              "Final = mean over the last 10% of interactions per seed; s.e. over seeds; IQM = "
              "interquartile mean over seeds with a percentile bootstrap 95% interval."]
    return "\n".join(lines) + "\n"


def plot_variants(rows: Sequence[dict[str, Any]], table: str, out_png: str | Path) -> Path:
    """Final return against the partner parameter: ours and the paper's, with s.e. bars, and
    the bootstrap 95% interval of our IQM as a band."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    ref = PAPER_TABLES[table]
    var = [r for r in rows if r["value"] is not None and r["return_mean"] is not None
           and r["algo"] == ref["algo"]]
    fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    xs = np.array([r["value"] for r in var], dtype=float)
    ax.errorbar(xs, [r["return_mean"] for r in var], [r["return_se"] for r in var],
                color=algo_color("lili"), marker="o", capsize=3, label="LILI (ours, mean ± s.e.)")
    banded = [r for r in var if r.get("return_iqm_ci")]
    if banded:
        ax.fill_between([r["value"] for r in banded], [r["return_iqm_ci"][0] for r in banded],
                        [r["return_iqm_ci"][1] for r in banded], color=algo_color("lili"),
                        alpha=0.15, lw=0, label="LILI (ours, IQM 95% CI)")
    paper = sorted(ref["rows"].items())
    ax.errorbar([k for k, _ in paper], [v[0] for _, v in paper], [v[1] for _, v in paper],
                color=algo_color("lili"), marker="s", ls="--", alpha=0.6, capsize=3,
                label="LILI (paper)")
    for algo in ("sac", "oracle"):
        at = [r for r in rows if r["value"] is not None and r["algo"] == algo
              and r["return_mean"] is not None]
        if at:
            ax.errorbar([r["value"] for r in at], [r["return_mean"] for r in at],
                        [r["return_se"] or 0.0 for r in at], color=algo_color(algo), marker="D",
                        ls="none", capsize=3, label=f"{algo_label(algo)} at that variant (ours)")
    for r in rows:
        if r["value"] is None and r["return_mean"] is not None:
            ax.axhline(r["return_mean"], color=algo_color(r["algo"]), lw=1.2,
                       label=f"{algo_label(r['algo'])} (ours)")
    for algo, (mean, _se) in ref["bounds"].items():
        ax.axhline(mean, color=algo_color(algo), lw=1.0, ls="--", alpha=0.6,
                   label=f"{algo_label(algo)} (paper)")
    ax.set_xlabel(ref["parameter_label"])
    ax.set_ylabel("final return per interaction")
    ax.set_title(ref["title"], fontsize=11)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best", framealpha=0.85)
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png
