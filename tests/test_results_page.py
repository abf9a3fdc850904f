"""docs/results.md is what `lili results` writes from the committed records, byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_claims import _air_hockey_runs

from lili.cli import main
from lili.experiments.page import (
    DEFAULT_OUT,
    DEFAULT_README,
    DEFAULT_SOURCES,
    QUICKSTART_BEGIN,
    QUICKSTART_END,
    quickstart_table,
    results_markdown,
    with_quickstart_table,
)

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
    assert ("lili reproduce air-hockey --seeds 3 --interactions 200\n"
            "lili reproduce air-hockey --check-only") in text
    assert text.count("No committed records.") == 6  # the other six items have no runs here
    assert (page.parent / "results" / "air-hockey.png").read_bytes()[:8] == PNG_MAGIC
    assert "results page:" in capsys.readouterr().out


def test_committed_readme_quickstart_table_is_regenerated(monkeypatch) -> None:
    monkeypatch.chdir(ROOT)
    committed = (ROOT / DEFAULT_README).read_text(encoding="utf-8")
    table = quickstart_table(DEFAULT_SOURCES)
    assert with_quickstart_table(committed, table) == committed, (
        "README.md's quick-start table is stale: regenerate it with `lili results`")
    assert table.startswith("| algo |") and "| LILI |" in table and "| SAC |" in table


def test_quickstart_block_is_rewritten_in_place_and_checked(tmp_path: Path, capsys) -> None:
    text = f"# R\n\n{QUICKSTART_BEGIN}\nold table\n{QUICKSTART_END}\n\nafter\n"
    assert with_quickstart_table(text, "| new |\n") == (
        f"# R\n\n{QUICKSTART_BEGIN}\n| new |\n{QUICKSTART_END}\n\nafter\n")
    with pytest.raises(ValueError, match="quickstart-table"):
        with_quickstart_table("no markers", "| new |\n")
    # A README without the block: one error, and neither the page nor the README is written.
    readme, page = tmp_path / "README.md", tmp_path / "results.md"
    readme.write_text("no markers\n")
    sources = tmp_path / "sources.yaml"
    sources.write_text("{}\n")
    assert main(["results", "--sources", str(sources), "--out", str(page),
                 "--readme", str(readme)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--readme" in err[0] and "quickstart-table" in err[0], err
    assert readme.read_text() == "no markers\n" and not page.exists()


def test_another_projects_readme_is_left_alone_by_default(tmp_path: Path, monkeypatch) -> None:
    """`lili results` at its default --out rewrites ./README.md only when it holds the block."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "README.md").write_text("# their project\n")
    sources = tmp_path / "sources.yaml"
    sources.write_text("{}\n")
    assert main(["results", "--sources", str(sources)]) == 0
    assert (tmp_path / DEFAULT_OUT).is_file()
    assert (tmp_path / "README.md").read_text() == "# their project\n"
