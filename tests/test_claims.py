"""The interval statistics (IQM, probability of improvement) against hand-computed cases, and
the paper's claims checked on synthetic run folders written as `lili train` writes them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from lili.cli import main
from lili.experiments.claims import CLAIMS, check_claims, load_sources, out_layout
from lili.experiments.plan import plan
from lili.experiments.presets import PRESETS, get_preset
from lili.report.stats import (
    iqm,
    iqm_ci,
    probability_of_improvement,
    probability_of_improvement_ci,
)
from lili.runs import metric_columns

# ---------------------------------------------------------------------------- statistics


def test_iqm_by_hand() -> None:
    assert iqm([1, 2, 3, 4, 100]) == 3.0          # one value cut from each end: (2 + 3 + 4) / 3
    assert iqm(range(1, 9)) == 4.5                 # two from each end: (3 + 4 + 5 + 6) / 4
    assert iqm([1.0, 2.0, 6.0]) == 3.0             # 3 seeds: nothing cut, the mean
    with pytest.raises(ValueError, match="allowed: one or more numbers"):
        iqm([])


@pytest.mark.parametrize("x, y, expected", [
    ([4, 5, 6], [1, 2, 3], 1.0),                   # separated
    ([1, 2, 3], [1, 2, 3], 0.5),                   # identical: ties count 1/2
    ([1, 2, 3], [4, 5, 6], 0.0),                   # reversed
    ([1, 3], [2, 2], 0.5),                         # 1 < 2 twice, 3 > 2 twice
])
def test_probability_of_improvement_by_hand(x, y, expected) -> None:
    assert probability_of_improvement(x, y) == expected
    p, low, high = probability_of_improvement_ci(x, y)
    assert p == expected and low <= p <= high


def test_separated_sets_have_a_degenerate_interval() -> None:
    assert probability_of_improvement_ci([4, 5, 6], [1, 2, 3]) == (1.0, 1.0, 1.0)
    assert probability_of_improvement_ci([1, 2, 3], [4, 5, 6]) == (0.0, 0.0, 0.0)


def test_iqm_interval_contains_the_estimate_shrinks_with_seeds_and_is_deterministic() -> None:
    rng = np.random.default_rng(7)
    few, many = rng.normal(1.0, 0.3, 4), rng.normal(1.0, 0.3, 40)
    point, low, high = iqm_ci(few)
    assert low <= point <= high and low < high
    point_m, low_m, high_m = iqm_ci(many)
    assert low_m <= point_m <= high_m
    assert high_m - low_m < high - low
    assert iqm_ci(few) == (point, low, high)       # fixed seed: the same interval every time
    assert iqm_ci([2.5]) == (2.5, None, None)      # one seed: no interval


# ---------------------------------------------------------------------------- claims

AH = "lili/AirHockey-v0"
LEFT, MIDDLE = 0, 1


def write_run(spec, final_return: float, final_success: float, left_share: float,
              rows: int = 200) -> None:
    """A finished run as `lili train` writes it: config.yaml, metrics.csv with the logger's
    columns (air hockey: 3 strategy columns), summary.json. The last 10% of interactions return
    ``final_return`` and succeed at ``final_success``; over the last 200 the striker fires left
    ``left_share`` of the time, middle otherwise."""
    spec.run_dir.mkdir(parents=True)
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(
        {"env": spec.env, "env_kwargs": spec.env_kwargs, "algo": spec.algo, "seed": spec.seed,
         "interactions": rows, "agent": spec.agent}))
    columns = metric_columns(3)
    window, n_left = rows // 10, round(left_share * rows)
    lines = [",".join(columns)]
    for i in range(rows):
        final = i >= rows - window
        ret = final_return if final else -1.0
        ok = float((i - (rows - window)) < final_success * window) if final else 0.0
        sid = LEFT if i < n_left else MIDDLE
        cells = {"interaction": i, "return": ret, "length": 10, "success": ok,
                 "strategy_0": float(sid == 0), "strategy_1": float(sid == 1),
                 "strategy_2": 0.0, "strategy_id": sid, "wall_time": 0.1 * i}
        lines.append(",".join(str(cells.get(c, "")) for c in columns))
    (spec.run_dir / "metrics.csv").write_text("\n".join(lines) + "\n")
    (spec.run_dir / "summary.json").write_text(json.dumps({"interactions": rows}))


# Per algo: final return, block rate, left share, the same for every seed but for a small
# spread in the return (so that seeds differ, as real ones do).
AIR_HOCKEY = {
    "random": (0.15, 0.5, 0.4),       # block rate 50%: the paper's 18% +- 10 FAILs
    "sac": (0.35, 0.4, 0.4),          # 40%: within 44% +- 10
    "lili-no-influence": (1.0, 0.8, 0.3),
    "lili": (1.2, 0.9, 0.4),          # above LILI (no influence) in every seed pair: PASS
    "oracle": (1.45, 1.0, 0.5),
}


def _air_hockey_runs(out: Path, seeds: int, lni_seeds: int | None = None) -> None:
    for spec in plan(get_preset("air-hockey"), out, seeds=seeds):
        if spec.algo == "lili-no-influence" and lni_seeds is not None \
                and spec.seed >= lni_seeds:
            continue
        ret, ok, left = AIR_HOCKEY[spec.algo]
        write_run(spec, ret + 0.01 * spec.seed, ok, left)


def _verdicts(out: Path) -> dict[str, tuple[str, str]]:
    results = check_claims(PRESETS["air-hockey"], out_layout(out))
    return {r.claim.statement: (r.verdict, r.ours) for _, r in results}


def test_a_pass_a_fail_and_too_few_seeds(tmp_path: Path) -> None:
    _air_hockey_runs(tmp_path, seeds=5)
    got = _verdicts(tmp_path)
    assert got["LILI > LILI (no influence)"][0] == "PASS"
    assert "P(>) 1.00 [1.00, 1.00] (5 vs 5 seeds)" in got["LILI > LILI (no influence)"][1]
    assert got["Random block rate 18% ± 10"] == ("FAIL", "50.0% [50.0, 50.0] (5 seeds)")
    assert got["LILI block rate 91% ± 10"][0] == "PASS"
    assert got["SAC block rate 44% ± 10"][0] == "PASS"
    assert got["LILI's striker fires left 41% ± 10"][0] == "PASS"       # 40% left
    assert got["LILI (no influence)'s striker fires left 33% ± 10 (uniform)"][0] == "PASS"
    assert set(got) == {c.statement for c in CLAIMS["air-hockey"]}

    fewer = tmp_path / "fewer"
    _air_hockey_runs(fewer, seeds=5, lni_seeds=4)  # the headline claim needs 5 seeds a side
    verdict, ours = _verdicts(fewer)["LILI > LILI (no influence)"]
    assert verdict == "too few seeds" and "(5 vs 4 seeds; needs 5)" in ours


def test_unfinished_runs_do_not_count(tmp_path: Path) -> None:
    _air_hockey_runs(tmp_path, seeds=5)
    for summary in tmp_path.glob("air-hockey/AirHockey-v0/lili/seed_*/summary.json"):
        summary.unlink()
    verdict, ours = _verdicts(tmp_path)["LILI block rate 91% ± 10"]
    assert verdict == "too few seeds" and ours.startswith("0 seeds")


def test_reversed_order_fails_and_is_printed(tmp_path: Path, capsys) -> None:
    for spec in plan(get_preset("air-hockey"), tmp_path, seeds=5):
        ret, ok, left = AIR_HOCKEY[spec.algo]
        if spec.algo == "lili":
            ret = 0.5  # below LILI (no influence) in every seed pair
        write_run(spec, ret + 0.01 * spec.seed, ok, left)
    assert main(["reproduce", "air-hockey", "--check-only", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("| air-hockey | LILI > LILI (no"))
    assert "P(>) 0.00 [0.00, 0.00]" in line and line.endswith("| **FAIL** |")
    assert "of 7 claims" in out
    assert not (tmp_path / "air-hockey" / "report").exists()  # --check-only writes nothing


def test_sources_file_points_at_run_folders(tmp_path: Path) -> None:
    _air_hockey_runs(tmp_path / "runs", seeds=5)
    sources = tmp_path / "sources.yaml"
    sources.write_text("air-hockey:\n  - path: runs/air-hockey\n    algos: [lili, sac]\n")
    got = {r.claim.statement: r.verdict
           for _, r in check_claims(PRESETS["air-hockey"], load_sources(sources))}
    assert got["LILI > SAC (block rate)"] == "PASS"
    assert got["LILI > LILI (no influence)"] == "too few seeds"  # not named in the file


@pytest.mark.parametrize("text, message", [
    ("nowhere:\n  - path: runs\n", "unknown group folder 'nowhere'"),
    ("air-hockey:\n  - path: missing\n", "is not a folder"),
    ("air-hockey:\n  - path: runs\n    algos: [slac]\n", "algos ['slac'] are not run"),
    ("air-hockey:\n  - {path: runs, colour: red}\n", "is invalid; allowed: {path"),
    ("air-hockey:\n  - [path: runs\n", "is not valid YAML: line 3, column 1"),
    (b"air-hockey: \xff\n", "is not UTF-8 text; allowed: a YAML file"),
])
def test_bad_sources_file(tmp_path: Path, capsys, text: str | bytes, message: str) -> None:
    (tmp_path / "runs").mkdir()
    sources = tmp_path / "sources.yaml"
    sources.write_bytes(text if isinstance(text, bytes) else text.encode())
    assert main(["reproduce", "paper", "--check-only", "--sources", str(sources)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lili: error: --sources") and message in err
    assert len(err.strip().splitlines()) == 1, err


def test_check_only_refuses_other_modes(tmp_path: Path, capsys) -> None:
    assert main(["reproduce", "air-hockey", "--check-only", "--dry-run",
                 "--out", str(tmp_path)]) == 2
    assert "--check-only is invalid with --dry-run" in capsys.readouterr().err
    assert main(["reproduce", "air-hockey", "--sources", "x.yaml",
                 "--out", str(tmp_path)]) == 2
    assert "only read with --check-only" in capsys.readouterr().err


def test_every_paper_item_states_claims() -> None:
    for name in PRESETS["paper"].includes:
        assert CLAIMS[name], name
