"""`lili reproduce`: presets, planning, skip / resume, bad input, and a real quick sweep."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from _old_configs import add_retired_fields, drop_new_agent_fields

from lili.cli import main
from lili.experiments import PRESETS, get_preset, plan, run_status
from lili.experiments.plan import QUICK_CONFIG
from lili.experiments.presets import ALL_ALGOS
from lili.report import PAPER_TABLES

# ----------------------------------------------------------------------------- presets, plan


def test_every_paper_item_has_a_preset() -> None:
    assert set(PRESETS["paper"].includes) == {"point-mass", "noise", "history", "driving-2d",
                                              "driving-steer", "lunar-lander", "air-hockey"}
    for name in ("point-mass", "driving-2d", "driving-steer", "lunar-lander"):
        assert PRESETS[name].algos == ALL_ALGOS
    assert PRESETS["air-hockey"].algos == ("random", "sac", "lili-no-influence", "lili", "oracle")


def test_noise_and_history_expand_to_the_paper_tables(tmp_path: Path) -> None:
    noise = plan(get_preset("noise"), tmp_path)
    lili = {s.env_kwargs.get("step_noise", 0.0) for s in noise if s.algo == "lili"}
    assert lili == set(PAPER_TABLES["noise"]["rows"])
    # 6 LILI rows, the bounds (SAC, Oracle) and SAC and the Oracle at two sigmas.
    assert len(noise) == 3 * (6 + 2 + 2 * 2) and {s.seed for s in noise} == {0, 1, 2}
    assert {s.interactions for s in noise} == {2000}
    bounded = {(s.algo, s.env_kwargs.get("step_noise")) for s in noise if s.algo != "lili"}
    assert bounded == {(a, v) for a in ("sac", "oracle") for v in (None, 0.4, 1.0)}
    history = plan(get_preset("history"), tmp_path)
    for s in history:
        n = s.env_kwargs.get("history", 1)
        # LILI's encoder reads the partner's N; SAC and the Oracle read no history.
        assert s.config.get("history", 1) == (n if s.algo == "lili" else 1)
    assert {(s.algo, s.env_kwargs.get("history")) for s in history if s.algo != "lili"} == {
        (a, v) for a in ("sac", "oracle") for v in (None, 5, 11)}
    assert {s.env_kwargs.get("history", 1) for s in history} == set(PAPER_TABLES["history"]["rows"])
    # sigma = 0, N = 1 and the bounds are the Point Mass preset's own runs.
    pm = {s.run_dir for s in plan(get_preset("point-mass"), tmp_path)}
    shared = {s.run_dir for s in noise if not s.env_kwargs}
    assert shared and shared <= pm


def test_the_influence_suite_is_a_preset_outside_paper(tmp_path: Path) -> None:
    specs = plan(get_preset("influence"), tmp_path)
    assert {s.env for s in specs} == {"lili/InfluenceDrift-v0", "lili/InfluenceSwitch-v0",
                                      "lili/InfluenceFlee-v0"}
    assert len(specs) == 3 * 5 * 3 and {s.interactions for s in specs} == {2000}
    assert {s.algo for s in specs} == {"sac", "lili-no-influence", "lili", "oracle", "oracle-last"}
    assert "influence" not in PRESETS["paper"].includes
    # Drift's version is written into every run's config (its default changed once).
    assert {s.env: s.env_kwargs for s in specs}["lili/InfluenceDrift-v0"] == {"returns": 0.05}


def test_envs_keeps_only_those_envs_by_id_or_alias(tmp_path: Path) -> None:
    drift = plan(get_preset("influence"), tmp_path, envs=("influence-drift",))
    assert {s.env for s in drift} == {"lili/InfluenceDrift-v0"} and len(drift) == 5 * 3
    paper = plan(get_preset("paper"), tmp_path, envs=("lili/AirHockey-v0",), algos=("sac",))
    assert [(s.env, s.algo) for s in paper] == [("lili/AirHockey-v0", "sac")] * 8


def test_set_overrides_every_run_and_is_checked(tmp_path: Path, capsys) -> None:
    specs = plan(get_preset("influence"), tmp_path, algos=("lili",), quick=True,
                 overrides={"gamma": 0.999})
    assert {s.config["gamma"] for s in specs} == {0.999}
    assert all(s.agent["gamma"] == 0.999 and s.agent["warmup_interactions"] == 3 for s in specs)
    out = tmp_path / "out"
    for bad, message in [("gamma=2", "--set: config gamma=2 is invalid; allowed: a number "
                                     "in [0, 1)"),
                         ("bogus=1", "--set: unknown config key(s) 'bogus'; allowed: "),
                         ("gamma", "--set 'gamma' is invalid; allowed: KEY=VALUE")]:
        assert main(["reproduce", "influence", "--set", bad, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_env_kwarg_sets_every_run_and_is_checked(tmp_path: Path, capsys) -> None:
    specs = plan(get_preset("influence"), tmp_path, envs=("influence-drift",),
                 env_kwargs={"returns": 0.0})
    assert specs and {s.env_kwargs["returns"] for s in specs} == {0.0}
    # Over the preset's own options, not in place of them.
    base = plan(get_preset("history"), tmp_path, algos=("lili",))
    kept = plan(get_preset("history"), tmp_path, algos=("lili",), env_kwargs={"step_noise": 0.1})
    assert any(s.env_kwargs for s in base)
    assert [s.env_kwargs for s in kept] == [{**s.env_kwargs, "step_noise": 0.1} for s in base]
    out = tmp_path / "out"
    for argv, message in [
            (["--env-kwarg", "returns=0"], "--env-kwarg returns=0 does not fit "
             "lili/InfluenceSwitch-v0 (every env of the plan must take it; choose them with "
             "--envs): unknown env kwarg(s) 'returns'"),
            (["--envs", "influence-drift", "--env-kwarg", "returns=2"],
             "does not fit lili/InfluenceDrift-v0 (every env of the plan must take it; choose "
             "them with --envs): returns=2 is invalid; allowed: a number in [0, 1]"),
            (["--env-kwarg", "returns"], "--env-kwarg 'returns' is invalid; allowed: KEY=VALUE")]:
        assert main(["reproduce", "influence", *argv, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_env_kwarg_reaches_the_run(tmp_path: Path) -> None:
    out = tmp_path / "out"
    # Two interactions, both before learning starts (warm-up 3): the check is the run's config
    # and report, and a run that learns would only add compiling SAC's update.
    assert main(["reproduce", "influence", "--envs", "influence-drift", "--algos", "sac",
                 "--quick", "--interactions", "2", "--env-kwarg", "returns=0", "--out",
                 str(out), "--no-progress"]) == 0
    (config,) = out.rglob("config.yaml")
    assert yaml.safe_load(config.read_text())["env_kwargs"] == {"returns": 0}
    # The report does not pass for the preset's own beside the paper.
    md = (out / "influence" / "report" / "results.md").read_text()
    assert "**Every run changed from the preset's:** `--env-kwarg returns=0`." in md


def test_each_algo_checks_its_own_constraints_before_anything_runs(tmp_path: Path,
                                                                    capsys) -> None:
    # --quick once set a warm-up LILAC refuses; its runs failed one by one after the sweep began.
    assert plan(get_preset("paper"), tmp_path, quick=True)
    with pytest.raises(ValueError, match="warmup_interactions=2 is invalid for LILAC"):
        plan(get_preset("point-mass"), tmp_path, algos=("lilac",),
             overrides={"warmup_interactions": 2})
    out = tmp_path / "out"
    assert main(["reproduce", "point-mass", "--algos", "lilac", "--set",
                 "warmup_interactions=2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "warmup_interactions=2 is invalid for LILAC" in err[0], err
    assert not out.exists()


def test_paper_counts_each_run_once(tmp_path: Path) -> None:
    specs = plan(get_preset("paper"), tmp_path)
    # Point Mass 6, noise and history 5 LILI rows + SAC and the Oracle at 2 variants each,
    # the three driving/landing tasks 6 (3 seeds each), air hockey 5 (8 seeds).
    assert len({s.run_dir for s in specs}) == len(specs) == 3 * (6 + 9 + 9 + 6 + 6 + 6) + 8 * 5


def test_quick_algos_and_seeds(tmp_path: Path) -> None:
    specs = plan(get_preset("point-mass"), tmp_path, quick=True, algos=("sac", "lili"))
    assert [(s.algo, s.seed, s.interactions) for s in specs] == [("sac", 0, 6), ("lili", 0, 6)]
    assert specs[0].config == QUICK_CONFIG
    assert len(plan(get_preset("point-mass"), tmp_path, quick=True, seeds=2)) == 12


def _fake_run(spec, rows: int, summary: int | None) -> None:
    spec.run_dir.mkdir(parents=True)
    (spec.run_dir / "metrics.csv").write_text("interaction,return\n" + "".join(
        f"{i},0\n" for i in range(rows)))
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(
        {"env": spec.env, "env_kwargs": spec.env_kwargs, "algo": spec.algo, "seed": spec.seed,
         "interactions": spec.interactions, "agent": spec.agent}))
    if summary is not None:
        (spec.run_dir / "summary.json").write_text(f'{{"interactions": {summary}}}')


def _fake_finished_run(spec, k: int) -> None:
    """A finished 6-interaction run with the columns `lili train` writes; returns fall with k."""
    _fake_run(spec, 6, 6)
    columns = ("interaction,return,length,success,strategy_0,strategy_1,strategy_id,critic_loss,"
               "actor_loss,alpha,rep_loss,q,entropy,wall_time")
    (spec.run_dir / "metrics.csv").write_text(columns + "\n" + "".join(
        f"{i},{-1 - k - 0.1 * i},50,,0.5,0.5,-1,0.1,0.1,0.1,0.1,0.1,0.1,{i}\n" for i in range(6)))


def test_a_table_report_keeps_its_variants_apart(tmp_path: Path) -> None:
    # Every sigma holds the same (env, algo, seed) under other env kwargs; one find_runs over
    # all of them refused them as duplicate seeds, so no noise or history table was written.
    for k, spec in enumerate(plan(get_preset("noise"), tmp_path, quick=True)):
        _fake_finished_run(spec, k)
    assert main(["reproduce", "noise", "--quick", "--out", str(tmp_path), "--no-progress"]) == 0
    report = tmp_path / "noise" / "report"
    assert (report / "variants.png").exists()
    assert (report / "curves" / "noise_sigma_0.4" / "results.md").exists()
    assert "0.4" in (report / "results.md").read_text()


def test_report_only_writes_an_interim_table_and_starts_nothing(tmp_path: Path,
                                                                 capsys) -> None:
    specs = plan(get_preset("noise"), tmp_path, quick=True)
    finished = specs[::2]
    for k, spec in enumerate(finished):
        _fake_finished_run(spec, k)
    _fake_run(specs[1], 3, None)  # half-way: left as it is
    before = _snapshot(tmp_path)
    assert main(["reproduce", "noise", "--quick", "--out", str(tmp_path), "--report-only"]) == 0
    assert f"interim report from {len(finished)} of {len(specs)} runs" in capsys.readouterr().out
    text = (tmp_path / "noise" / "report" / "results.md").read_text()
    assert f"Interim report: {len(finished)} of {len(specs)} runs finished" in text
    after = _snapshot(tmp_path)
    assert {k: v for k, v in after.items() if k in before} == before  # no run touched
    assert all("/report/" in k for k in set(after) - set(before))
    assert not any(s.run_dir.exists() for s in specs if s not in finished and s != specs[1])


@pytest.mark.parametrize(("extra", "message"), [
    (["--dry-run"], "--dry-run and --report-only are invalid together"),
    ([], "--report-only: no run of preset 'noise' is finished under"),
])
def test_report_only_bad_input(tmp_path: Path, capsys, extra, message) -> None:
    argv = ["reproduce", "noise", "--quick", "--report-only", "--out", str(tmp_path / "o")]
    assert main(argv + extra) == 2
    err = capsys.readouterr().err
    assert err.startswith("lili: error: ") and message in err
    assert not (tmp_path / "o").exists()


def test_run_status_new_resume_done(tmp_path: Path) -> None:
    a, b, c, d = plan(get_preset("driving-2d"), tmp_path, seeds=1)[:4]
    _fake_run(b, 3, None)       # killed half-way
    _fake_run(c, 6, 6)          # finished at a smaller budget: extended with --resume
    _fake_run(d, 1000, 1000)    # finished
    assert [run_status(s) for s in (a, b, c, d)] == ["new", "resume", "resume", "done"]


def test_a_run_written_before_new_agent_fields_counts_as_done(tmp_path: Path) -> None:
    (spec,) = plan(get_preset("point-mass"), tmp_path, quick=True, algos=("lili",))
    _fake_run(spec, spec.interactions, spec.interactions)
    cfg = drop_new_agent_fields(yaml.safe_load((spec.run_dir / "config.yaml").read_text()))
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(cfg))
    assert run_status(spec) == "done"
    cfg = add_retired_fields(yaml.safe_load((spec.run_dir / "config.yaml").read_text()))
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(cfg))
    assert run_status(spec) == "done"


# --------------------------------------------------------------------------------- bad input


def _snapshot(root: Path) -> dict[str, bytes]:
    return {str(p): p.read_bytes() for p in root.rglob("*") if p.is_file()}


@pytest.mark.parametrize(("argv", "message"), [
    (["nope"], "unknown preset 'nope'; allowed: point-mass, noise"),
    (["point-mass", "--jobs", "0"], "--jobs 0 is invalid; allowed: an integer in [1, 1024]"),
    (["point-mass", "--seeds", "0"], "--seeds 0 is invalid"),
    (["point-mass", "--interactions", "-1"], "--interactions -1 is invalid"),
    (["air-hockey", "--algos", "slac"], "--algos slac is not in preset 'air-hockey'; allowed"),
    (["influence", "--envs", "point-mass"], "--envs point-mass is not in preset 'influence'; "
     "allowed: lili/InfluenceDrift-v0, lili/InfluenceSwitch-v0, lili/InfluenceFlee-v0"),
    (["influence", "--envs", "nowhere"], "unknown env 'nowhere'; allowed:"),
])
def test_bad_input_is_one_clear_error(tmp_path: Path, capsys, argv, message) -> None:
    assert main(["reproduce", *argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lili: error: ") and message in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_out_dir_with_runs_of_another_config(tmp_path: Path, capsys) -> None:
    (spec,) = plan(get_preset("point-mass"), tmp_path, quick=True, algos=("lili",))
    _fake_run(spec, 3, None)
    cfg = yaml.safe_load((spec.run_dir / "config.yaml").read_text())
    cfg["agent"]["latent_dim"] = 4
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(cfg))
    before = _snapshot(tmp_path)
    assert main(["reproduce", "point-mass", "--quick", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{spec.run_dir} holds a run of another config (agent: latent_dim=4 there, 8 here" in err
    assert _snapshot(tmp_path) == before


def test_out_is_a_file(tmp_path: Path, capsys) -> None:
    (tmp_path / "f").write_text("x")
    assert main(["reproduce", "point-mass", "--out", str(tmp_path / "f")]) == 2
    f = tmp_path / "f"
    assert f"--out '{f}' is invalid: '{f}' is a file" in capsys.readouterr().err


def test_ray_without_the_extra(tmp_path: Path) -> None:
    # A real failing import: `ray` is made unimportable in the child before lili runs.
    code = ("import sys; sys.modules['ray'] = None; from lili.cli import main; "
            f"sys.exit(main(['reproduce', 'point-mass', '--quick', '--ray', '--out', "
            f"{str(tmp_path / 'out')!r}]))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2
    assert res.stderr.strip().splitlines() == [
        "lili: error: --ray needs Ray, which is not installed; install the extra: "
        "pip install -e '.[ray]' (or pip install 'lili[ray]')"]
    assert not (tmp_path / "out").exists()


def test_dry_run_lists_runs_and_cpu_hours(tmp_path: Path, capsys) -> None:
    assert main(["reproduce", "paper", "--dry-run", "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert out.count("\nnew ") + out.startswith("new ") == 166
    assert "paper: 166 runs (166 to run, 0 done); estimated " in out
    hours = float(out.split("estimated ")[1].split(" CPU-hours")[0])
    assert 10 < hours < 200
    assert "  noise: " in out and "  air-hockey: " in out
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------- real runs (tiny budgets)


def _reproduce(out: Path, *args: str) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "lili.cli", "reproduce", "point-mass", "--quick", "--out",
           str(out), "--no-progress", *args]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)


def _numbers(run_dir: Path) -> list[list[str]]:
    """metrics.csv without the wall-time column (the one that may differ between runs)."""
    with (run_dir / "metrics.csv").open() as f:
        rows = list(csv.reader(f))
    drop = rows[0].index("wall_time")
    return [r[:drop] + r[drop + 1:] for r in rows]


@pytest.fixture(scope="module")
def quick_sweep(tmp_path_factory) -> Path:
    """`lili reproduce point-mass --quick --algos sac lili`: 2 runs of 6 interactions."""
    out = tmp_path_factory.mktemp("quick")
    proc = _reproduce(out, "--algos", "sac", "lili")
    log = proc.communicate(timeout=600)[0]
    assert proc.returncode == 0, log
    return out


def test_quick_sweep_writes_runs_and_report(quick_sweep: Path) -> None:
    for algo in ("sac", "lili"):
        run = quick_sweep / "point-mass" / "PointMass-v0" / algo / "seed_0"
        assert len(_numbers(run)) == 7 and (run / "summary.json").is_file()
    report = quick_sweep / "point-mass" / "report"
    md = (report / "results.md").read_text()
    assert "`lili reproduce point-mass`" in md and "Fig. 4" in md
    assert "changed from the preset" not in md
    assert "| SAC | 1 |" in md and "-5.05" in md and "| LILI | 1 |" in md
    assert (report / "curves.png").is_file() and (report / "heatmap.png").is_file()
    assert (report / "results.json").is_file()


def test_finished_runs_are_skipped(quick_sweep: Path, capsys) -> None:
    before = {p: p.stat().st_mtime_ns for p in quick_sweep.rglob("metrics.csv")}
    # In this process: the sweep's own command, with nothing to run, needs no fresh interpreter.
    assert main(["reproduce", "point-mass", "--quick", "--algos", "sac", "lili", "--out",
                 str(quick_sweep), "--no-progress"]) == 0
    assert "all 2 runs are done" in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in quick_sweep.rglob("metrics.csv")} == before


# The Ray backend on a local Ray instance (127.0.0.1): the quick sweep's runs again, as Ray
# tasks, give every number of the local runs. Its programs are the quick sweep's (the same
# runs), so the run's compilation cache (tests/conftest.py) serves them. The default sweeps one
# algo; the two-algo sweep (two runs at once) is slow.
@pytest.mark.parametrize("algos", [("sac",), pytest.param(("sac", "lili"), marks=pytest.mark.slow)],
                         ids=["sac", "sac-lili"])
def test_a_ray_sweep_equals_the_local_one(quick_sweep: Path, tmp_path: Path,
                                          algos: tuple[str, ...]) -> None:
    pytest.importorskip("ray")
    out = tmp_path / "ray"
    proc = _reproduce(out, "--algos", *algos, "--ray", "--jobs", "2")
    log = proc.communicate(timeout=900)[0]
    assert proc.returncode == 0, log
    assert "to run on Ray (local, 2 CPUs)" in log
    for algo in algos:
        run = Path("point-mass", "PointMass-v0", algo, "seed_0")
        assert (out / run / "summary.json").is_file()
        assert _numbers(out / run) == _numbers(quick_sweep / run) \
            and len(_numbers(quick_sweep / run)) == 7
    assert (out / "point-mass" / "report" / "results.md").is_file()


@pytest.mark.slow
def test_killed_run_resumes_to_the_same_numbers(quick_sweep: Path, tmp_path: Path) -> None:
    out = tmp_path / "killed"
    proc = _reproduce(out, "--algos", "lili")
    run = out / "point-mass" / "PointMass-v0" / "lili" / "seed_0"
    deadline = time.time() + 300
    # Kill the whole sweep (reproduce and its `lili train`) after the checkpoint at 2.
    while not ((run / "metrics.csv").exists() and len(_numbers(run)) >= 4):
        assert proc.poll() is None and time.time() < deadline
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert not (run / "summary.json").exists()
    assert run_status(plan(get_preset("point-mass"), out, quick=True, algos=("lili",))[0]) \
        == "resume"
    again = _reproduce(out, "--algos", "lili")
    log = again.communicate(timeout=300)[0]
    assert again.returncode == 0, log
    reference = quick_sweep / "point-mass" / "PointMass-v0" / "lili" / "seed_0"
    assert _numbers(run) == _numbers(reference)
    assert np.isfinite(float(_numbers(run)[-1][1]))


@pytest.mark.slow
def test_paper_quick(tmp_path: Path) -> None:
    assert main(["reproduce", "paper", "--quick", "--out", str(tmp_path), "--no-progress"]) == 0
    md = (tmp_path / "paper" / "report" / "results.md").read_text()
    for name in PRESETS["paper"].includes:
        assert f"`lili reproduce {name}`" in md


def test_history_text_rule_is_the_mirror_image() -> None:
    # The two readings of the majority rule are mirror images (x -> -x): the same actions,
    # mirrored, give the same rewards when the target starts at the mirrored angle.
    from lili.envs.point_mass import PointMassEnv

    rng = np.random.default_rng(0)
    a, b = PointMassEnv(history=3), PointMassEnv(history=3, inside_turn="counterclockwise")
    a.reset(seed=1)
    b.reset(seed=1)
    a.unwrapped.partner.theta, b.unwrapped.partner.theta = 0.3, np.pi - 0.3
    for _ in range(8):
        a.reset(), b.reset()
        for _ in range(50):
            act = rng.uniform(-1, 1, 2).astype(np.float32)
            _, ra, *_ = a.step(act)
            _, rb, *_ = b.step(act * np.array([-1, 1], np.float32))
            assert ra == pytest.approx(rb, abs=1e-9)
    with pytest.raises(ValueError, match="inside_turn='left' is invalid; allowed: clockwise"):
        PointMassEnv(inside_turn="left")
