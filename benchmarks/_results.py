"""Where the benchmark scripts write their JSON, the check of a ``--name`` for it, and the command
line of the scripts that read run folders (:func:`records_args`)."""

from __future__ import annotations

import argparse
import glob
import json
from collections.abc import Callable
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def check_result_name(parser: argparse.ArgumentParser, name: str) -> None:
    """Refuse a ``--name`` that is not a plain file name (it would write outside results/)."""
    if not name or Path(name).name != name or name.startswith("."):
        parser.error(f"--name {name!r} is invalid; allowed: a plain file name (it is written "
                     f"under {RESULTS})")


def run_folders(parser: argparse.ArgumentParser, patterns: list[str]) -> list[str]:
    """The run folders each glob pattern matches, in order; a pattern matching none is an
    error of ``parser``."""
    folders: list[str] = []
    for pattern in patterns:
        found = sorted(glob.glob(pattern))
        if not found:
            parser.error(f"{pattern!r} matches no run folder")
        folders += found
    return folders


def records_args(doc: str, name: str, counts: dict[str, int],
                 more: Callable[[argparse.ArgumentParser], None] | None = None,
                 ) -> tuple[argparse.ArgumentParser, argparse.Namespace, list[str]]:
    """The command line of a script that reads run folders: ``RUN_GLOB ...``, the options
    ``more`` adds, one integer option ``--<flag>`` per entry ``flag: default`` of ``counts``
    (each checked >= 1), and ``--name`` (default ``name``, checked). Returns the parser (for
    errors about the runs), the arguments and the run folders the globs match, in order."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("runs", nargs="+", metavar="RUN_GLOB")
    if more is not None:
        more(p)
    for flag, default in counts.items():
        p.add_argument(f"--{flag}", type=int, default=default)
    p.add_argument("--name", default=name, help="results file name (without .json)")
    args = p.parse_args()
    for flag in counts:
        if getattr(args, flag) < 1:
            p.error(f"--{flag} {getattr(args, flag)} is invalid; allowed: an integer >= 1")
    check_result_name(p, args.name)
    return p, args, run_folders(p, args.runs)


def write_result(name: str, table: str, **payload: object) -> Path:
    """Print ``table`` and write it with ``payload`` to ``results/<name>.json``."""
    print(table)
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"table": table, **payload}, indent=1))
    return path


def window_table(title: str, window: int, rows: list[tuple[str, list[str]]]) -> str:
    """A markdown table of per-run ``rows`` (the run, then one cell per consecutive window of
    ``window`` interactions), under ``title``; a shorter run's row ends in empty cells, so every
    row has the longest run's columns (the column heads name each window's interactions)."""
    n_windows = max(len(cells) for _, cells in rows)
    head = [f"{k * window}-{(k + 1) * window - 1}" for k in range(n_windows)]
    lines = [f"| {run} | " + " | ".join(cells + [""] * (n_windows - len(cells))) + " |"
             for run, cells in rows]
    return "\n".join([f"{title}, windows of {window} interactions", "",
                      "| run | " + " | ".join(head) + " |", "|---|" + "---|" * n_windows, *lines])
