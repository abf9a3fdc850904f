"""Why a claim FAILs: the explanations kept beside a sources file (``claims_why.yaml`` next to
``benchmarks/results/claims_sources.yaml``), printed under each claim table that has a FAIL.

A FAIL of the committed records is a finding, not a bug to hide; what the reader needs beside
it is the experiment that says why. Each entry names a claim of
:data:`lili.experiments.claims.CLAIMS` (or an influence goal,
:func:`~lili.experiments.claims.influence_goals`) by its preset and statement, and gives

- ``state``: one of :data:`STATES` (an entry may honestly say the FAIL is not yet explained),
- ``finding``: the explanation in words (no typed learning numbers: the page's tables hold
  them, computed from the records),
- ``journal``: headings of the lab journal's sections that measured it, and/or ``records``:
  files or folders (relative to the file) of the experiment,
- ``command``: the command of that experiment,
- ``next``: the experiment that would tell what is still open (needed unless ``explained``).

:func:`load_why` checks every key and path before anything is printed (one error line naming
the file and the bad entry); :func:`why_markdown` lists each FAIL of a claim table with its
entry, or says "no explanation recorded" (a FAIL is never left without a line).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from lili.config import read_yaml
from lili.experiments.claims import CLAIMS, Claim, ClaimResult, influence_goals
from lili.experiments.presets import Preset

__all__ = ["WHY_FILE", "STATES", "Why", "load_why", "why_beside", "why_markdown", "claim_key"]

WHY_FILE = "claims_why.yaml"
"""The explanations' file name, beside the sources file whose records they explain."""
STATES = ("explained", "partly explained", "not yet explained")
_FIELDS = {"state", "finding", "journal", "records", "command", "next"}


@dataclass(frozen=True)
class Why:
    """One FAIL's explanation (the module doc); ``journal_file`` is the journal's path as the
    reader names it, ``records`` the experiment's paths (both as given, joined to the file's
    folder)."""

    state: str
    finding: str
    command: str
    journal: tuple[str, ...] = ()
    journal_file: str = ""
    records: tuple[str, ...] = ()
    next: str = ""


Whys = dict[tuple[str, str], Why]
"""(preset, claim statement) -> its explanation."""


def _known() -> dict[str, tuple[Claim, ...]]:
    """The claims an entry may name, by preset: :data:`CLAIMS`, with the ``influence`` goals on
    every env of the suite (the results page checks them on Point Mass too, against the Point
    Mass runs)."""
    from lili.envs.influence import SUITE

    known = dict(CLAIMS)
    goals = [c for env in SUITE for c in influence_goals(env)]
    known["influence"] = tuple(dict.fromkeys([*known.get("influence", ()), *goals]))
    return known


_KNOWN = _known()
_OWNER = {claim: name for name, claims in _KNOWN.items() for claim in claims}


def claim_key(claim: Claim) -> tuple[str, str]:
    """(the preset that states ``claim``, its statement): the key of its explanation."""
    return _OWNER.get(claim, ""), claim.statement


def why_beside(sources: str | Path) -> Path:
    """The explanations' file of the records a sources file names (it may not exist)."""
    return Path(sources).parent / WHY_FILE


def _headings(path: Path, journal: Path) -> set[str]:
    """The headings of ``journal`` (named by the explanations file ``path``)."""
    try:
        text = journal.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: journal {journal} cannot be read ({e}); allowed: a UTF-8 "
                         "markdown file") from None
    return {m.group(1).strip() for m in re.finditer(r"^#+ (.+)$", text, re.MULTILINE)}


def _strings(value: object) -> tuple[str, ...] | None:
    """A string or a list of strings as a tuple; None for anything else."""
    if isinstance(value, str):
        return (value,)
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return tuple(value)
    return None


