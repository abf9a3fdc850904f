"""``lili results``: the one results page, ``docs/results.md``, written from the committed records
only (every number on it is computed from ``metrics.csv`` files; none is typed by hand).

Per paper item (the parts of the ``paper`` preset): a table of ours beside the paper's, one
figure (``docs/results/<preset>.png``), the claim checks (:mod:`lili.experiments.claims`),
which records are the evidence and why (the sources file), and the ``lili reproduce`` commands
that retrain those runs. Then the influence suite (:mod:`lili.experiments.influence_page`):
per suite env, the scripted optima beside the learned agents, with gap and held shares and
issue 36's goals. Regenerating it from the same records gives the same file, byte for byte
(``tests/test_results_page.py``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lili.experiments.claims import (
    RULE_NOTE,
    VERDICTS,
    Evidence,
    check_claim,
    claims_for,
    claims_markdown,
    load_evidence,
    load_sources,
    metric_values,
)
from lili.experiments.influence_page import influence_section
from lili.experiments.presets import PRESETS, Preset
from lili.experiments.provenance import (
    interactions_text,
    reproduce_commands,
    setting,
    sources_markdown,
)
from lili.experiments.why import Whys, load_why, why_beside, why_markdown
from lili.report.files import Run
from lili.report.paper import PAPER_TABLES
from lili.report.stats import iqm_ci, summarize
from lili.report.style import DPI, algo_color, algo_label, env_title
from lili.report.tables import fmt_interval, fmt_mean_se
from lili.report.variants import plot_variants, variant_rows

__all__ = ["write_results_page", "results_markdown", "DEFAULT_SOURCES", "DEFAULT_OUT",
           "DEFAULT_README", "QUICKSTART_BEGIN", "QUICKSTART_END", "quickstart_table",
           "with_quickstart_table"]

DEFAULT_SOURCES = "benchmarks/results/claims_sources.yaml"
DEFAULT_OUT = "docs/results.md"
DEFAULT_README = "README.md"
QUICKSTART_BEGIN = "<!-- quickstart-table: written by `lili results` from the committed records -->"
QUICKSTART_END = "<!-- /quickstart-table -->"


def _paper_cell(row: dict[str, Any]) -> str:
    cited = []
    if row.get("paper_return") is not None:
        cited.append(f"return {row['paper_return']:.2f}")
    if row.get("paper_success") is not None:
        cited.append(f"success {100 * row['paper_success']:.0f}%")
    elif row.get("paper_text"):
        cited.append(f"success {row['paper_text']}")
    return ", ".join(cited) or "—"


def _env_table(part: Preset, evidence: Evidence) -> tuple[str, list[dict[str, Any]]]:
    group = part.groups[0]
    runs = [r for algo in group.algos for r in evidence.get((group.folder, algo), [])]
    if not runs:
        return "No committed records.\n", []
    rows = summarize(runs)
    has_success = any(r["success_mean"] is not None for r in rows)
    head = "| algo | return IQM [95% CI] | return mean ± s.e. |"
    rule = "|---|---:|---:|"
    if has_success:
        head += " success IQM [95% CI] | success mean ± s.e. |"
        rule += "---:|---:|"
    lines = [head + " seeds | interactions | setting | paper |", rule + "---:|---:|---|---|"]
    for row in rows:
        mine = evidence[(group.folder, row["algo"])]
        ci = row["return_iqm_ci"] or (None, None)
        cells = [algo_label(row["algo"]), fmt_interval(row["return_iqm"], *ci),
                 fmt_mean_se(row["return_mean"], row["return_se"], n=row["n"])]
        if has_success:
            sci = row["success_iqm_ci"] or (None, None)
            cells += [fmt_interval(row["success_iqm"], *sci, pct=True),
                      fmt_mean_se(row["success_mean"], row["success_se"], pct=True, n=row["n"])]
        cells += [str(row["n"]), interactions_text(mine), setting(mine, group, part),
                  _paper_cell(row)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n", rows


def _variants(part: Preset, evidence: Evidence) -> tuple[list, list[Run]]:
    variants, bounds = [], []
    for group in part.groups:
        runs = [r for a in group.algos for r in evidence.get((group.folder, a), [])]
        if group.value is None:
            bounds += runs
        elif runs:
            variants.append((group.label, group.value, runs))
    return variants, bounds


def _variant_table(part: Preset, evidence: Evidence) -> tuple[str, list[dict[str, Any]]]:
    variants, bounds = _variants(part, evidence)
    if not variants:
        return "No committed records.\n", []
    rows = variant_rows(variants, bounds, part.table)
    ref = PAPER_TABLES[part.table]
    lines = [f"| {ref['parameter_label']} | algo | return IQM [95% CI] | return mean ± s.e. "
             "| seeds | interactions | setting | paper (mean ± s.e.) |",
             "|---|---|---:|---:|---:|---:|---|---:|"]
    by_label = {g.label: g for g in part.groups}
    for r in rows:
        if r["value"] is None:
            group = next(g for g in part.groups if g.value is None)
            mine = evidence.get((group.folder, r["algo"]), [])
        else:
            group = by_label[r["label"]]
            mine = evidence.get((group.folder, r["algo"]), [])
        value = "—" if r["value"] is None else f"{r['value']:g}"
        lines.append(
            f"| {value} | {algo_label(r['algo'])} "
            f"| {fmt_interval(r['return_iqm'], *(r['return_iqm_ci'] or (None, None)))} "
            f"| {fmt_mean_se(r['return_mean'], r['return_se'], n=r['n'])} | {r['n']} "
            f"| {interactions_text(mine)} | {setting(mine, group, part)} "
            f"| {fmt_mean_se(r['paper_mean'], r['paper_se'], '.4g')} |")
    return "\n".join(lines) + "\n", rows


def _plot_env(part: Preset, evidence: Evidence, rows: list[dict[str, Any]], path: Path) -> None:
    """Per metric the claims use: every seed's final value (dots), the IQM and its 95% CI
    (bar), the paper's number where it gives one (hollow square)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    group = part.groups[0]
    metrics = [m for m in ("return", "success")
               if any(c.metric == m for _, c in claims_for(part))]
    fig, axes = plt.subplots(1, len(metrics), figsize=(5.2 * len(metrics), 3.8),
                             layout="constrained", squeeze=False)
    algos = [r["algo"] for r in rows]
    paper = {r["algo"]: r for r in rows}
    for ax, metric in zip(axes[0], metrics, strict=True):
        scale = 100.0 if metric == "success" else 1.0
        for x, algo in enumerate(algos):
            values = metric_values(evidence[(group.folder, algo)], metric)
            if not values:
                continue
            color = algo_color(algo)
            jitter = np.linspace(-0.15, 0.15, len(values)) if len(values) > 1 else [0.0]
            ax.scatter(x + np.asarray(jitter), scale * np.asarray(values), s=12, color=color,
                       alpha=0.5, lw=0)
            point, low, high = iqm_ci(values)
            err = None if low is None else [[scale * (point - low)], [scale * (high - point)]]
            ax.errorbar([x], [scale * point], yerr=err, color=color, marker="o", capsize=4,
                        lw=2)
            cited = paper[algo].get(f"paper_{metric}")
            if cited is not None:
                ax.scatter([x + 0.3], [scale * cited], marker="s", facecolors="none",
                           edgecolors=color, s=40)
        ax.set_xticks(range(len(algos)), [algo_label(a) for a in algos], rotation=30,
                      ha="right", fontsize=8)
        ax.set_ylabel("final success (%)" if metric == "success" else "final return")
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"{part.title}: seeds (dots), IQM and 95% CI (bars), paper (squares)",
                 fontsize=10)
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    plt.close(fig)


