"""Why the FAILs fail: benchmarks/results/claims_why.yaml explains every FAIL of the committed
records, names only real claims, journal sections and records, and is printed under the claim
tables (the results page, `lili reproduce --check-only --sources`)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from test_claims import _air_hockey_runs

from lili.cli import main
from lili.experiments.claims import check_claim, claims_for, load_evidence, load_sources
from lili.experiments.influence_page import influence_section
from lili.experiments.page import DEFAULT_SOURCES
from lili.experiments.presets import PRESETS
from lili.experiments.why import STATES, WHY_FILE, claim_key, load_why, why_beside

ROOT = Path(__file__).resolve().parents[1]
WHY = ROOT / "benchmarks" / "results" / WHY_FILE
JOURNAL = "journal: ../../docs/journal/2026-11-to-12.md\n"
RANDOM = "Random block rate 18% ± 10"  # FAILs on _air_hockey_runs' records


@pytest.fixture(scope="module")
def committed_results() -> list:
    """Every claim of the results page checked against the committed records, as the page
    checks them (the paper's parts, then the influence suite's goals)."""
    locate = load_sources(ROOT / DEFAULT_SOURCES)
    paper = PRESETS["paper"]
    evidence = load_evidence(paper, locate)
    results = [(part, check_claim(part, claim, evidence)) for part, claim in claims_for(paper)]
    return results + influence_section(locate, evidence)[1]


def test_every_fail_of_the_committed_records_is_explained(committed_results) -> None:
    whys = load_why(WHY)
    fails = {claim_key(r.claim) for _, r in committed_results if r.verdict == "FAIL"}
    missing = sorted(fails - set(whys))
    assert not missing, f"FAILs with no entry in {WHY_FILE} (add one, even 'not yet " \
        f"explained'): {missing}"
    stale = sorted(set(whys) - fails)
    assert not stale, f"entries of {WHY_FILE} whose claims no longer FAIL: {stale}"


def test_committed_entries_name_real_sections_and_records_and_type_no_numbers() -> None:
    whys = load_why(WHY)  # checks every heading and path (the errors: the test below)
    journal = (ROOT / "docs" / "journal" / "2026-11-to-12.md").read_text(encoding="utf-8")
    for key, why in whys.items():
        assert why.state in STATES and why.journal_file.endswith("docs/journal/2026-11-to-12.md")
        for heading in why.journal:
            assert re.search(rf"^#+ {re.escape(heading)}$", journal, re.MULTILINE), heading
        for record in why.records:
            assert Path(record).exists(), (key, record)
        # Results are generated, not typed: no percentage or two-decimal number in the words.
        for text in (why.finding, why.next):
            assert not re.search(r"\d\s*%|\d\.\d\d", text), (key, text)


def _why_file(folder: Path, claims: str, journal: str = JOURNAL) -> Path:
    path = folder / WHY_FILE
    path.write_text(journal + "claims:\n" + claims, encoding="utf-8")
    return path


ENTRY = ("    {state: explained, finding: Random wanders in the middle., journal: [Preface (the "
         "file's original introduction)], command: python benchmarks/air_hockey_scripted.py}\n")


@pytest.mark.parametrize("claims, message", [
    ("  nowhere: {}\n", "unknown preset 'nowhere'; allowed: point-mass"),
    ("  air-hockey:\n    Random beats everyone:\n" + ENTRY[4:].replace("{", "      {", 1),
     "air-hockey: no claim 'Random beats everyone'; allowed: "),
    (f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY.replace("explained", "obvious"),
     "state 'obvious' is invalid; allowed: explained, partly explained"),
    (f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY.replace("Preface", "Nowhere"),
     "journal section \"Nowhere (the file's original introduction)\" is not a heading"),
    (f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY.replace("journal: [Preface (the file's "
                                                         "original introduction)]",
                                                         "records: [runs/missing]"),
     "runs/missing do not exist"),
    (f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY.replace("state: explained",
                                                         "state: partly explained"),
     "needs 'next': the experiment that would tell"),
    (f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY.replace("finding: Random wanders in the "
                                                         "middle., ", ""),
     "finding is missing"),
    (f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY.replace("state: explained",
                                                         "state: explained, next: [1]"),
     "next [1] is invalid; allowed: the experiment that would tell"),
])
def test_a_bad_entry_is_one_clear_error(tmp_path: Path, claims: str, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)) as err:
        load_why(_why_file(tmp_path, claims, JOURNAL.replace("../../", str(ROOT) + "/")))
    assert str(tmp_path / WHY_FILE) in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("text, message", [
    (b"claims:\n  air-hockey: [1\n", "is not valid YAML: line 3, column 1"),
    (b"claims: {}\n# \xff\n", "is not UTF-8 text"),
    (f"claims:\n  air-hockey:\n    {RANDOM}: {{}}\n    {RANDOM}: {{}}\n".encode(),
     "is given twice"),
    (b"journal: journal.md\nclaims: {}\n", "journal.md cannot be read"),
])
def test_an_unreadable_file_is_one_clear_error(tmp_path: Path, text: bytes, message: str) -> None:
    (tmp_path / "journal.md").write_bytes(b"# \xff\n")  # not UTF-8
    (tmp_path / WHY_FILE).write_bytes(text)
    with pytest.raises(ValueError, match=re.escape(message)) as err:
        load_why(tmp_path / WHY_FILE)
    assert str(tmp_path / WHY_FILE) in str(err.value) and "\n" not in str(err.value)


def _check_only(tmp_path: Path, capsys) -> tuple[int, str, str]:
    sources = tmp_path / "sources.yaml"
    sources.write_text("air-hockey:\n  - path: runs/air-hockey\n")
    code = main(["reproduce", "air-hockey", "--check-only", "--sources", str(sources)])
    out, err = capsys.readouterr()
    return code, out, err


def test_check_only_prints_each_fail_with_its_explanation_or_none(tmp_path: Path,
                                                                  capsys) -> None:
    _air_hockey_runs(tmp_path / "runs", seeds=5)
    code, out, _ = _check_only(tmp_path, capsys)  # no explanations' file: no list
    assert code == 0 and f"| {RANDOM} |" in out and "Why the FAILs fail" not in out

    journal = JOURNAL.replace("../../", str(ROOT) + "/")
    _why_file(tmp_path, f"  air-hockey:\n    {RANDOM}:\n  " + ENTRY, journal)
    code, out, _ = _check_only(tmp_path, capsys)
    assert code == 0 and out.index("Why the FAILs fail") > out.index(f"| {RANDOM} |")
    assert (f"- **{RANDOM}**: Explained. Random wanders in the middle. Measured by: "
            "`python benchmarks/air_hockey_scripted.py`; journal "
            f"({ROOT.as_posix()}/docs/journal/2026-11-to-12.md): \"Preface (the file's "
            "original introduction)\".") in out
    assert out.count("\n- **") == 1  # the other claims PASS here: no line for them

    _why_file(tmp_path, "  air-hockey: {}\n", journal)  # the entry deleted: still listed
    code, out, _ = _check_only(tmp_path, capsys)
    assert f"- **{RANDOM}**: No explanation recorded (no entry in `{WHY_FILE}`)." in out


def test_check_only_refuses_a_bad_explanations_file_before_checking(tmp_path: Path,
                                                                     capsys) -> None:
    _air_hockey_runs(tmp_path / "runs", seeds=3)
    _why_file(tmp_path, "  air-hockey:\n    LILI wins:\n  " + ENTRY, "")
    code, out, err = _check_only(tmp_path, capsys)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "no claim 'LILI wins'" in err and str(tmp_path / WHY_FILE) in err


def test_the_explanations_sit_beside_the_sources_file() -> None:
    assert why_beside(DEFAULT_SOURCES) == Path("benchmarks/results") / WHY_FILE
    assert (ROOT / why_beside(DEFAULT_SOURCES)).is_file()
