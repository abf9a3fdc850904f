"""``lili reproduce NAME --backend jax``: the runs whose env and algo the JAX-native path
supports train there (``lili train --backend jax``), the others on the Gymnasium envs, as the
plan and the dry run say."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from lili.cli import main
from lili.experiments import get_preset, plan, run_status
from lili.experiments.runner import group_runs, train_command


def _started(spec, rows: int, backend: str | None = None, done: bool = False) -> None:
    """A run folder as ``lili train`` leaves it: config.yaml, ``rows`` rows of metrics and,
    when ``done``, summary.json."""
    spec.run_dir.mkdir(parents=True)
    cfg = {"env": spec.env, "env_kwargs": spec.env_kwargs, "algo": spec.algo,
           "seed": spec.seed, "interactions": spec.interactions, "agent": spec.agent}
    if backend:
        cfg["backend"] = backend
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(cfg))
    (spec.run_dir / "metrics.csv").write_text("interaction\n" + "".join(
        f"{i}\n" for i in range(rows)))
    if done:
        (spec.run_dir / "summary.json").write_text(json.dumps({"interactions": rows}))


def test_the_plan_sends_what_the_jax_path_supports_there(tmp_path: Path) -> None:
    history = plan(get_preset("history"), tmp_path, seeds=2, quick=True, backend="jax")
    # Every run of the history table (N up to 11, the JAX partner's memory is 16).
    assert {s.algo for s in history} == {"sac", "lili", "oracle"}
    assert "history/n_11" in {s.folder for s in history}
    assert {s.backend for s in history} == {"jax"}
    assert all(s.backend == "gym" for s in plan(get_preset("history"), tmp_path, quick=True))
    specs = plan(get_preset("point-mass"), tmp_path, seeds=2, quick=True,
                 algos=("sac", "lilac", "oracle"), backend="jax")
    assert {(s.algo, s.backend) for s in specs} == {("sac", "jax"), ("lilac", "gym"),
                                                    ("oracle", "jax")}
    # An env without a JAX twin, or env kwargs its twin does not take, stay there too.
    lander = plan(get_preset("lunar-lander"), tmp_path, quick=True, algos=("sac",),
                  backend="jax")
    assert {s.backend for s in lander} == {"gym"}
    long = plan(get_preset("point-mass"), tmp_path / "h", quick=True, algos=("sac",),
                env_kwargs={"history": 30}, backend="jax")
    assert {s.backend for s in long} == {"gym"}
    jobs = group_runs(specs, 2)
    assert all(len(j) == 2 and len({s.backend for s in j}) == 1 for j in jobs)
    for job in jobs:
        cmd = train_command(job)
        if job[0].backend == "jax":
            assert cmd[cmd.index("--backend") + 1] == "jax"
        else:
            assert "--backend" not in cmd


def test_the_dry_run_says_which_runs_take_which_path(tmp_path: Path, capsys) -> None:
    assert main(["reproduce", "point-mass", "--quick", "--backend", "jax", "--dry-run",
                 "--algos", "sac", "lilac", "oracle", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "PointMass-v0/oracle/seed_0  (6 interactions" in out and "backend jax)" in out
    assert "PointMass-v0/lilac/seed_0" in out and "backend gym)" in out
    assert ("--backend jax: 2 runs on the JAX-native path, 1 on the Gymnasium path: algo "
            "'lilac' has no JAX-native training (1 run)") in out
    assert not (tmp_path / "o").exists()


def test_a_run_started_on_the_other_backend_is_one_clear_error(tmp_path: Path) -> None:
    specs = plan(get_preset("point-mass"), tmp_path, quick=True, algos=("sac", "oracle"))
    _started(specs[0], 2)  # sac: started on the Gymnasium path
    _started(specs[1], 6, done=True)  # oracle: finished there
    with pytest.raises(ValueError, match=r"sac/seed_0 holds a run started with --backend "
                                         r"'gym', which resumes only on that backend"):
        plan(get_preset("point-mass"), tmp_path, quick=True, algos=("sac",), backend="jax")
    # A finished run counts, whichever path trained it.
    done = plan(get_preset("point-mass"), tmp_path, quick=True, algos=("oracle",),
                backend="jax")
    assert done[0].backend == "jax" and run_status(done[0]) == "done"
    # And the other way round.
    jax_spec = plan(get_preset("point-mass"), tmp_path / "j", quick=True, algos=("sac",))[0]
    _started(jax_spec, 2, backend="jax")
    with pytest.raises(ValueError, match="started with --backend 'jax'"):
        run_status(jax_spec)
    assert run_status(plan(get_preset("point-mass"), tmp_path / "j", quick=True,
                           algos=("sac",), backend="jax")[0]) == "resume"


def test_a_bad_backend_is_one_clear_error(tmp_path: Path, capsys) -> None:
    assert main(["reproduce", "point-mass", "--quick", "--backend", "tpu", "--out",
                 str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lili: error: ") and "invalid choice: 'tpu'" in err
    assert err.count("\n") == 1 and not (tmp_path / "o").exists()
    with pytest.raises(ValueError, match="--backend 'tpu' is invalid; allowed: gym, jax"):
        plan(get_preset("point-mass"), tmp_path, backend="tpu")


@pytest.mark.slow
def test_a_sweep_with_backend_jax_trains_each_run_on_its_path(tmp_path: Path) -> None:
    """The Oracle on the JAX path and LILAC on the Gymnasium one, 4 interactions each, then
    the preset's report; 2 processes."""
    out = tmp_path / "o"
    proc = subprocess.run([sys.executable, "-m", "lili.cli", "reproduce", "point-mass",
                           "--quick", "--interactions", "4", "--algos", "oracle", "lilac",
                           "--backend", "jax", "--out", str(out), "--no-progress"],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "--backend jax: 1 run on the JAX-native path, 1 on the Gymnasium path" in proc.stdout
    runs = out / "point-mass" / "PointMass-v0"
    for algo, backend in (("oracle", "jax"), ("lilac", None)):
        cfg = yaml.safe_load((runs / algo / "seed_0" / "config.yaml").read_text())
        assert cfg.get("backend") == backend
        assert json.loads((runs / algo / "seed_0" / "summary.json").read_text())[
            "interactions"] == 4
    assert (out / "point-mass" / "report").is_dir()
