"""Tests of lili.report on synthetic run folders with known numbers."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from lili import report
from lili.report import (
    PAPER,
    final_performance,
    find_runs,
    markdown_table,
    moving_average,
    plot_learning_curves,
    plot_strategy_heatmap,
    strategy_frequencies,
    summarize,
    write_report,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
PM, DR = "lili/PointMass-v0", "lili/Driving2D-v0"
N = 100  # interactions per run; the final window is the last 10
HEADER = (
    "interaction,return,length,success,strategy_0,strategy_1,strategy_id,"
    "critic_loss,actor_loss,alpha,rep_loss,wall_time"
)

# Final returns per (env, algo) for seeds 0, 1, 2 (early interactions return EARLY); binary
# fractions, so that means over the final window are exact.
FINAL_RETURN = {
    PM: {"sac": [-6.0, -5.0, -4.0], "oracle": [-1.0, -0.5, 0.0], "lili": [-1.5, -1.0, -0.5]},
    DR: {"sac": [-0.5, -0.25, -0.75], "oracle": [0.0, 0.0, 0.0], "lili": [-0.25, 0.0, -0.5]},
}
# Driving: number of successes among the last 10 interactions, per seed.
FINAL_SUCCESSES = {"sac": [4, 5, 6], "oracle": [10, 10, 10], "lili": [10, 9, 8]}
EARLY = -20.0


def _metrics_csv(env: str, algo: str, seed: int, n: int = N) -> str:
    lines = [HEADER]
    window = n // 10
    for i in range(n):
        final = i >= n - window
        ret = FINAL_RETURN[env][algo][seed] if final else EARLY
        if env == PM:
            # Targets on the circle; LILI keeps them near the top, the others spread around.
            theta = math.pi / 2 + (0.2 * (i % 3) if algo == "lili" else 0.2 * i)
            sx, sy = 0.1 * math.cos(theta), -0.05 + 0.1 * math.sin(theta)
            success, sid, strat = "", -1, f"{sx:.6f},{sy:.6f}"
        else:
            k = i - (n - window)
            success = str(int(final and k < FINAL_SUCCESSES[algo][seed])) if final else "0"
            sid = i % 2
            strat = f"{2 * sid - 1:.1f},"  # one strategy column: strategy_1 is empty
        losses = ",,," if i < 5 else "0.5,0.25,0.1,"
        lines.append(f"{i},{ret},50,{success},{strat},{sid},{losses},{0.01 * i:.2f}")
    return "\n".join(lines) + "\n"


def _write_run(root: Path, env: str, algo: str, seed: int, n: int = N, csv: str | None = None):
    folder = root / env.split("/")[-1] / algo / f"seed_{seed}"
    folder.mkdir(parents=True)
    config = {"env": env, "algo": algo, "seed": seed, "interactions": n, "lr": 3e-4}
    (folder / "config.yaml").write_text(yaml.safe_dump(config))
    if csv is None:
        csv = _metrics_csv(env, algo, seed, n)
    (folder / "metrics.csv").write_text(csv)
    return folder


@pytest.fixture()
def runs_dir(tmp_path: Path) -> Path:
    root = tmp_path / "runs"
    for env in (PM, DR):
        for algo in ("sac", "oracle", "lili"):
            for seed in range(3):
                _write_run(root, env, algo, seed)
    return root


def _row(summary, env, algo):
    (row,) = [r for r in summary if r["env"] == env and r["algo"] == algo]
    return row


def test_find_runs_reads_config_and_metrics(runs_dir: Path) -> None:
    runs = find_runs([runs_dir])
    assert len(runs) == 18
    algos = ("sac", "oracle", "lili")
    assert {(r.env, r.algo) for r in runs} == {(e, a) for e in (PM, DR) for a in algos}
    run = next(r for r in runs if r.env == PM and r.algo == "lili" and r.seed == 2)
    assert run.n_interactions == N and run.budget == N
    assert run.metrics["interaction"].dtype == np.int64
    assert np.isnan(run.metrics["success"]).all() and not run.has_success
    assert np.isnan(run.metrics["critic_loss"][:5]).all() and run.metrics["critic_loss"][5] == 0.5
    assert run.strategy is not None and run.strategy.shape == (N, 2)
    # A run folder, a parent and the same folder twice: each run is loaded once.
    again = find_runs([run.path, runs_dir / "PointMass-v0", run.path / "metrics.csv"])
    assert len(again) == 9


def test_final_performance(runs_dir: Path) -> None:
    runs = find_runs([runs_dir])
    for run in runs:
        assert final_performance(run) == FINAL_RETURN[run.env][run.algo][run.seed]
        assert final_performance(run, frac=1.0) == pytest.approx(
            0.9 * EARLY + 0.1 * FINAL_RETURN[run.env][run.algo][run.seed], rel=1e-12
        )
        if run.env == DR:
            assert final_performance(run, "success") == FINAL_SUCCESSES[run.algo][run.seed] / 10
        else:
            assert math.isnan(final_performance(run, "success"))
    run = runs[0]
    with pytest.raises(ValueError, match="no metric 'nope'"):
        final_performance(run, "nope")
    with pytest.raises(ValueError, match="frac"):
        final_performance(run, frac=0.0)


def test_final_performance_uses_at_least_one_interaction(tmp_path: Path) -> None:
    csv = HEADER + "\n" + "".join(
        f"{i},{float(i)},50,,0,0,-1,,,,,0\n" for i in range(5)
    )
    _write_run(tmp_path, PM, "sac", 0, csv=csv)
    (run,) = find_runs([tmp_path])
    assert final_performance(run) == 4.0  # 10% of 5 is less than 1 -> 1 interaction
    # The window is lili.runs' (the one summary.json uses): the last 3 of 5 at frac 0.5.
    from lili.runs import final_window

    k = final_window(5, 0.5)
    assert final_performance(run, frac=0.5) == np.mean(np.arange(5.0)[-k:]) == 3.0


def test_summarize_numbers(runs_dir: Path) -> None:
    summary = summarize(find_runs([runs_dir]))
    assert [(r["env"], r["algo"]) for r in summary] == [
        (PM, "sac"), (PM, "lili"), (PM, "oracle"), (DR, "sac"), (DR, "lili"), (DR, "oracle"),
    ]
    for row in summary:
        assert row["n"] == 3 and row["seeds"] == [0, 1, 2]
        assert row["interactions_min"] == row["interactions_max"] == row["budget"] == N
        finals = FINAL_RETURN[row["env"]][row["algo"]]
        assert row["returns"] == finals
        assert row["return_mean"] == pytest.approx(np.mean(finals), rel=1e-12, abs=1e-15)
        assert row["return_se"] == pytest.approx(np.std(finals, ddof=1) / np.sqrt(3), rel=1e-12)

    sac, lili, oracle = (_row(summary, PM, a) for a in ("sac", "lili", "oracle"))
    assert sac["return_mean"] == pytest.approx(-5.0)
    assert sac["return_se"] == pytest.approx(1 / math.sqrt(3))
    assert oracle["return_mean"] == pytest.approx(-0.5)
    assert oracle["return_se"] == pytest.approx(0.5 / math.sqrt(3))
    assert sac["gap_closed"] == 0.0 and oracle["gap_closed"] == 1.0
    assert lili["gap_closed"] == pytest.approx((-1.0 + 5.0) / (-0.5 + 5.0), rel=1e-12)
    assert lili["success_mean"] is None and lili["success_se"] is None
    assert sac["paper_return"] == -5.05 and lili["paper_return"] == -0.72
    assert oracle["paper_return"] == -0.54
    assert lili["paper_gap_closed"] == pytest.approx((-0.72 + 5.05) / (-0.54 + 5.05))

    dsac, dlili, doracle = (_row(summary, DR, a) for a in ("sac", "lili", "oracle"))
    assert dsac["success_mean"] == pytest.approx(0.5)
    assert dsac["success_se"] == pytest.approx(0.1 / math.sqrt(3))
    assert dlili["success_mean"] == pytest.approx(0.9)
    assert dlili["success_se"] == pytest.approx(0.1 / math.sqrt(3))
    assert doracle["success_mean"] == 1.0 and doracle["success_se"] == 0.0
    assert dlili["gap_closed"] == pytest.approx((-0.25 + 0.5) / (0.0 + 0.5))
    assert dlili["paper_return"] is None and dlili["paper_text"] == "near 100%"


def test_summarize_single_seed_and_missing_baselines(tmp_path: Path) -> None:
    _write_run(tmp_path, PM, "lili", 2)
    _write_run(tmp_path, PM, "sac", 0)
    summary = summarize(find_runs([tmp_path]))
    row = _row(summary, PM, "lili")
    assert row["n"] == 1 and row["return_se"] == 0.0
    assert row["gap_closed"] is None  # no Oracle run
    assert "| LILI | 1 | -0.50 | — | — | -0.72 (gap 0.96) |" in markdown_table(summary)  # no s.e.


def test_markdown_table(runs_dir: Path) -> None:
    md = markdown_table(summarize(find_runs([runs_dir])))
    assert "### Point Mass (lili/PointMass-v0)" in md
    assert "### Driving (2D) (lili/Driving2D-v0)" in md
    assert (
        "| algo | seeds | final return (mean ± s.e.) | success (mean ± s.e.) | gap closed | paper |"
        in md
    )
    assert "| SAC | 3 | -5.00 ± 0.58 | — | 0.00 | -5.05 |" in md
    assert "| LILI | 3 | -1.00 ± 0.29 | — | 0.89 | -0.72 (gap 0.96) |" in md
    assert "| Oracle | 3 | -0.50 ± 0.29 | — | 1.00 | -0.54 |" in md
    assert "| SAC | 3 | -0.50 ± 0.14 | 50.0% ± 5.8% | 0.00 | success about 50% or below |" in md
    assert "| LILI | 3 | -0.25 ± 0.14 | 90.0% ± 5.8% | 0.50 | success near 100% |" in md
    assert "| Oracle | 3 | 0.00 ± 0.00 | 100.0% ± 0.0% | 1.00 | success near 100% |" in md
    assert PAPER[DR]["text"] in md
    assert "Steps per interaction" not in md  # every interaction ran to H = 50


def test_the_table_gives_the_steps_per_interaction_where_they_differ(tmp_path: Path) -> None:
    # Interactions that end early: SAC's last 10 take 20 steps, LILI's seeds 30 and 40.
    for algo, seed, final in (("sac", 0, 20), ("lili", 0, 30), ("lili", 1, 40)):
        csv = "interaction,return,length\n" + "".join(
            f"{i},-1.0,{final if i >= 90 else 60}\n" for i in range(100))
        _write_run(tmp_path, DR, algo, seed, csv=csv)
    summary = summarize(find_runs([tmp_path]))
    lili = next(row for row in summary if row["algo"] == "lili")
    assert (lili["length_mean"], lili["length_se"]) == (35.0, 5.0)
    md = markdown_table(summary)
    assert "Steps per interaction (final, mean ± s.e.): SAC 20.0, LILI 35.0 ± 5.0." in md


def test_strategy_frequencies(runs_dir: Path, tmp_path: Path) -> None:
    runs = find_runs([runs_dir])
    driving = [r for r in runs if r.env == DR and r.algo == "lili"]
    # The fixture's driving partner alternates ids 0, 1, 0, ...
    np.testing.assert_allclose(strategy_frequencies(driving), [0.5, 0.5])
    assert strategy_frequencies([r for r in runs if r.env == PM]) is None  # ids are -1
    # An air hockey run whose striker ends up firing left 3 times in 4: the table names the
    # strategies as the paper does and cites the paper's block rate.
    ids = [0, 0, 0, 2] * 50
    csv = "interaction,return,success,strategy_id\n" + "".join(
        f"{i},1.5,1,{sid}\n" for i, sid in enumerate(ids))
    _write_run(tmp_path / "hockey", "lili/AirHockey-v0", "lili", 0, n=len(ids), csv=csv)
    summary = summarize(find_runs([tmp_path / "hockey"]))
    assert summary[0]["strategy_freq"] == pytest.approx([0.75, 0.0, 0.25])
    md = markdown_table(summary)
    assert "LILI: partner played left 75%, middle 0%, right 25% over the last 200" in md
    assert "| 1.15, success 91% |" in md


def test_wall_time_per_run(runs_dir: Path) -> None:
    summary = summarize(find_runs([runs_dir]))
    # Every fixture run logs wall_time = 0.01 * i, so the last row of N interactions gives this.
    assert _row(summary, PM, "lili")["wall_time_mean"] == pytest.approx(0.01 * (N - 1))
    md = markdown_table(summary)
    assert "| wall time / run |" in md
    assert "| -0.72 (gap 0.96) | 1 s |" in md


def test_moving_average() -> None:
    y = np.array([1.0, 2.0, 3.0, 4.0, np.nan, 6.0])
    np.testing.assert_allclose(moving_average(y, 3), [1.0, 1.5, 2.0, 3.0, 3.5, 5.0])
    np.testing.assert_allclose(moving_average(y[:4], 1), y[:4])
    with pytest.raises(ValueError, match="window"):
        moving_average(y, 0)


def _is_png(path: Path) -> bool:
    data = path.read_bytes()
    return len(data) > 1000 and data.startswith(PNG_MAGIC)


def test_write_report_all_files(runs_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    result = write_report([runs_dir], out)
    for name in ("curves.png", "success.png", "heatmap.png", "strategies.png"):
        assert _is_png(out / name), name
    assert set(result["files"]) == {"curves.png", "success.png", "heatmap.png", "strategies.png",
                                    "results.md", "results.json"}
    assert (out / "results.md").read_text() == result["markdown"]
    # The CLI prints markdown_table(write_report(...)): the returned dict is accepted too.
    assert markdown_table(result) == result["markdown"] == markdown_table(result["summary"])
    assert "| LILI | 3 | -1.00 ± 0.29 | — | 0.89 | -0.72 (gap 0.96) |" in result["markdown"]
    data = json.loads((out / "results.json").read_text())
    assert data["summary"] == result["summary"]
    assert len(data["runs"]) == 18 == len(result["runs"])
    assert _row(data["summary"], PM, "lili")["gap_closed"] == pytest.approx(4 / 4.5)
    assert data["paper"][PM]["return"]["sac"] == -5.05


def test_write_report_without_point_mass_has_no_heatmap(runs_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    (out).mkdir()
    (out / "heatmap.png").write_bytes(PNG_MAGIC)  # left over from an earlier report
    result = write_report([runs_dir / "Driving2D-v0"], out)
    assert _is_png(out / "curves.png") and _is_png(out / "success.png")
    assert not (out / "heatmap.png").exists() and "heatmap.png" not in result["files"]
    assert "Point Mass" not in result["markdown"]


def test_write_report_point_mass_only_has_no_success_plot(runs_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    result = write_report([runs_dir / "PointMass-v0"], out)
    assert _is_png(out / "curves.png") and _is_png(out / "heatmap.png")
    assert not (out / "success.png").exists() and "success.png" not in result["files"]


def test_plot_functions_direct(runs_dir: Path, tmp_path: Path) -> None:
    runs = find_runs([runs_dir])
    assert _is_png(plot_learning_curves(runs, tmp_path / "c.png", window=5))
    assert _is_png(plot_strategy_heatmap(runs, tmp_path / "h.png", last=20))
    driving = [r for r in runs if r.env == DR]
    with pytest.raises(ValueError, match="Point Mass"):
        plot_strategy_heatmap(driving, tmp_path / "x.png")
    with pytest.raises(ValueError, match="success"):
        plot_learning_curves([r for r in runs if r.env == PM], tmp_path / "x.png", "success")


def test_unfinished_runs(tmp_path: Path) -> None:
    # Different lengths, no summary.json, a half-written last line and a run with no rows yet.
    _write_run(tmp_path, PM, "lili", 0, n=200)
    partial = _metrics_csv(PM, "lili", 1, n=100) + "100,-3.0,50"
    _write_run(tmp_path, PM, "lili", 1, csv=partial)
    _write_run(tmp_path, PM, "lili", 2, csv=HEADER + "\n")
    runs = find_runs([tmp_path])
    assert [r.n_interactions for r in runs] == [200, 100, 0]
    (row,) = summarize(runs)
    assert row["n"] == 2 and row["interactions_min"] == 100 and row["interactions_max"] == 200
    result = write_report([tmp_path], tmp_path / "out")
    assert _is_png(tmp_path / "out" / "curves.png")
    # Seeds column flags runs that have not used their budget yet.
    assert "| LILI | 2 (100/200 int.) |" in result["markdown"]


def test_bad_paths_raise(tmp_path: Path) -> None:
    missing = tmp_path / "does-not-exist"
    with pytest.raises(ValueError, match=str(missing)):
        find_runs([missing])
    empty = tmp_path / "empty"
    (empty / "sub").mkdir(parents=True)
    with pytest.raises(ValueError, match=f"{empty}.*no run folder"):
        find_runs([empty])
    with pytest.raises(ValueError, match=str(missing)):
        write_report([missing], tmp_path / "out")


def test_metrics_without_return_column_raises(tmp_path: Path) -> None:
    folder = _write_run(tmp_path, PM, "sac", 0, csv="interaction,length\n0,50\n1,50\n")
    with pytest.raises(ValueError, match=f"{folder / 'metrics.csv'}.*missing column.*return"):
        find_runs([tmp_path])


@pytest.mark.parametrize(
    ("csv", "message"),
    [
        ("", "empty"),
        ("interaction,return\n0,-1.0\n1,-1.0,7\n2,-1.0\n", "line 3 has 3 fields"),
        ("interaction,return\n0,abc\n", "'abc' is not a number"),
        ("interaction,return\n,-1.0\n", "'interaction' must be an integer"),
    ],
)
def test_malformed_metrics_raise(tmp_path: Path, csv: str, message: str) -> None:
    folder = _write_run(tmp_path, PM, "sac", 0, csv=csv)
    with pytest.raises(ValueError, match=message) as info:
        find_runs([folder])
    assert str(folder / "metrics.csv") in str(info.value)


def test_bad_config_and_duplicate_runs_raise(tmp_path: Path) -> None:
    folder = _write_run(tmp_path / "a", PM, "sac", 0)
    (folder / "config.yaml").write_text(yaml.safe_dump({"env": PM, "algo": "sac"}))
    with pytest.raises(ValueError, match=f"{folder / 'config.yaml'}.*seed"):
        find_runs([folder])
    _write_run(tmp_path / "b", PM, "sac", 0)
    _write_run(tmp_path / "c", PM, "sac", 0)
    with pytest.raises(ValueError, match="same env/algo/seed"):
        find_runs([tmp_path / "b", tmp_path / "c"])


def test_paper_reference_matches_aliases() -> None:
    assert report.paper_reference("point-mass") is PAPER[PM]
    assert report.paper_reference("lili/Driving2D-v0") is PAPER[DR]
    assert report.paper_reference("CartPole-v1") is None
    assert report.algo_color("lili") != report.algo_color("sac")
    assert report.algo_color("new-algo") == report.algo_color("new-algo")


def test_upto_compares_runs_at_one_budget(tmp_path: Path) -> None:
    # A 200-interaction run and a 100-interaction run: at upto=100 the long run's final window
    # is its interactions 90-99 (EARLY return), not its last 20.
    _write_run(tmp_path, PM, "lili", 0, n=200)
    _write_run(tmp_path, PM, "lili", 1, n=100)
    runs = find_runs([tmp_path], upto=100)
    assert [r.n_interactions for r in runs] == [100, 100]
    assert [r.budget for r in runs] == [100, 100]
    (row,) = summarize(runs)
    assert row["returns"] == [EARLY, FINAL_RETURN[PM]["lili"][1]]
    result = write_report([tmp_path], tmp_path / "out", upto=100)
    assert "| LILI | 2 |" in result["markdown"]
    assert "last 10% of the first 100 interactions" in result["markdown"]
    # Without upto the long run is judged on its own last 10%.
    (full,) = summarize(find_runs([tmp_path]))
    assert full["returns"] == [FINAL_RETURN[PM]["lili"][0], FINAL_RETURN[PM]["lili"][1]]


@pytest.mark.parametrize("logged", [True, False], ids=["random-column", "before-the-column"])
def test_policy_only_leaves_out_the_interactions_played_at_random(tmp_path: Path,
                                                                  logged: bool) -> None:
    from lili.cli import main
    from lili.metrics_file import plays_at_random

    # Interactions drawn at random return -1 (their strategy id 1), the policy's return +1 (id 0):
    # the policy's own final return is exactly 1, the run's as logged is lower.
    n, warmup, share = 200, 5, 0.5
    played = [plays_at_random(3, i, warmup, share) for i in range(n)]
    drawn = [i >= warmup and p for i, p in enumerate(played)]
    # The columns `lili train` writes (a config with an agent section is checked against them):
    # with the `random` column, or as written before it existed.
    header = HEADER.replace("wall_time", "q,entropy,wall_time")
    if logged:
        header = header.replace("success,", "success,random,")
    rows = [header] + [
        f"{i},{-1.0 if d else 1.0},50,{int(not d)},{f'{int(p)},' if logged else ''}0.0,,"
        f"{int(d)},,,,,,,{0.01 * i}" for i, (p, d) in enumerate(zip(played, drawn, strict=True))]
    folder = _write_run(tmp_path, DR, "lili", 3, n=n, csv="\n".join(rows) + "\n")
    config = yaml.safe_load((folder / "config.yaml").read_text())
    # Where the column is logged the report reads it, not the config: here the config names
    # no random interactions, from which nothing could be recomputed.
    config["agent"] = {"warmup_interactions": warmup,
                       **({} if logged else {"random_interactions": share})}
    (folder / "config.yaml").write_text(yaml.safe_dump(config))
    (run,) = find_runs([tmp_path])
    assert run.played_at_random.tolist() == played
    assert run.random_draws.tolist() == drawn and 0 < sum(drawn) < n - warmup
    assert final_performance(run) < 1.0
    (policy,) = find_runs([tmp_path], policy_only=True)
    assert final_performance(policy) == 1.0 and final_performance(policy, "success") == 1.0
    assert strategy_frequencies([policy]).tolist() == [1.0]
    # The warm-up is the policy's curve too; a run without random interactions is unchanged.
    assert not policy.random_draws[:warmup].any()
    assert policy.metrics["return"][:warmup].tolist() == run.metrics["return"][:warmup].tolist()
    plain = _write_run(tmp_path / "plain", DR, "sac", 0)
    (same,) = find_runs([plain], policy_only=True)
    assert np.array_equal(same.metrics["return"], find_runs([plain])[0].metrics["return"])
    if not logged:
        return  # the command line reads both kinds of file through find_runs: once is enough
    out = tmp_path / "report"
    assert main(["report", str(folder), "--policy-only", "--out", str(out)]) == 0
    assert "interactions the policy played" in (out / "results.md").read_text()
    assert json.loads((out / "results.json").read_text())["summary"][0]["returns"] == [1.0]


@pytest.mark.parametrize("upto", [0, -5, 2.5, True])
def test_bad_upto_raises(runs_dir: Path, upto) -> None:
    with pytest.raises(ValueError, match="upto must be a positive number"):
        find_runs([runs_dir], upto=upto)


# ------------------------------------------------------------- files edited by hand, bad --out

FULL_HEADER = ("interaction,return,length,success,strategy_0,strategy_1,strategy_id,critic_loss,"
               "actor_loss,alpha,rep_loss,q,entropy,wall_time")


def _train_like_run(root: Path, n: int = 30, header: str = FULL_HEADER) -> Path:
    """A run folder as `lili train` writes it (config with 'agent', summary.json)."""
    folder = root / "PointMass-v0" / "lili" / "seed_0"
    folder.mkdir(parents=True)
    cols = header.split(",")
    rows = [",".join("0" if c != "interaction" else str(i) for c in cols) for i in range(n)]
    (folder / "metrics.csv").write_text("\n".join([header, *rows]) + "\n")
    (folder / "config.yaml").write_text(yaml.safe_dump(
        {"env": PM, "algo": "lili", "seed": 0, "interactions": n, "agent": {"gamma": 0.99}}))
    (folder / "summary.json").write_text(json.dumps({"interactions": n}))
    return folder


def test_train_like_run_loads(tmp_path: Path) -> None:
    (run,) = find_runs([_train_like_run(tmp_path)])
    assert run.n_interactions == 30


def test_deleted_column_is_an_error(tmp_path: Path) -> None:
    header = FULL_HEADER.replace(",rep_loss", "")
    folder = _train_like_run(tmp_path, header=header)
    with pytest.raises(ValueError, match="column\\(s\\) rep_loss were deleted") as info:
        write_report([folder], tmp_path / "out")
    assert str(folder / "metrics.csv") in str(info.value)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("drop", "message"), [
    (range(10, 20), "interactions 10 to 19 are missing \\(line 12 jumps from 9 to 20\\)"),
    (range(0, 3), "the first row is interaction 3, not 0"),
    (range(25, 30), "has 25 rows but summary.json says the run did 30 interactions"),
])
def test_deleted_rows_are_an_error(tmp_path: Path, drop, message: str) -> None:
    folder = _train_like_run(tmp_path)
    lines = (folder / "metrics.csv").read_text().splitlines()
    kept = [lines[0]] + [line for i, line in enumerate(lines[1:]) if i not in drop]
    (folder / "metrics.csv").write_text("\n".join(kept) + "\n")
    with pytest.raises(ValueError, match=message) as info:
        find_runs([folder])
    assert str(folder / "metrics.csv") in str(info.value)


def test_upto_beyond_a_run_is_an_error(tmp_path: Path) -> None:
    _write_run(tmp_path, PM, "lili", 0, n=300)
    with pytest.raises(ValueError, match="--upto 5000 is more than .* \\(300 interactions\\);"
                                         " allowed: 1 to 300"):
        write_report([tmp_path], tmp_path / "out", upto=5000)
    assert not (tmp_path / "out").exists()
    assert find_runs([tmp_path], upto=300)[0].n_interactions == 300


def test_report_out_is_a_file_is_an_error(tmp_path: Path) -> None:
    from lili.cli import main

    folder = _write_run(tmp_path, PM, "lili", 0)
    target = tmp_path / "taken.txt"
    target.write_text("keep me")
    with pytest.raises(ValueError, match=f"--out '{target}' is invalid: '{target}' is a file"):
        write_report([folder], target)
    assert main(["report", str(folder), "--out", str(target / "sub")]) == 2
    assert target.read_text() == "keep me"


def test_heatmap_title_fits_the_figure(runs_dir: Path) -> None:
    from lili.report.figures import heatmap_figure

    runs = [r for r in find_runs([runs_dir]) if r.env == PM]
    for subset in ([r for r in runs if r.algo == "lili"], runs):
        fig = heatmap_figure(subset)
        fig.canvas.draw()
        box = fig._suptitle.get_window_extent()
        width = fig.get_size_inches()[0] * fig.dpi
        assert box.x0 >= 0 and box.x1 <= width, (box, width)


def test_success_by_strategy_counts_each_window(tmp_path: Path) -> None:
    from lili.report.files import load_run
    from lili.report.stats import success_by_strategy

    run = load_run(_write_run(tmp_path, DR, "lili", 0))  # ids alternate; the last 10 succeed
    counts = success_by_strategy(run, 50)
    assert counts.tolist() == [[[0, 25], [0, 25]], [[5, 25], [5, 25]]]
    assert success_by_strategy(run, 30)[-1].tolist() == [[5, 5], [5, 5]]  # the short last one
    with pytest.raises(ValueError, match="window=0 is invalid; allowed: an integer >= 1"):
        success_by_strategy(run, 0)
    point_mass = load_run(_write_run(tmp_path, PM, "lili", 0))  # no discrete strategy
    with pytest.raises(ValueError, match="no strategy_id and success columns to count"):
        success_by_strategy(point_mass, 50)
