"""docs/results.md is what `lili results` writes from the committed records, byte for byte."""

from __future__ import annotations

from pathlib import Path

from test_claims import _air_hockey_runs

from lili.cli import main
from lili.experiments.page import DEFAULT_OUT, DEFAULT_SOURCES, results_markdown

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_committed_results_page_is_regenerated_byte_for_byte(monkeypatch) -> None:
    monkeypatch.chdir(ROOT)  # the page names the records by their paths from the repo root
    committed = (ROOT / DEFAULT_OUT).read_text(encoding="utf-8")
    assert results_markdown(DEFAULT_SOURCES) == committed, (
        "docs/results.md is stale: regenerate it with `lili results` from the repo root")
    for link in (line for line in committed.splitlines() if line.startswith("![")):
        assert (ROOT / "docs" / link.split("](")[1].rstrip(")")).is_file(), link


def test_lili_results_writes_the_page_and_a_figure_per_item(tmp_path: Path, capsys) -> None:
    _air_hockey_runs(tmp_path / "runs", seeds=3)
    sources = tmp_path / "sources.yaml"
    sources.write_text("air-hockey:\n  - path: runs/air-hockey\n")
    page = tmp_path / "site" / "results.md"
    assert main(["results", "--sources", str(sources), "--out", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert "## Air hockey" in text and "![Air hockey](results/air-hockey.png)" in text
    assert "| LILI | 1.21 [1.20, 1.22] | 1.21 ± 0.01 | 90.0% [90.0, 90.0] |" in text
    # The setting and the command come from the runs' config.yaml (200 interactions here).
    assert "| 3 | 200 | `interactions=200` |" in text
    assert ("lili reproduce air-hockey --interactions 200\n"
            "lili reproduce air-hockey --check-only") in text
    assert text.count("No committed records.") == 6  # the other six items have no runs here
    assert (page.parent / "results" / "air-hockey.png").read_bytes()[:8] == PNG_MAGIC
    assert "results page:" in capsys.readouterr().out
