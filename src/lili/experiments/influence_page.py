"""The results page's influence-suite section (issue 36): per env of
:data:`lili.envs.influence.SUITE`, its scripted policies' derived returns beside the learned
agents' final returns, the share of the gap each closes from SAC to the Oracle and from SAC to
the scripted influencer, and how often the partner sits where the influencer holds it; then
issue 36's goals on that env as claims (:func:`lili.experiments.claims.influence_goals`).

The scripted returns are the ones each env's docstring derives (``SUITE``'s second entry, held
there and nowhere else; ``benchmarks/influence.py`` measures them by simulation), so the page
runs no simulation. The learned rows are the ``influence`` preset's runs on the env, or, for an
env the paper's presets run (Point Mass), that preset's runs, the ones its section shows; below
them, the ``contrib`` preset's variants of LILI (:mod:`lili.contrib`) measured on the env,
labelled as such. The goals are about the core LILI: the variants' rows never enter them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from lili.agents.registry import CONTRIB_ALGOS
from lili.envs.influence import HELD, HELD_WHERE, POLICIES, SUITE
from lili.experiments.claims import (
    GOAL_GAP,
    GOAL_ORACLE_MARGIN,
    VERDICTS,
    Evidence,
    Locate,
    check_claim,
    claims_markdown,
    influence_goals,
    load_evidence,
)
from lili.experiments.presets import PRESETS, Preset
from lili.experiments.provenance import (
    interactions_text,
    reproduce_commands,
    setting,
    sources_markdown,
)
from lili.experiments.why import Whys, why_markdown
from lili.report.files import Run
from lili.report.stats import final_performance, gap_share, held_share, iqm, iqm_ci
from lili.report.style import algo_label
from lili.report.tables import fmt_interval

__all__ = ["LEARNED", "VARIANTS", "influence_part", "influence_rows", "influence_section"]

LEARNED = ("sac", "lili-no-influence", "lili", "oracle", "oracle-last")
"""The learned rows of each env's table, in order, where the records hold them."""
VARIANTS = "contrib"
"""The preset whose variants of LILI (:data:`lili.agents.registry.CONTRIB_ALGOS`) follow them."""
CONTRIB_NOTE = ("Rows marked contrib are variants of LILI kept out of the core (`lili.contrib`; "
                "README.md, \"Contrib variants\"), from the `contrib` preset's records; the "
                "goals below are about the core LILI, not them. The lab journal "
                "(docs/journal/2026-11-to-12.md) says how each was measured and why it is not "
                "in the core.")


def influence_part(env: str) -> Preset:
    """The preset part whose runs are ``env``'s learned rows: the ``influence`` preset's groups
    on it, else the first of the paper's parts that runs it (Point Mass: ``point-mass``)."""
    candidates = [PRESETS["influence"], *(PRESETS[n] for n in PRESETS["paper"].includes)]
    for part in candidates:
        if env in part.envs:
            return part.for_env(env)
    raise ValueError(f"no preset runs the influence-suite env {env!r}; allowed: "
                     f"{', '.join(e for p in candidates for e in p.envs)}")


def _learned(algo: str, runs: Sequence[Run], held: tuple[int, ...] | None,
             part: Preset) -> dict[str, Any]:
    finals = [final_performance(r) for r in runs]
    shares = [] if held is None else [held_share(r, held) for r in runs]
    return {"policy": algo, "scripted": False, "return": iqm_ci(finals), "runs": list(runs),
            "held": shares if shares and None not in shares else None, "part": part,
            "contrib": algo in CONTRIB_ALGOS}


def influence_rows(env: str, part: Preset, evidence: Evidence,
                   variants: tuple[Preset, Evidence] | None = None) -> list[dict[str, Any]]:
    """The rows of ``env``'s table: the scripted policies (``return``: (derived, None, None)),
    then each of :data:`LEARNED` that ``evidence`` holds, then each variant of
    :data:`~lili.agents.registry.CONTRIB_ALGOS` that ``variants`` (the :data:`VARIANTS`
    preset's part on ``env`` and its evidence) holds (``return``: IQM and its interval over
    seeds; ``held``: each seed's share, None where the env names no held strategy; ``part``:
    the preset part of its runs; ``contrib``: whether it is a variant), each with
    ``gap_oracle`` and ``gap_influencer``, the shares of the gaps from SAC's IQM."""
    known = SUITE[env][1]
    rows: list[dict[str, Any]] = [{"policy": name, "scripted": True,
                                   "return": (known[name], None, None)}
                                  for name in POLICIES if name in known]
    learned = [(part, evidence, LEARNED)]
    if variants is not None:
        learned.append((*variants, CONTRIB_ALGOS))
    for owner, runs_of, algos in learned:
        group = owner.groups[0]
        for algo in algos:
            runs = runs_of.get((group.folder, algo), []) if algo in group.algos else []
            if runs:
                rows.append(_learned(algo, runs, HELD.get(env), owner))
    by_policy = {r["policy"]: r["return"][0] for r in rows}
    for row in rows:
        row["gap_oracle"] = gap_share(row["return"][0], by_policy.get("sac"),
                                      by_policy.get("oracle"))
        row["gap_influencer"] = gap_share(row["return"][0], by_policy.get("sac"),
                                          known.get("influencer"))
    return rows


def _share(value: float | None) -> str:
    return "—" if value is None else f"{value:.2f}"


def _held(shares: list[float] | None) -> str:
    if not shares:
        return "—"
    text = f"{100 * iqm(shares):.0f}%"
    if len(shares) > 1:
        text += " (" + " / ".join(f"{100 * s:.0f}" for s in shares) + ")"
    return text


