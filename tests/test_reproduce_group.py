"""`lili reproduce --group K`: seeds of one cell trained together in one process."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from lili.cli import main
from lili.experiments import get_preset, plan, run_status
from lili.experiments.runner import group_runs, groupable, log_path, train_command


def _start(spec, rows: int) -> None:
    """A run folder as a killed run leaves it: config.yaml and ``rows`` rows of metrics."""
    spec.run_dir.mkdir(parents=True)
    cfg = {"env": spec.env, "env_kwargs": spec.env_kwargs, "algo": spec.algo,
           "seed": spec.seed, "interactions": spec.interactions, "agent": spec.agent}
    (spec.run_dir / "config.yaml").write_text(yaml.safe_dump(cfg))
    (spec.run_dir / "metrics.csv").write_text("interaction\n" + "".join(
        f"{i}\n" for i in range(rows)))


def test_groupable_is_read_from_the_algo_class() -> None:
    assert groupable("sac") and groupable("lili") and groupable("lilac")
    # No update block (random) or a model pretrained first (SLAC): one process each.
    assert not groupable("random") and not groupable("slac")


def test_runs_of_one_cell_share_a_job_of_at_most_k(tmp_path: Path) -> None:
    specs = plan(get_preset("point-mass"), tmp_path, seeds=3, algos=("slac", "sac", "lili"))
    jobs = group_runs(specs, 2)
    named = [[(s.algo, s.seed) for s in job] for job in jobs]
    assert named == [[("sac", 0), ("sac", 1)], [("slac", 0)], [("lili", 0), ("lili", 1)],
                     [("slac", 1)], [("sac", 2)], [("slac", 2)], [("lili", 2)]]
    assert [len(j) for j in group_runs(specs, 1)] == [1] * len(specs)
    cmd = train_command(jobs[0])
    assert cmd[cmd.index("--seeds") + 1] == "0,1" and "--seed" not in cmd
    assert log_path(jobs[0]).name == "PointMass-v0-sac-seeds_0,1.log"
    assert log_path(jobs[1]).name == "PointMass-v0-slac-seed_0.log"


def test_a_started_run_does_not_share_a_job_with_new_ones(tmp_path: Path) -> None:
    specs = plan(get_preset("point-mass"), tmp_path, seeds=3, algos=("sac",))
    _start(specs[1], 3)
    assert [run_status(s) for s in specs] == ["new", "resume", "new"]
    jobs = group_runs(specs, 3)
    assert [[s.seed for s in j] for j in jobs] == [[0, 2], [1]]
    assert "--resume" in train_command(jobs[1]) and "--resume" not in train_command(jobs[0])


@pytest.mark.parametrize(("argv", "message"), [
    (["--group", "0"], "--group 0 is invalid; allowed: an integer in [1, 4096]"),
    (["--device", "tpu"], "--device 'tpu' is invalid; allowed: cpu, gpu"),
])
def test_bad_group_or_device_is_one_clear_error(tmp_path: Path, capsys, argv, message) -> None:
    assert main(["reproduce", "point-mass", "--quick", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lili: error: ") and message in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_device_gpu_without_a_gpu_is_one_clear_error(tmp_path: Path, capsys) -> None:
    import jax

    try:
        jax.devices("gpu")
        pytest.skip("this machine has a GPU")
    except RuntimeError:
        pass
    assert main(["reproduce", "point-mass", "--quick", "--device", "gpu", "--out",
                 str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--device gpu: JAX sees no GPU on this machine; allowed: cpu" in err
    assert not (tmp_path / "o").exists()


def _numbers(run_dir: Path) -> np.ndarray:
    with (run_dir / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    skip = {"wall_time", "cpu_time"}
    return np.array([[float(v) if v != "" else np.nan for k, v in r.items() if k not in skip]
                     for r in rows])


def _reproduce(out: Path, *args: str) -> str:
    proc = subprocess.run([sys.executable, "-m", "lili.cli", "reproduce", "point-mass",
                           "--quick", "--algos", "sac", "--out", str(out), "--no-progress",
                           *args], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


@pytest.mark.slow
def test_a_grouped_sweep_trains_each_run_as_alone(tmp_path: Path) -> None:
    log = _reproduce(tmp_path / "g", "--seeds", "2", "--group", "2", "--device", "cpu")
    assert "as 1 jobs (up to 2 seeds of a cell in one process)" in log
    exp = tmp_path / "g" / "point-mass"
    assert [p.name for p in (exp / "logs").iterdir()] == ["PointMass-v0-sac-seeds_0,1.log"]
    for seed in (0, 1):
        assert (exp / "PointMass-v0" / "sac" / f"seed_{seed}" / "summary.json").is_file()
    _reproduce(tmp_path / "a", "--seeds", "1")
    alone = _numbers(tmp_path / "a" / "point-mass" / "PointMass-v0" / "sac" / "seed_0")
    together = _numbers(exp / "PointMass-v0" / "sac" / "seed_0")
    # Loose: the vmapped program rounds differently and the updates amplify it (tests/
    # test_many.py pins each step tightly); a seed or config mix-up differs by far more.
    np.testing.assert_allclose(together, alone, rtol=2e-2, atol=1e-3, equal_nan=True)


# ------------------------------------------------- presets that reproduce by default (issue 34)


def test_presets_write_their_departures_and_the_paper_setting_is_one_flag_away(tmp_path):
    hockey = plan(get_preset("air-hockey"), tmp_path, seeds=1)
    assert {s.interactions for s in hockey} == {3000}
    assert all(s.agent["random_interactions"] == 0.1 for s in hockey)
    literal = plan(get_preset("air-hockey"), tmp_path, seeds=1, paper_settings=True)
    assert {s.interactions for s in literal} == {1000}
    assert all(s.agent["random_interactions"] == 0.0 for s in literal)
    lander = plan(get_preset("lunar-lander"), tmp_path, seeds=1)
    assert {s.agent["boundary_discount"] for s in lander} == {"horizon"}
    literal_lander = plan(get_preset("lunar-lander"), tmp_path, seeds=1, paper_settings=True)
    assert {s.agent["boundary_discount"] for s in literal_lander} == {"step"}
    # SLAC's own option reaches SLAC's runs alone; the paper's setting drops it.
    assert {s.algo: s.agent["extra"] for s in lander}["slac"] == {"slac": {"decoder_std": 0.1}}
    assert all(s.agent["extra"] == {} for s in lander if s.algo != "slac")
    assert all(s.agent["extra"] == {} for s in literal_lander)
    assert "`extra.slac.decoder_std=0.1`" in get_preset("lunar-lander").departs()
    # The paper preset is made of the parts, each with its own departures.
    paper = {s.run_dir: s for s in plan(get_preset("paper"), tmp_path, seeds=1)}
    assert all(paper[s.run_dir].interactions == 3000 for s in hockey)
    text = get_preset("air-hockey").departs()
    assert "`random_interactions=0.1`, 3000 interactions (the paper: 1000)" in text
    assert "`--paper-settings` runs the paper's setting" in text
    assert get_preset("point-mass").departs() == ""


def test_the_report_header_names_the_departures(tmp_path):
    from lili.experiments.results import _header

    specs = plan(get_preset("air-hockey"), tmp_path, seeds=1)
    assert "**Departs from the paper's setting:** `random_interactions=0.1`" in \
        _header(get_preset("air-hockey"), specs)
    assert "At the paper's own setting (`--paper-settings`)" in \
        _header(get_preset("air-hockey"), specs, paper_settings=True)
