"""The training loop through the CLI: run folders, resume equivalence, random interactions,
learning. (Every algo's determinism and API-level resume: tests/test_contract.py.)"""

import csv
import json

import gymnasium as gym
import numpy as np
import pytest
import yaml

import lili.envs  # noqa: F401
from lili import cli, runs
from lili.agents import LILI, SAC, Oracle
from lili.agents.registry import config_for
from lili.config import AgentConfig
from lili.evaluate import Episodes, evaluate
from lili.report import find_runs
from lili.report.stats import final_performance
from lili.runs import RunLogger, final_window
from lili.train import Stream, plays_at_random, train

FAST = {"hidden": [32, 32], "enc_hidden": [16, 16], "latent_dim": 3, "warmup_interactions": 3,
        "checkpoint_every": 4, "batch_interactions": 8, "per_interaction": 4}
FAST_SAC = config_for("sac", FAST)  # SAC and the Oracle read no latent field


def _rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(f)]


@pytest.fixture
def cfg_file(tmp_path):
    p = tmp_path / "fast.yaml"
    p.write_text(yaml.safe_dump(FAST))
    return str(p)


def _loop(agent, n):
    """The loop's rows for ``n`` interactions of ``agent`` on a fresh stream of its env."""
    return train(agent, Stream.for_agent(agent, agent.env), n)


def _train(out, cfg_file, algo="lili", n=10, extra=()):
    return cli.main(["train", "driving-2d", "--algo", algo, "--interactions", str(n), "--out",
                     str(out), "--config", cfg_file, "--no-progress", *extra])


def test_run_folder_contents(tmp_path, cfg_file, monkeypatch):
    run = tmp_path / "a" / "Driving2D-v0" / "lili" / "seed_0"
    # A commit made while a run trains must not be credited with the run's numbers. The stand-in
    # for git's HEAD moves once the run has logged an interaction (a commit made mid-run).
    monkeypatch.setattr(runs, "_git_commit", lambda: "moved" if (run / "metrics.csv").exists()
                        and len((run / "metrics.csv").read_text().splitlines()) > 1 else "start")
    assert _train(tmp_path / "a", cfg_file, n=6) == 0
    rows = _rows(run / "metrics.csv")
    assert [int(r["interaction"]) for r in rows] == list(range(6))
    assert {"return", "success", "strategy_0", "strategy_id", "critic_loss", "rep_loss"} <= set(
        rows[0])
    assert rows[0]["critic_loss"] == "" and rows[-1]["critic_loss"] != ""
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["algo"] == "lili" and cfg["agent"]["latent_dim"] == 3
    summary = json.loads((run / "summary.json").read_text())
    assert summary["interactions"] == 6
    assert {"jax", "jaxlib", "optax", "cpu"} <= set(summary["versions"])
    assert summary["git_commit"] == "start"
    assert summary["final_return"] == float(rows[-1]["return"])
    assert "final_return_policy" not in summary  # only runs with random interactions have it
    # CPU-seconds of the training (what lili.experiments.costs estimates from): at least the
    # compiles, and no more than wall time x the 2 cores' threads could spend (and then some).
    assert 0.5 < summary["cpu_time_s"] < 8 * summary["wall_time_s"] + 1
    assert list((run / "tb").glob("events.out.tfevents.*"))
    assert (run / "checkpoints" / "latest.json").exists()