def _table(rows: list[dict[str, Any]]) -> str:
    lines = ["| policy | return IQM [95% CI] | seeds | interactions | gap closed, SAC to "
             "Oracle | gap closed, SAC to influencer | held (per seed) | setting |",
             "|---|---:|---:|---:|---:|---:|---:|---|"]
    for row in rows:
        if row["scripted"]:
            cells = [f"scripted: {row['policy'].replace('-', ' ')}",
                     f"{row['return'][0]:.3f} (derived)", "—", "—"]
            held, how = "—", "—"
        else:
            runs, owner = row["runs"], row["part"]
            label = algo_label(row["policy"]) + (", contrib" if row["contrib"] else "")
            cells = [label, fmt_interval(*row["return"], spec=".3f"), str(len(runs)),
                     interactions_text(runs)]
            held, how = _held(row["held"]), setting(runs, owner.groups[0], owner)
        cells += [_share(row["gap_oracle"]), _share(row["gap_influencer"]), held, how]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _env_section(env: str, part: Preset, evidence: Evidence,
                 variants: tuple[Preset, Evidence] | None,
                 whys: Whys | None) -> tuple[str, list]:
    rows = influence_rows(env, part, evidence, variants)
    results = [(part, check_claim(part, claim, evidence)) for claim in influence_goals(env)]
    held = HELD.get(env)
    held_text = (f"Held: the partner at {HELD_WHERE[env]} (strategy id "
                 f"{' or '.join(str(i) for i in held)}), where the scripted influencer holds it."
                 if held is not None else "Held: not defined here (`lili.envs.influence.HELD` "
                 "names no strategy the scripted influencer holds this partner at).")
    learned = ("" if any(not r["scripted"] for r in rows)
               else "No committed records of learned agents.\n\n")
    if any(r.get("contrib") for r in rows):
        learned += CONTRIB_NOTE + "\n\n"
    commands = [] if variants is None else reproduce_commands(*variants)
    if part.name in PRESETS["paper"].includes:  # the paper's runs: that section says how
        reproduce = f" Records and `lili reproduce` commands: the {part.title} section above."
    else:
        reproduce, commands = "", reproduce_commands(part, evidence) + commands
    if commands:
        reproduce += " Reproduce: " + "; ".join(f"`{c}`" for c in commands) + "."
    text = (f"### {env}\n\n{_table(rows)}\n{learned}{held_text}{reproduce}\n\n"
            f"{claims_markdown(results, with_part=False, rules=False)}")
    why = why_markdown(results, whys)
    return text + (f"\n{why}" if why else ""), results


def influence_section(locate: Locate, paper_evidence: Evidence,
                      whys: Whys | None = None) -> tuple[str, list]:
    """The section's markdown and its claim results: one table and the goals per env of the
    suite. ``locate`` finds the ``influence`` preset's records; ``paper_evidence`` holds the
    paper's parts' runs (Point Mass's rows are that section's runs, not read twice);
    ``whys``: the explanations of FAILs listed under each env's goals (none: no list)."""
    paper, contrib = PRESETS["paper"].includes, PRESETS[VARIANTS]
    sections, results = [], []
    for env in SUITE:
        part = influence_part(env)
        evidence = paper_evidence if part.name in paper else load_evidence(part, locate)
        variants = None
        if env in contrib.envs:
            on_env = contrib.for_env(env)
            found = load_evidence(on_env, locate)  # LILI's row: the core's records
            variants = (on_env, {k: v for k, v in found.items() if k[1] in CONTRIB_ALGOS})
        text, mine = _env_section(env, part, evidence, variants, whys)
        sections.append(text)
        results += mine
    influence = PRESETS["influence"]
    counts = ", ".join(f"{sum(r.verdict == v for _, r in results)} {v}" for v in VERDICTS[1:]
                       if any(r.verdict == v for _, r in results))
    passed = sum(r.verdict == "PASS" for _, r in results)
    evidence_list = "".join(t for t in (sources_markdown(influence, locate),
                                        sources_markdown(contrib, locate)) if t.strip())
    head = (
        "## Influence suite (not in the paper; issue 36)\n\n"
        "Envs whose best greedy and best influencing returns are known by construction "
        "(`lili.envs.influence`, docs/influence.md). Scripted rows: the long-run return per "
        "interaction that each env's docstring derives for its no-information, greedy and "
        "influencing policies (told the partner's strategy; `benchmarks/influence.py` measures "
        "them by simulation: `benchmarks/results/influence*.md`). Learned rows: the final "
        "return over seeds as elsewhere on this page (the `influence` preset's runs; Point "
        "Mass: the Point Mass section's), then, marked contrib, the `contrib` preset's "
        "variants of LILI measured on the env. "
        "Gap closed = (R - R_SAC) / (R_end - R_SAC), on the IQMs, with R_end the Oracle's IQM "
        "or the scripted influencer's derived return; held = each seed's share of its last 10% "
        "of interactions in which the partner was at a strategy the scripted influencer holds "
        "it at, IQM over seeds (per seed in brackets). Goals (issue 36): on every env where "
        f"the Oracle comes within {GOAL_ORACLE_MARGIN:g} of the scripted influencer, LILI "
        f"closes at least {GOAL_GAP:g} of the gap from SAC to the Oracle, at 3 seeds; checked "
        "below (`lili.experiments.claims.influence_goals`), a goal whose condition "
        f"fails is reported as not applicable. **{passed} of the {len(results)} goal checks "
        f"PASS{', ' if counts else ''}{counts}.**\n\n"
        f"**Evidence** (committed records)\n\n{evidence_list}\n"
    )
    return head + "\n".join(sections), results