def _section(part: Preset, locate, evidence: Evidence, figures: Path | None,
             rel: str, whys: Whys | None) -> tuple[str, list]:
    if part.kind == "table":
        table, rows = _variant_table(part, evidence)
    else:
        table, rows = _env_table(part, evidence)
    results = [(part, check_claim(part, claim, evidence)) for _, claim in claims_for(part)]
    figure = ""
    if rows:
        png = f"{part.name}.png"
        if figures is not None and part.kind == "table":
            plot_variants(rows, part.table, figures / png)
        elif figures is not None:
            _plot_env(part, evidence, rows, figures / png)
        figure = f"![{part.title}]({rel}/{png})\n\n"
    envs = ", ".join(env_title(e) for e in part.envs)
    commands = reproduce_commands(part, evidence)
    text = (f"## {part.title}\n\nPaper: {part.where}. Env: {envs}. Ours: {part.metric}.\n\n"
            f"{table}\n{figure}**Claims**\n\n"
            f"{claims_markdown(results, with_part=False, rules=False)}\n"
            f"{_why(results, whys)}"
            f"**Evidence** (committed records)\n\n{sources_markdown(part, locate)}\n"
            "**Reproduce** (retrains these runs into `runs/reproduce`; the last command "
            "checks the claims)\n\n```\n" + "\n".join(commands)
            + f"\nlili reproduce {part.name} --check-only\n```\n")
    return text, results


def _why(results: list, whys: Whys | None) -> str:
    """The claim table's "Why the FAILs fail" list and a blank line (nothing where there is no
    explanations' file or nothing FAILs)."""
    text = why_markdown(results, whys)
    return f"{text}\n" if text else ""