def test_resume_gives_the_same_numbers(tmp_path, cfg_file, monkeypatch):
    """Through the CLI: a killed run resumes to the numbers of an uninterrupted one, also from a
    metrics.csv written before the `random` column existed. (Every algo's resume at the API
    level: tests/test_contract.py.)"""
    algo = "lili"
    assert _train(tmp_path / "full", cfg_file, algo, n=10) == 0
    original_log = RunLogger.log

    def dying_log(self, row, agent, stream):
        original_log(self, row, agent, stream)
        if row["interaction"] == 6:  # killed two interactions after the checkpoint at 4
            raise KeyboardInterrupt

    monkeypatch.setattr(RunLogger, "log", dying_log)
    assert _train(tmp_path / "cut", cfg_file, algo, n=10) == 130
    monkeypatch.setattr(RunLogger, "log", original_log)
    run = tmp_path / "cut" / "Driving2D-v0" / algo / "seed_0"
    assert len(_rows(run / "metrics.csv")) == 7
    with (run / "metrics.csv").open(newline="") as f:
        old = [{k: v for k, v in r.items() if k != "random"} for r in csv.DictReader(f)]
    with (run / "metrics.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, list(old[0]))
        writer.writeheader()
        writer.writerows(old)
    assert _train(tmp_path / "cut", cfg_file, algo, n=10, extra=["--resume"]) == 0
    full = _rows(tmp_path / "full" / "Driving2D-v0" / algo / "seed_0" / "metrics.csv")
    assert _rows(run / "metrics.csv") == full


def test_random_interactions_are_drawn_from_the_seed_and_played_at_random():
    draws = [plays_at_random(4, i, 3, 0.3) for i in range(2000)]
    assert draws[:3] == [True] * 3 and 0.27 < np.mean(draws[3:]) < 0.33
    assert draws == [plays_at_random(4, i, 3, 0.3) for i in range(2000)]
    assert not any(plays_at_random(4, i, 3, 0.0) for i in range(3, 200))
    assert draws != [plays_at_random(5, i, 3, 0.3) for i in range(2000)]
    # In the loop: after the warm-up an interaction drawn at random plays the warm-up's
    # uniform actions (from the same (seed, interaction) generator), the others the policy's.
    agent = SAC(gym.make("lili/InfluenceDrift-v0"),
                AgentConfig.from_dict({**FAST_SAC, "random_interactions": 0.5}), seed=2)
    rows = _loop(agent, 12)
    buf = agent.stream.buffer
    chosen = [i for i in range(3, 12) if plays_at_random(2, i, 3, 0.5)]
    assert [r["random"] for r in rows] == [i < 3 or i in chosen for i in range(12)]
    assert 0 < len(chosen) < 9
    for i in range(3, 12):
        rng = np.random.default_rng([2, i])
        uniform = np.array([rng.uniform(-1.0, 1.0, 1) for _ in range(agent.horizon)])
        acts = np.asarray(buf.window(i, 1, None)["act"])[0]
        assert np.allclose(acts, uniform) == (i in chosen), i


def test_summary_gives_the_policys_own_final_numbers_beside_all(tmp_path, capsys):
    cfg = tmp_path / "random.yaml"
    cfg.write_text(yaml.safe_dump({**FAST_SAC, "random_interactions": 0.5}))
    n, warmup = 30, FAST["warmup_interactions"]
    assert _train(tmp_path, str(cfg), algo="sac", n=n) == 0
    run = tmp_path / "Driving2D-v0" / "sac" / "seed_0"
    rows = _rows(run / "metrics.csv")
    # metrics.csv logs which interactions were played at random, the warm-up included.
    played = np.array([r["random"] == "1" for r in rows])
    assert played.tolist() == [plays_at_random(0, i, warmup, 0.5) for i in range(n)]
    drawn = played & (np.arange(n) >= warmup)
    returns = np.array([float(r["return"]) for r in rows])
    success = np.array([float(r["success"]) for r in rows])
    own = ~drawn
    k = final_window(int(own.sum()))  # the last 10% of the policy's own, as in the report
    # The last 10% (3 interactions) of all and of the policy's own are different sets here.
    assert drawn[-3:].any() and 0 < drawn.sum() < n - warmup
    summary = json.loads((run / "summary.json").read_text())
    assert summary["final_return"] == pytest.approx(returns[-3:].mean(), abs=1e-5)
    assert summary["final_return_policy"] == pytest.approx(returns[own][-k:].mean(), abs=1e-5)
    assert summary["final_success_policy"] == pytest.approx(success[own][-k:].mean())
    # The report's --policy-only reads the same number from the run folder.
    (policy,) = find_runs([run], policy_only=True)
    assert final_performance(policy) == pytest.approx(summary["final_return_policy"], abs=1e-5)
    assert f"the policy's own interactions: {summary['final_return_policy']:.3f}" in (
        capsys.readouterr().out)


def test_evaluate_reports_per_interaction_metrics():
    agent = LILI(gym.make("lili/Driving2D-v0"), AgentConfig.from_dict(FAST))
    res = evaluate(agent, gym.make("lili/Driving2D-v0"), n_interactions=4, seed=3)
    assert len(res["returns"]) == 4 and res["success_rate"] is not None
    assert res["strategy_ids"][0] in (0, 1)
    with pytest.raises(ValueError, match="n_interactions=0"):
        evaluate(agent, n_interactions=0)


def test_episodes_give_the_oracle_the_strategy_it_trained_with():
    # A bare env handed to the step-by-step driver must be wrapped as in training: the Oracle
    # acting on observations without the strategy gave wrong actions and no error.
    agent = Oracle(gym.make("lili/InfluenceDrift-v0"), AgentConfig.from_dict(FAST_SAC))
    bare = Episodes(agent, gym.make("lili/InfluenceDrift-v0"), seed=3)
    assert bare.obs.shape == (agent.obs_dim,)
    played = [float(bare.play()["ret"]) for _ in range(3)]
    assert played == evaluate(agent, gym.make("lili/InfluenceDrift-v0"), 3, seed=3)["returns"]


@pytest.mark.slow  # 4-5 CPU-minutes; tests/test_readme.py keeps a learning test in the suite
def test_lili_learns_driving_2d():
    """LILI beats a random policy by far on Driving (2D) within a small budget (fixed seed).

    A random policy passes 3.6% of the time (measured over 500 interactions); a policy that
    ignores the partner about 50%; LILI should model the partner and go beyond.
    """
    env = gym.make("lili/Driving2D-v0")
    agent = LILI(env, AgentConfig(updates_per_step=2.0), seed=0)
    rows = _loop(agent, 400)
    success = np.mean([r["success"] for r in rows[-50:]])
    assert success >= 0.6, success


class _Endless(gym.Env):
    """Claims a horizon of 3 but never ends an interaction: breaks the contract."""

    horizon = 3
    observation_space = gym.spaces.Box(-1, 1, (1,), np.float32)
    action_space = gym.spaces.Box(-1, 1, (1,), np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action):
        return np.zeros(1, np.float32), 0.0, False, False, {}


def test_training_on_an_env_that_breaks_the_contract_fails_clearly():
    from lili.envs.checker import EnvContractError

    agent = SAC(_Endless(), AgentConfig.from_dict(FAST_SAC))
    with pytest.raises(EnvContractError, match="did not end within the env's horizon \\(3"):
        _loop(agent, 1)
