"""``write_report``: find runs, write the figures, ``results.md`` and ``results.json``."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from lili.report.figures import (
    plot_learning_curves,
    plot_strategy_frequencies,
    plot_strategy_heatmap,
)
from lili.report.files import find_runs
from lili.report.paper import PAPER
from lili.report.stats import strategy_frequencies, summarize
from lili.report.style import env_key
from lili.report.tables import markdown_table
from lili.runs import check_out_dir

__all__ = ["write_report", "json_safe", "check_out_dir"]


def json_safe(value: Any) -> Any:
    """``value`` with numpy scalars as Python numbers and NaN / inf as None (strict JSON)."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return None if math.isnan(value) or math.isinf(value) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def write_report(paths: Sequence[str | Path], out_dir: str | Path,
                 upto: int | None = None, policy_only: bool = False) -> dict[str, Any]:
    """Find runs under ``paths`` and write the report into ``out_dir`` (created if needed).

    ``upto`` compares every run at one budget: only its first ``upto`` interactions count.
    ``policy_only`` leaves out the interactions that training played at random after the
    warm-up (``AgentConfig.random_interactions``; :meth:`Run.policy_only`), so that runs with
    and without them are compared on what their policies did.

    Files: ``curves.png`` (return), ``success.png`` (only if some env defines success),
    ``heatmap.png`` (only if there are Point Mass runs), ``strategies.png`` (only if some run
    logs discrete strategy ids, :func:`plot_strategy_frequencies`), ``results.md``
    (:func:`markdown_table`) and ``results.json`` (``{"summary", "runs", "paper"}``). An optional
    PNG left by an earlier report in ``out_dir`` is removed when not produced this
    time. Prints nothing.

    Returns ``{"summary": summarize(...), "markdown": str, "runs": [run folders],
    "files": {name: path}}``. Raises ValueError as :func:`find_runs` does, when ``out_dir`` is
    a file (:func:`check_out_dir`) or when no run has logged an interaction yet; nothing is
    written then.
    """
    out_dir = check_out_dir(out_dir)
    runs = find_runs(paths, upto, policy_only)
    if not any(r.n_interactions for r in runs):
        raise ValueError(
            f"{', '.join(str(p) for p in paths)}: no run has logged an interaction yet"
        )
    out_dir.mkdir(parents=True, exist_ok=True)
    summary = summarize(runs)
    for row in summary:
        row["upto"] = upto
        row["policy_only"] = policy_only
    markdown = markdown_table(summary)
    files: dict[str, str] = {}
    files["curves.png"] = str(plot_learning_curves(runs, out_dir / "curves.png", "return"))
    optional = {
        "success.png": (any(r.has_success for r in runs),
                        lambda p: plot_learning_curves(runs, p, "success")),
        "heatmap.png": (any("pointmass" in env_key(r.env) and r.strategy is not None
                            and r.n_interactions for r in runs),
                        lambda p: plot_strategy_heatmap(runs, p)),
        "strategies.png": (any(strategy_frequencies([r]) is not None for r in runs),
                           lambda p: plot_strategy_frequencies(runs, p)),
    }
    for name, (wanted, plot) in optional.items():
        target = out_dir / name
        if wanted:
            files[name] = str(plot(target))
        elif target.is_file():
            target.unlink()
    (out_dir / "results.md").write_text(markdown, encoding="utf-8")
    files["results.md"] = str(out_dir / "results.md")
    run_paths = [str(r.path) for r in runs]
    payload = {"summary": summary, "runs": run_paths, "paper": PAPER}
    (out_dir / "results.json").write_text(
        json.dumps(json_safe(payload), indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    files["results.json"] = str(out_dir / "results.json")
    return {"summary": json_safe(summary), "markdown": markdown, "runs": run_paths, "files": files}