def results_markdown(sources: str | Path = DEFAULT_SOURCES,
                     figures: str | Path | None = None, rel: str = "results") -> str:
    """The page's markdown from the records ``sources`` names; figures are written into
    ``figures`` (none when None) and linked as ``rel/<preset>.png``."""
    locate = load_sources(sources)
    why_file = why_beside(sources)
    whys = load_why(why_file) if why_file.is_file() else None  # checked before any figure
    paper = PRESETS["paper"]
    evidence = load_evidence(paper, locate)
    fig_dir = Path(figures) if figures is not None else None
    if fig_dir is not None:
        fig_dir.mkdir(parents=True, exist_ok=True)
    sections, all_results = [], []
    for name in paper.includes:
        part = PRESETS[name]
        text, results = _section(part, locate, evidence, fig_dir, rel, whys)
        sections.append(text)
        all_results += results
    influence, _ = influence_section(locate, evidence, whys)
    counts = {v: sum(r.verdict == v for _, r in all_results) for v in VERDICTS}
    summary = claims_markdown(all_results, rules=False)
    head = (
        "# Results\n\n"
        "<!-- Generated by `lili results` from the committed records; do not edit by hand. -->\n\n"
        "Every number on this page is computed by `lili results` from the per-interaction "
        f"records under `benchmarks/results/runs/` that `{Path(sources).as_posix()}` names "
        "for each experiment; none is typed by hand. Final = the mean over the last 10% of a "
        "run's interactions (success: the same over the success flag; a striker's mode: its "
        "share of the last 200 interactions), one number per seed. Across seeds: the "
        "interquartile mean (IQM; with 3 seeds the mean) with a percentile bootstrap 95% "
        "confidence interval, beside mean ± s.e.; P(>) is the probability of improvement "
        "(Agarwal et al. 2021) with its stratified bootstrap interval. 'Setting' names what a "
        "row's runs changed from the preset (`lili reproduce --set` / `--interactions`). "
        "The lab journal behind these records is `docs/journal/2026-11-to-12.md`."
        + ("" if whys is None else " Under each claim table, \"Why the FAILs fail\" gives "
           "each FAIL the experiment that says why, in words, or says that it is not yet "
           f"explained (`{why_file.as_posix()}`).")
        + "\n\n"
        f"**{counts['PASS']} of the paper's {len(all_results)} claims PASS, "
        f"{counts['FAIL']} FAIL, {counts['too few seeds']} have too few seeds.** {RULE_NOTE} "
        "The same table, from the same records, without writing anything: `lili reproduce "
        f"paper --check-only --sources {Path(sources).as_posix()}`.\n\n{summary}\n"
    )
    return head + "\n".join([*sections, influence])


def quickstart_table(sources: str | Path = DEFAULT_SOURCES) -> str:
    """The README's quick-start table: ``make run``'s algos (the ``quickstart`` preset) from
    the records ``sources`` names, as the results page tables an env (:func:`_env_table`)."""
    part = PRESETS["quickstart"]
    return _env_table(part, load_evidence(part, load_sources(sources)))[0]


def with_quickstart_table(readme: str, table: str) -> str:
    """``readme`` with the text between its quick-start markers replaced by ``table``;
    ValueError when the markers are not there once each, in order."""
    begin, end = readme.find(QUICKSTART_BEGIN), readme.find(QUICKSTART_END)
    if readme.count(QUICKSTART_BEGIN) != 1 or readme.count(QUICKSTART_END) != 1 or end < begin:
        raise ValueError(f"the README has no {QUICKSTART_BEGIN!r} ... {QUICKSTART_END!r} "
                         "block; allowed: a README with each marker once, in that order")
    head = readme[:begin + len(QUICKSTART_BEGIN)]
    return f"{head}\n{table}{readme[end:]}"


def write_results_page(sources: str | Path = DEFAULT_SOURCES,
                       out: str | Path = DEFAULT_OUT,
                       readme: str | Path | None = None) -> Path:
    """Write the page to ``out`` and its figures to ``results/`` beside it; return its path.
    ``readme``: a README whose quick-start block (:func:`with_quickstart_table`) is rewritten
    too, checked before anything is written."""
    out = Path(out)
    if out.exists() and not out.is_file():
        raise ValueError(f"--out {out} is not a file; allowed: a markdown file path")
    new_readme = None
    if readme is not None:
        readme = Path(readme)
        try:
            old = readme.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            raise ValueError(f"--readme {readme}: cannot read it ({e}); allowed: a readable "
                             "text file, or none") from None
        table = quickstart_table(sources)  # a bad --sources is its own error, not the README's
        try:
            new_readme = with_quickstart_table(old, table)
        except ValueError as e:
            raise ValueError(f"--readme {readme}: {e}") from None
    text = results_markdown(sources, out.parent / "results", "results")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    if new_readme is not None:
        readme.write_text(new_readme, encoding="utf-8")
    return out
