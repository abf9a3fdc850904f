"""Figures and tables from run folders (and nothing else).

- :mod:`~lili.report.files`: find and read run folders (``config.yaml`` + ``metrics.csv``),
  with one clear error for a file edited so that it would mislead.
- :mod:`~lili.report.stats`: final performance per seed (:func:`lili.runs.final_mean`, the
  number ``summary.json`` holds), mean +- s.e. over seeds, gap closed.
- :mod:`~lili.report.paper`: every number of the paper that is reproduced, with its place.
- :mod:`~lili.report.tables`, :mod:`~lili.report.figures`: markdown and PNG.
- :mod:`~lili.report.variants`: the appendix tables whose rows are partner variants.
- :mod:`~lili.report.write`: :func:`write_report`, what ``lili report`` runs.

Typical use::

    from lili.report import write_report
    result = write_report(["runs/"], "runs/report")   # curves.png, results.md, results.json, ...
"""

from lili.report.figures import (
    plot_learning_curves,
    plot_strategy_frequencies,
    plot_strategy_heatmap,
)
from lili.report.files import Run, find_runs, load_run
from lili.report.paper import PAPER, PAPER_TABLES, paper_reference
from lili.report.stats import (
    STRATEGY_WINDOW,
    final_performance,
    moving_average,
    strategy_frequencies,
    strategy_names,
    summarize,
)
from lili.report.style import ALGO_COLORS, algo_color, algo_label
from lili.report.tables import markdown_table
from lili.report.write import write_report

__all__ = [
    "ALGO_COLORS",
    "PAPER",
    "PAPER_TABLES",
    "Run",
    "STRATEGY_WINDOW",
    "algo_color",
    "algo_label",
    "final_performance",
    "find_runs",
    "load_run",
    "markdown_table",
    "moving_average",
    "paper_reference",
    "plot_learning_curves",
    "plot_strategy_heatmap",
    "plot_strategy_frequencies",
    "strategy_frequencies",
    "strategy_names",
    "summarize",
    "write_report",
]
