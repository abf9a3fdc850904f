"""Where the benchmark scripts write their JSON, and the check of a ``--name`` for it."""

from __future__ import annotations

import argparse
import glob
import json
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


def write_result(name: str, table: str, **payload: object) -> Path:
    """Print ``table`` and write it with ``payload`` to ``results/<name>.json``."""
    print(table)
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"table": table, **payload}, indent=1))
    return path


def window_table(title: str, window: int, n_windows: int, lines: list[str]) -> str:
    """A markdown table of per-run rows ``lines`` over consecutive windows of ``window``
    interactions, under ``title`` (the column heads name each window's interactions)."""
    head = [f"{k * window}-{(k + 1) * window - 1}" for k in range(n_windows)]
    return "\n".join([f"{title}, windows of {window} interactions", "",
                      "| run | " + " | ".join(head) + " |", "|---|" + "---|" * n_windows, *lines])
