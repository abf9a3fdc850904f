"""The report of a preset: ``<out>/<name>/report/`` with figures, ``results.md`` and JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from lili.experiments.plan import RunSpec
from lili.experiments.presets import PRESETS, Preset
from lili.report import PAPER_TABLES, find_runs, write_report
from lili.report.variants import plot_variants, variant_markdown, variant_rows
from lili.report.write import json_safe
from lili.runs import check_out_dir

__all__ = ["write_preset_report"]


def _header(preset: Preset, specs: list[RunSpec], of: int | None = None,
            changes: str = "", paper_settings: bool = False) -> str:
    budget = max(s.interactions for s in specs)
    seeds = len({s.seed for s in specs})
    interim = ("" if of is None or of == len(specs) else
               f"**Interim report: {len(specs)} of {of} runs finished** (`--report-only`); "
               "the seeds column counts each row's. ")
    if changes:  # an ablation must not read as the preset itself beside the paper
        interim += f"**Every run changed from the preset's:** {changes}. "
    departs = preset.departs()
    if departs and paper_settings:
        interim += "At the paper's own setting (`--paper-settings`). "
    elif departs:  # a reader compares it with the paper: say where it is not the paper's run
        interim += f"**Departs from the paper's setting:** {departs}. "
    return (f"## {preset.title} (`lili reproduce {preset.name}`)\n\n{interim}"
            f"Paper: {preset.where}. "
            f"Ours: {seeds} seed{'s' * (seeds > 1)}, {budget} interactions per run; "
            f"{preset.metric}.\n\n")


def _table_report(preset: Preset, specs: list[RunSpec], out: Path) -> dict[str, Any]:
    upto = min(s.interactions for s in specs)
    variants, bounds = [], []
    by_folder: dict[str, list] = {}
    for group in preset.groups:
        dirs = [s.run_dir for s in specs if s.folder == group.folder and s.algo in group.algos]
        if not dirs:
            continue
        # One group at a time: the groups hold the same (env, algo, seed) under different env
        # kwargs (sigma = 0.2 and 0.4), which one find_runs call refuses as duplicate seeds.
        mine = find_runs(dirs, upto=upto)
        by_folder.setdefault(group.folder, []).extend(mine)
        if group.value is None:
            bounds += mine
        else:
            variants.append((group.label, group.value, mine))
    rows = variant_rows(variants, bounds, preset.table)
    bounds_from = ("the Point Mass preset's runs (sigma = 0, N = 1)" if bounds
                   else "not run (use --algos without a filter)")
    markdown = variant_markdown(rows, preset.table, bounds_from)
    out.mkdir(parents=True, exist_ok=True)
    files = {"variants.png": str(plot_variants(rows, preset.table, out / "variants.png"))}
    for folder, runs in by_folder.items():  # learning curves per variant, never mixed
        name = "curves/" + folder.replace("/", "_")
        curves = write_report([r.path for r in runs], out / name, upto=upto)
        files.update({f"{name}/{k}": v for k, v in curves["files"].items()})
    return {"rows": rows, "markdown": markdown, "files": files}


def write_preset_report(preset: Preset, specs: list[RunSpec], out: Path,
                        planned: list[RunSpec] | None = None,
                        changes: str = "", paper_settings: bool = False) -> dict[str, Any]:
    """Write ``out/<preset>/report/`` (and each part's report for ``paper``); return it.

    ``planned``: every run of the preset, when ``specs`` are only the finished ones (an
    interim report says so in its header). ``changes``: the ``--set`` / ``--env-kwarg``
    flags every run was given, named in the header. ``paper_settings``: the runs are at the
    paper's setting, not the preset's departures from it (the header says which).
    """
    report_dir = check_out_dir(out / preset.name / "report")
    parts = [PRESETS[n] for n in preset.includes] or [preset]
    sections, payload = [], {}
    for part in parts:
        mine = [s for s in specs if s.preset == part.name]
        if not mine:
            continue
        part_dir = out / part.name / "report"
        if part.kind == "table":
            result = _table_report(part, mine, part_dir)
            payload[part.name] = {"rows": result["rows"], "files": result["files"],
                                  "paper": PAPER_TABLES[part.table]}
            (part_dir / "results.json").write_text(
                json.dumps(json_safe(payload[part.name]), indent=1) + "\n")
        else:  # write_report writes results.json (ours, the runs, the paper's numbers)
            result = write_report([s.run_dir for s in mine], part_dir,
                                  upto=min(s.interactions for s in mine))
            payload[part.name] = {"summary": result["summary"], "files": result["files"]}
        of = None if planned is None else sum(s.preset == part.name for s in planned)
        text = _header(part, mine, of, changes, paper_settings) + result["markdown"]
        (part_dir / "results.md").write_text(text, encoding="utf-8")
        rel = Path("..") / ".." / part.name / "report" if part is not preset else Path(".")
        figures = [f"![{name}]({rel / name})" for name in result["files"]
                   if name.endswith(".png")]
        sections.append(text + "\n" + "\n".join(figures) + "\n")
    report_dir.mkdir(parents=True, exist_ok=True)
    markdown = "\n".join(sections)
    if preset.includes:
        (report_dir / "results.md").write_text(f"# {preset.title}\n\n{markdown}",
                                               encoding="utf-8")
        (report_dir / "results.json").write_text(json.dumps(json_safe(payload), indent=1) + "\n")
    return {"markdown": markdown, "results": payload, "dir": str(report_dir)}