def _entry(path: Path, where: str, entry: object, headings: set[str] | None,
           journal_file: str) -> Why:
    def bad(what: str) -> ValueError:
        return ValueError(f"{path}: {where}: {what}")

    allowed = ("allowed: {state, finding, command, journal: [HEADING], records: [PATH], "
               "next}")
    if not isinstance(entry, dict) or set(entry) - _FIELDS:
        raise bad(f"entry {entry!r} is invalid; {allowed}")
    if entry.get("state") not in STATES:
        raise bad(f"state {entry.get('state')!r} is invalid; allowed: {', '.join(STATES)}")
    for name in ("finding", "command"):
        if not isinstance(entry.get(name), str) or not entry[name].strip():
            raise bad(f"{name} is missing; {allowed}")
    journal = _strings(entry.get("journal", []))
    records = _strings(entry.get("records", []))
    if journal is None or records is None:
        raise bad(f"journal and records must be a string or a list of strings; {allowed}")
    if not journal and not records:
        raise bad("names no experiment; allowed: a journal heading and/or records")
    if journal and headings is None:
        raise bad("names journal sections but the file names no journal; allowed: a top-level "
                  "'journal: PATH'")
    for heading in journal:
        if heading not in headings:
            raise bad(f"journal section {heading!r} is not a heading of {journal_file}")
    for record in records:
        if not (path.parent / record).exists():
            raise bad(f"records {path.parent / record} do not exist")
    nxt = entry.get("next", "")
    if not isinstance(nxt, str):
        raise bad(f"next {nxt!r} is invalid; allowed: the experiment that would tell, in words")
    if entry["state"] != "explained" and not nxt.strip():
        raise bad(f"state {entry['state']!r} needs 'next': the experiment that would tell")
    return Why(entry["state"], " ".join(entry["finding"].split()), entry["command"].strip(),
               journal, journal_file, tuple((path.parent / r).as_posix() for r in records),
               " ".join(nxt.split()))


def load_why(path: str | Path) -> Whys:
    """The explanations in ``path``::

        journal: ../../docs/journal/2026-11-to-12.md   # relative to the file
        claims:
          air-hockey:                                   # a preset of CLAIMS
            "Random block rate 18% ± 10":               # one of its claims' statements
              state: explained
              finding: why, in words
              journal: [a heading of the journal]
              records: [runs/s9/air-hockey]
              command: python benchmarks/air_hockey_scripted.py

    ValueError naming the file and the bad entry (an unknown preset or claim, a heading the
    journal lacks, a path that does not exist, a missing field).
    """
    path = Path(path)
    data = read_yaml(path, "explanations file")  # one line for non-UTF-8 or malformed YAML
    if not isinstance(data, dict) or set(data) - {"journal", "claims"} \
            or not isinstance(data.get("claims"), dict):
        raise ValueError(f"{path}: expected a mapping {{journal: PATH, claims: {{PRESET: "
                         "{STATEMENT: entry}}}")
    headings, journal_file = None, ""
    if data.get("journal") is not None:
        journal = path.parent / str(data["journal"])
        if not journal.is_file():
            raise ValueError(f"{path}: journal {journal} is not a file")
        headings = _headings(path, journal)
        journal_file = os.path.normpath(journal).replace(os.sep, "/")
    whys: Whys = {}
    for preset, entries in data["claims"].items():
        if preset not in _KNOWN:
            raise ValueError(f"{path}: unknown preset {preset!r}; allowed: "
                             f"{', '.join(_KNOWN)}")
        statements = {c.statement for c in _KNOWN[preset]}
        if not isinstance(entries, dict):
            raise ValueError(f"{path}: {preset}: expected a mapping of claim statements to "
                             "entries")
        for statement, entry in entries.items():
            if statement not in statements:
                raise ValueError(f"{path}: {preset}: no claim {statement!r}; allowed: "
                                 + "; ".join(sorted(statements)))
            whys[(preset, statement)] = _entry(path, f"{preset}: {statement}", entry,
                                               headings, journal_file)
    return whys


def _line(why: Why) -> str:
    text = f"{why.state[0].upper()}{why.state[1:]}. {why.finding}"
    if why.next:
        text += f" The experiment that would tell: {why.next}"
    where = [f"`{why.command}`"]
    if why.journal:
        where.append(f"journal ({why.journal_file}): "
                     + "; ".join(f"\"{h}\"" for h in why.journal))
    if why.records:
        where.append("records: " + ", ".join(f"`{r}`" for r in why.records))
    return f"{text} Measured by: {'; '.join(where)}."


def why_markdown(results: Sequence[tuple[Preset, ClaimResult]],
                 whys: Mapping[tuple[str, str], Why] | None, with_part: bool = False) -> str:
    """"Why the FAILs fail": a bullet per FAIL in ``results`` with its explanation, or "no
    explanation recorded"; empty where nothing FAILs or there is no explanations' file
    (``whys`` None). ``with_part``: each bullet names its preset (a table of several)."""
    if whys is None:
        return ""
    lines = []
    for part, result in results:
        if result.verdict != "FAIL":
            continue
        key = claim_key(result.claim)
        why = whys.get(key)
        name = f"{key[0] or part.name}: " if with_part else ""
        text = (_line(why) if why is not None
                else f"No explanation recorded (no entry in `{WHY_FILE}`).")
        lines.append(f"- **{name}{result.claim.statement}**: {text}")
    if not lines:
        return ""
    return "**Why the FAILs fail**\n\n" + "\n".join(lines) + "\n"
