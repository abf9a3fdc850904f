"""Markdown tables: ours (mean +- s.e. over seeds) beside the paper's numbers."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from lili.report.paper import paper_reference
from lili.report.stats import STRATEGY_WINDOW, strategy_names
from lili.report.style import algo_label, env_title

__all__ = ["markdown_table", "fmt_mean_se", "fmt_duration", "fmt_interval"]


def fmt_mean_se(value: float | None, se: float | None, spec: str = ".2f", pct: bool = False,
                n: int | None = None) -> str:
    """``-1.00 ± 0.29`` (or a percentage), ``—`` when there is no value.

    The value alone when ``se`` is None or it is the mean of ``n`` = 1 seed: one seed has no
    standard error, and "± 0.00" would read as a spread measured to be zero.
    """
    if value is None:
        return "—"
    if pct:
        text = f"{100 * value:.1f}%"
        spread = f" ± {100 * (se or 0.0):.1f}%"
    else:
        text = f"{value:{spec}}"
        spread = f" ± {(se or 0.0):{spec}}"
    return text if se is None or n == 1 else text + spread


def fmt_interval(value: float | None, low: float | None = None, high: float | None = None,
                 spec: str = ".2f", pct: bool = False) -> str:
    """``1.16 [1.07, 1.26]`` (a point and its interval; a percentage with ``pct``), the point
    alone without bounds (one seed), ``—`` without a value."""
    if value is None:
        return "—"
    scale, unit, spec = (100.0, "%", ".1f") if pct else (1.0, "", spec)
    text = f"{scale * value:{spec}}{unit}"
    if low is None or high is None:
        return text
    return f"{text} [{scale * low:{spec}}, {scale * high:{spec}}]"


def _fmt_iqm(row: dict[str, Any], metric: str, pct: bool = False) -> str:
    ci = row.get(f"{metric}_iqm_ci") or (None, None)
    return fmt_interval(row.get(f"{metric}_iqm"), *ci, pct=pct)


def fmt_duration(seconds: float | None) -> str:
    """Seconds below two minutes, minutes above; ``—`` when unknown."""
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
            f"### {env_title(env)}",
            "",
            "| algo | seeds | final return (mean ± s.e.) | success (mean ± s.e.) "
            "| gap closed | paper | wall time / run | return IQM [95% CI] "
            "| success IQM [95% CI] |",
            "|---|---:|---:|---:|---:|---|---:|---:|---:|",
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
                f"| {fmt_mean_se(row['return_mean'], row['return_se'], n=row['n'])} "
                f"| {fmt_mean_se(row['success_mean'], row['success_se'], pct=True, n=row['n'])} "
                f"| {gap} | {paper} | {fmt_duration(row.get('wall_time_mean'))} "
                f"| {_fmt_iqm(row, 'return')} | {_fmt_iqm(row, 'success', pct=True)} |"
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
        lengths = [row for row in rows if row.get("length_mean") is not None]
        # Only where interactions end early: there the length is part of what an agent learnt
        # (an agent that bootstraps across the boundary is paid for ending sooner).
        if len({round(row["length_mean"], 6) for row in lengths}) > 1:
            shares = ", ".join(
                f"{algo_label(row['algo'])} "
                f"{fmt_mean_se(row['length_mean'], row['length_se'], '.1f', n=row['n'])}"
                for row in lengths)
            notes.append(f"Steps per interaction (final, mean ± s.e.): {shares}.")
        if "return" in ref:
            over = f" over {ref['seeds']} seeds" if "seeds" in ref else ""
            notes.append(f"Paper: final return{over} ({ref['source']}).")
        if "text" in ref:
            notes.append(f"Paper: {ref['text']}.")
        upto = rows[0].get("upto")
        window = f"the first {upto} interactions" if upto else "interactions"
        if rows[0].get("policy_only"):
            window += " the policy played (those played at random left out)"
        notes.append(
            f"Final = mean over the last 10% of {window} per seed; s.e. over seeds; "
            "gap closed = (R − R_SAC) / (R_Oracle − R_SAC); IQM = interquartile mean over "
            "seeds (the mean with 3 seeds), with a percentile bootstrap 95% confidence "
            "interval over seeds."
        )
        lines += ["", *notes]
        parts.append("\n".join(lines))
    return "\n\n".join(parts) + "\n"
