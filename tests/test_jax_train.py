"""The JAX-native training path (``lili.jax_train``, ``lili train --backend jax``): a run's
numbers do not depend on its group, its run folder is one ``lili report`` reads, bad input is one
clear error with nothing written, and (slow) Point Mass LILI learns on it."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import jax
import numpy as np
import pytest
import yaml

from lili import cli
from lili.jax_train import JaxRuns
from lili.metrics_file import metric_columns

TINY = {"hidden": [32, 32], "enc_hidden": [16, 16], "latent_dim": 3, "warmup_interactions": 3,
        "buffer_capacity": 20, "checkpoint_every": 4, "batch_interactions": 4,
        "per_interaction": 4, "updates_per_step": 0.1}


def test_a_run_has_the_same_numbers_alone_and_in_a_group():
    # Driving (2D) with a noisy partner: its partner draws come from the env's key stream.
    group = JaxRuns("lili", "driving-2d", [4, 0, 9], TINY)
    together = group.train(5)
    alone = JaxRuns("lili", "driving-2d", [0], TINY)
    rows = alone.train(5)[0]
    assert [r["interaction"] for r in rows] == list(range(5))
    assert [r["random"] for r in rows] == [True] * 3 + [False] * 2
    assert "critic_loss" not in rows[1] and "critic_loss" in rows[2]  # learning starts at 3
    for a, b in zip(rows, together[1], strict=True):
        assert a.keys() == b.keys()
        for k, v in a.items():
            if k != "wall_time":
                np.testing.assert_allclose(b[k], v, rtol=1e-3, atol=1e-5, err_msg=k)
    one = jax.tree.leaves(alone.carry.states)
    three = jax.tree.leaves(group.carry.states)
    for x, y in zip(one, three, strict=True):
        np.testing.assert_allclose(np.asarray(y[1]), np.asarray(x[0]), rtol=1e-3, atol=1e-4)
    # Three runs, not one run copied: other seeds, other returns.
    assert not np.allclose([r["return"] for r in together[0]], [r["return"] for r in rows])
    # The stacked buffers hold each run's interactions as played.
    rew = np.asarray(group.stacked.arrays["rew"])[1, :5].sum(-1)
    np.testing.assert_allclose(rew, [r["return"] for r in rows], rtol=1e-4, atol=1e-4)


def _train(tmp_path: Path, *extra: str) -> int:
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY))
    return cli.main(["train", "point-mass", "--backend", "jax", "--interactions", "6",
                     "--config", str(config), "--out", str(tmp_path / "runs"), "--no-progress",
                     *extra])


def test_run_folders_of_the_jax_path_are_read_by_lili_report(tmp_path, capsys):
    assert _train(tmp_path, "--seeds", "0-1", "--algo", "sac") == 0
    for seed in (0, 1):
        run = tmp_path / "runs" / "PointMass-v0" / "sac" / f"seed_{seed}"
        with (run / "metrics.csv").open() as f:
            table = list(csv.reader(f))
        assert table[0] == metric_columns(2)
        assert [int(r[0]) for r in table[1:]] == list(range(6))
        summary = json.loads((run / "summary.json").read_text())
        assert summary["interactions"] == 6 and summary["seed"] == seed
        assert yaml.safe_load((run / "config.yaml").read_text())["backend"] == "jax"
        assert json.loads((run / "checkpoints" / "latest.json").read_text())["interactions"] == 6
        assert list((run / "tb").glob("events.out.tfevents.*"))
    assert cli.main(["report", str(tmp_path / "runs"), "--out", str(tmp_path / "report")]) == 0
    out = capsys.readouterr().out
    assert "sac" in out
    assert (tmp_path / "report").is_dir()


@pytest.mark.parametrize(("args", "message"), [
    (["--algo", "oracle"], "algo 'oracle' has no JAX-native training"),
    (["--algo", "lili", "--env-kwarg", "bogus=1"], "bogus"),
    (["--resume"], "--resume with --backend jax is not supported"),
])
def test_bad_input_is_one_clear_error_and_writes_nothing(tmp_path, capsys, args, message):
    with pytest.raises(SystemExit) as e:
        _train(tmp_path, *args)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("lili: error:") and message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "runs").exists()


def test_an_env_without_a_jax_twin_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit):
        cli.main(["train", "lunar-lander", "--backend", "jax", "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert "has no JAX version" in err and "lili/PointMass-v0" in err
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_point_mass_lili_learns_on_the_jax_path():
    """The paper's sizes, 4 seeds x 600 interactions (about N minutes on 2 CPU cores)."""
    runs = JaxRuns("lili", "point-mass", [0, 1, 2, 3])
    rows = runs.train(600)
    returns = np.array([[r["return"] for r in run] for run in rows])
    warmup = runs.config.warmup_interactions
    first, last = returns[:, :warmup].mean(), returns[:, -100:].mean()
    assert last > first + 5.0, (first, last)
