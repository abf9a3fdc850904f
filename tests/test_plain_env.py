"""Any Gymnasium env trains: a plain ``gymnasium.Env`` that follows the contract goes through
``lili check-env``, ``lili train`` and ``lili eval`` from the shell, and an env with no partner
strategy at all (Pendulum) trains SAC and LILI while the Oracle refuses it clearly."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from lili.agents import LILI, SAC, Oracle
from lili.agents.base import env_horizon
from lili.agents.registry import config_for
from lili.config import AgentConfig

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SPEC = "plain_hide_and_seek:PlainHideAndSeek"
SMALL = {"hidden": [32, 32], "enc_hidden": [16, 16], "latent_dim": 2, "warmup_interactions": 2,
         "checkpoint_every": 2, "batch_interactions": 4, "per_interaction": 4}


def _lili(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(EXAMPLES))
    return subprocess.run([sys.executable, "-m", "lili.cli", *args], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=600)


@pytest.fixture(scope="module")
def small_config(tmp_path_factory) -> Path:
    import yaml

    path = tmp_path_factory.mktemp("cfg") / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    return path


@pytest.fixture(scope="module")
def small_sac_config(tmp_path_factory) -> Path:
    """SMALL without the latent fields, which SAC and the Oracle do not read."""
    import yaml

    path = tmp_path_factory.mktemp("cfg") / "small_sac.yaml"
    path.write_text(yaml.safe_dump(config_for("sac", SMALL)))
    return path


@pytest.mark.slow
def test_a_plain_gymnasium_env_checks_trains_and_evaluates_from_the_shell(tmp_path,
                                                                          small_config):
    out = _lili("check-env", SPEC, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    out = _lili("train", SPEC, "--algo", "lili", "--interactions", "4", "--out", "runs",
                "--config", str(small_config), "--no-progress", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    run = tmp_path / "runs" / "plain_hide_and_seek_PlainHideAndSeek" / "lili" / "seed_0"
    with (run / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and rows[-1]["critic_loss"] != ""
    assert {r["strategy_0"] for r in rows} <= {"-0.5", "0.5"}
    out = _lili("eval", str(run), "--interactions", "3", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "mean return" in out.stdout and "success rate" in out.stdout
    # Resuming from the shell works for a user's env too.
    out = _lili("train", SPEC, "--algo", "lili", "--interactions", "6", "--out", "runs",
                "--config", str(small_config), "--no-progress", "--resume", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "resumed at interaction 4" in out.stdout


def test_a_misspelt_user_env_is_one_clear_error(tmp_path):
    out = _lili("train", "plain_hide_and_seek:NoSuchEnv", "--interactions", "2", cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and "has no attribute 'NoSuchEnv'" in out.stderr
    assert not (tmp_path / "runs").exists()


def test_the_horizon_comes_from_a_time_limit():
    assert env_horizon(gym.make("Pendulum-v1")) == 200
    wrapped = gym.wrappers.TimeLimit(gym.make("Pendulum-v1").unwrapped, max_episode_steps=7)
    assert env_horizon(wrapped) == 7
    with pytest.raises(ValueError, match="has no interaction length .*TimeLimit"):
        env_horizon(gym.make("Pendulum-v1").unwrapped)


@pytest.mark.slow
def test_an_env_without_a_strategy_trains_sac_and_lili_and_the_oracle_refuses_it():
    cfg = AgentConfig.from_dict({**SMALL, "updates_per_step": 0.05})
    for cls in (SAC, LILI):
        agent = cls(gym.make("Pendulum-v1"), config_for(cls.algo, cfg)).learn(3)
        assert agent.num_interactions == 3
        assert np.isfinite(agent.train_block(agent.stream.buffer,
                                             __import__("jax").random.PRNGKey(0))["critic_loss"])
    with pytest.raises(ValueError, match="the Oracle needs the partner's true strategy"):
        Oracle(gym.make("Pendulum-v1"), config_for("oracle", cfg))


def test_lili_train_pendulum_from_the_shell(tmp_path, small_sac_config):
    out = _lili("train", "Pendulum-v1", "--algo", "sac", "--interactions", "3", "--out", "r",
                "--config", str(small_sac_config), "--no-progress", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "reports no partner strategy" in out.stdout
    out = _lili("train", "Pendulum-v1", "--algo", "oracle", "--interactions", "3", "--out",
                "r", "--config", str(small_sac_config), cwd=tmp_path)
    assert out.returncode == 2 and out.stderr.count("\n") == 1, out.stderr
    assert "the Oracle needs the partner's true strategy" in out.stderr
    assert not (tmp_path / "r" / "Pendulum-v1" / "oracle").exists()
