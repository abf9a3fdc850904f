"""The influence suite on the results page: gap and held shares, issue 36's goals as claims
(a gap rule, and a goal that does not apply where its condition fails), and the section's
table, on synthetic run folders written as `lili train` writes them."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_claims import write_run

from lili.envs.influence import SUITE
from lili.experiments.claims import check_claims, claims_markdown, load_evidence, out_layout
from lili.experiments.influence_page import influence_section
from lili.experiments.plan import plan
from lili.experiments.presets import PRESETS, get_preset
from lili.report.files import load_run
from lili.report.stats import gap_share, held_share

SWITCH = "lili/InfluenceSwitch-v0"
# Final return per algo (seed k adds 0.01 k) and the share of interactions, from the first,
# at Switch's left mode (id 0); the rest are at the middle mode (id 1), which the scripted
# influencer holds. 200 interactions: the last 10% are the last 20.
RUNS = {"sac": (-1.75, 0.5), "lili-no-influence": (-0.86, 0.5), "lili": (-0.2, 0.5),
        "oracle": (-0.12, 0.5)}


def _switch_runs(out: Path, returns: dict[str, tuple[float, float]]) -> None:
    for spec in plan(get_preset("influence"), out, seeds=3, envs=(SWITCH,),
                     algos=tuple(returns)):
        ret, left = returns[spec.algo]
        write_run(spec, ret + 0.01 * spec.seed, 0.0, left)


def test_gap_share_and_held_share(tmp_path: Path) -> None:
    assert gap_share(-1.0, -2.0, 0.0) == 0.5
    assert gap_share(0.5, -2.0, 0.0) == 1.25           # beyond the end: more than the gap
    assert gap_share(-1.0, -2.0, -2.0) is None         # no gap
    assert gap_share(None, -2.0, 0.0) is None
    _switch_runs(tmp_path, {"lili": (-0.2, 0.95)})
    run = load_run(next(tmp_path.rglob("seed_0")))
    # 95% of 200 at the left mode: the first 190; of the last 20, the last 10 are middle.
    assert held_share(run, (1,)) == 0.5
    assert held_share(run, (0, 1)) == 1.0
    assert held_share(run, (2,)) == 0.0


def test_goals_pass_where_the_oracle_reaches_the_influencer(tmp_path: Path) -> None:
    _switch_runs(tmp_path, RUNS)
    got = {r.claim.statement: r for _, r in check_claims(PRESETS["influence"],
                                                         out_layout(tmp_path))}
    reach = got[f"{SWITCH}: Oracle within 0.1 of the scripted influencer (-0.050)"]
    assert reach.verdict == "PASS" and reach.ours.startswith("-0.11 [")
    share = got[f"{SWITCH}: LILI closes >= 0.8 of the SAC-to-Oracle gap"]
    # (-0.19 - -1.74) / (-0.11 - -1.74) = 0.951; the interval is over LILI's seeds (-0.20 to
    # -0.18), SAC and the Oracle held at their IQMs.
    assert share.verdict == "PASS" and share.ours.startswith("0.95 [0.94, 0.96] of the gap")
    assert "(3 vs 3 vs 3 seeds)" in share.ours
    # The other envs have no runs here: said so, never PASS.
    others = [r for s, r in got.items() if not s.startswith(SWITCH)]
    assert len(others) == 4 and {r.verdict for r in others} == {"too few seeds"}


def test_the_gap_goal_is_not_applicable_where_the_oracle_falls_short(tmp_path: Path) -> None:
    _switch_runs(tmp_path, {**RUNS, "oracle": (-0.3, 0.5), "lili": (-1.0, 0.5)})
    got = {r.claim.statement: r for _, r in check_claims(PRESETS["influence"],
                                                         out_layout(tmp_path))}
    assert got[f"{SWITCH}: Oracle within 0.1 of the scripted influencer (-0.050)"].verdict \
        == "FAIL"
    share = got[f"{SWITCH}: LILI closes >= 0.8 of the SAC-to-Oracle gap"]
    assert share.verdict == "not applicable"
    assert share.ours.startswith("0.52 [") and share.ours.endswith(": FAIL")  # still shown
    assert "1 FAIL, 4 too few seeds, 1 not applicable, of 6 claims." in claims_markdown(
        check_claims(PRESETS["influence"], out_layout(tmp_path)))


def test_a_folder_of_several_envs_is_read_one_env_at_a_time(tmp_path: Path) -> None:
    _switch_runs(tmp_path, RUNS)
    with pytest.raises(ValueError, match="folder 'influence' holds runs of 3 envs"):
        load_evidence(PRESETS["influence"], out_layout(tmp_path))
    switch = PRESETS["influence"].for_env(SWITCH)
    assert set(load_evidence(switch, out_layout(tmp_path))) == {("influence", a) for a in RUNS}
    with pytest.raises(ValueError, match="runs no env 'lili/PointMass-v0'"):
        PRESETS["influence"].for_env("lili/PointMass-v0")


def test_the_section_tables_every_suite_env(tmp_path: Path) -> None:
    _switch_runs(tmp_path, RUNS)
    text, results = influence_section(out_layout(tmp_path), {})
    assert [line for line in text.splitlines() if line.startswith("### ")] == \
        [f"### {env}" for env in SUITE]
    switch = text[text.index(f"### {SWITCH}"):]
    assert "| scripted: influencer | -0.050 (derived) | — | — | 1.04 | 1.00 | — | — |" in switch
    # Held: the last 20 of each seed are all at the middle mode.
    assert ("| LILI | -0.190 [-0.200, -0.180] | 3 | 200 | 0.95 | 0.92 | 100% (100 / 100 / 100) "
            "| `interactions=200` |") in switch
    assert ("lili reproduce influence --algos sac lili-no-influence lili oracle --envs "
            "lili/InfluenceSwitch-v0 --interactions 200") in switch
    assert text.count("No committed records of learned agents.") == 3
    assert len(results) == 2 * len(SUITE)
    assert "**2 of the 8 goal checks PASS, 6 too few seeds.**" in text


FLEE = "lili/InfluenceFlee-v0"


def test_contrib_variants_are_rows_below_the_preset_and_stay_out_of_the_goals(
        tmp_path: Path) -> None:
    # LILI closes (-2.0 - -2.5) / (-0.1 - -2.5) = 0.21 of the gap: the goal FAILs. The variant
    # would PASS it, and so would the contrib folder's own LILI (the preset's baseline there).
    core = {"sac": (-2.5, 0.5), "lili": (-2.0, 0.5), "oracle": (-0.1, 0.5)}
    for spec in plan(get_preset("influence"), tmp_path, seeds=3, envs=(FLEE,),
                     algos=tuple(core)):
        write_run(spec, core[spec.algo][0] + 0.01 * spec.seed, 0.0, 0.5)
    before, core_results = influence_section(out_layout(tmp_path), {})
    assert "contrib" not in before[before.index(f"### {FLEE}"):]
    for spec in plan(get_preset("contrib"), tmp_path, seeds=3, envs=(FLEE,),
                     algos=("lili", "lili-prediction-critic")):
        write_run(spec, -0.2 + 0.01 * spec.seed, 0.0, 0.5)
    text, results = influence_section(out_layout(tmp_path), {})
    flee = text[text.index(f"### {FLEE}"):]
    table = flee[flee.index("| policy"):flee.index("\n\n", flee.index("| policy"))]
    labels = [line.split(" | ")[0][2:] for line in table.splitlines()[2:]]
    assert labels[-3:] == ["LILI", "Oracle", "LILI (prediction critic), contrib"]
    assert labels.count("LILI") == 1  # the contrib folder's LILI is no row of its own
    # (-0.19 - -2.49) / (-0.09 - -2.49) = 0.96 of the gap to the Oracle; same columns as LILI's.
    assert ("| LILI (prediction critic), contrib | -0.190 [-0.200, -0.180] | 3 | 200 | 0.96 | "
            "0.92 | 0% (0 / 0 / 0) | `interactions=200` |") in flee
    assert "Rows marked contrib are variants of LILI kept out of the core" in flee
    assert ("`lili reproduce contrib --algos lili-prediction-critic --envs "
            "lili/InfluenceFlee-v0 --interactions 200`") in flee
    # The goals read the core LILI only: the same verdicts and numbers as without the variant.
    assert [(r.claim.statement, r.verdict, r.ours) for _, r in results] == \
        [(r.claim.statement, r.verdict, r.ours) for _, r in core_results]
    gap = next(r for _, r in results if r.claim.statement == f"{FLEE}: LILI closes >= 0.8 of "
               "the SAC-to-Oracle gap")
    assert gap.verdict == "FAIL" and gap.ours.startswith("0.21 [")
    assert "Rows marked contrib" not in text[:text.index(f"### {FLEE}")]  # Drift, Switch: none
