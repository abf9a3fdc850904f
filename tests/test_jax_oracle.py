"""The Oracles on the JAX-native path (``lili.envs.jax.wrappers``, ``lili train --algo oracle
--backend jax``): they observe what the Gymnasium Oracles observe, step for step, for the same
partner sequence; an env without a strategy is one clear error; and (slow) a run trains, its
observations carry the strategy, its folder is one ``lili report`` reads and it resumes."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml
from test_jax_envs import CASES, _play_both
from test_jax_train import TINY

from lili import cli
from lili.agents.registry import config_for
from lili.envs.jax import JAX_ENVS, PointMass
from lili.envs.jax.wrappers import LastInteractionObservation, StrategyObservation
from lili.envs.wrappers import LastInteractionObservation as GymLast
from lili.envs.wrappers import OracleObservation
from lili.jax_train import JaxRuns

WRAPPERS = {
    "oracle": (OracleObservation, StrategyObservation),
    "oracle-last": (GymLast, LastInteractionObservation),
    "oracle-last-outcome": (lambda env: GymLast(env, outcome=True),
                            lambda env: LastInteractionObservation(env, outcome=True)),
}


@pytest.mark.parametrize(("case", "oracle"), [
    ("noise", "oracle"), ("history", "oracle"), ("drift-returns", "oracle"),
    ("switch", "oracle"), ("driving-2d-history", "oracle"),
    ("history-noise-mirrored", "oracle-last"), ("drift", "oracle-last"),
    ("switch", "oracle-last-outcome"), ("driving-2d", "oracle-last-outcome"),
])
def test_the_jax_oracles_observe_what_the_gymnasium_oracles_observe(case, oracle):
    """Observations (after reset, every step and every new interaction, the strategy part
    included), rewards and the partner's whole sequence, as in ``test_jax_envs``."""
    wrap_gym, wrap_jax = WRAPPERS[oracle]
    (gym_cls, jenv, _, _), kwargs, _ = CASES[case]
    assert wrap_jax(jenv).observation_shape == wrap_gym(gym_cls(**kwargs)).observation_space.shape
    outcomes, _, strategies = _play_both(case, wrap_gym=wrap_gym, wrap_jax=wrap_jax)
    # The compared observations changed their appended part: the strategy moved and the
    # interactions ended differently.
    assert len({tuple(s) for s in strategies}) >= 2 and len(set(outcomes)) >= 2


@dataclass(frozen=True)
class _NoStrategy(PointMass):
    """Point Mass with its strategy hidden: a JAX env that reports none."""

    strategy_shape: tuple[int, ...] = ()


@pytest.mark.parametrize("wrapper", [StrategyObservation, LastInteractionObservation])
def test_an_env_without_a_strategy_is_refused(wrapper):
    with pytest.raises(ValueError, match=r"needs the partner's true strategy, and JAX env "
                                         r"_NoStrategy reports none .*allowed: a JAX env with"):
        wrapper(_NoStrategy())


@pytest.mark.parametrize("wrapper", [StrategyObservation, LastInteractionObservation])
def test_an_env_with_a_non_flat_observation_is_refused(wrapper):
    with pytest.raises(ValueError, match=r"needs a flat observation; got shape \(2, 1\); "
                                         r"allowed: a JAX env whose observation has one axis"):
        wrapper(PointMass(observation_shape=(2, 1)))


def test_the_oracle_on_an_env_without_a_strategy_is_one_clear_error(tmp_path, capsys):
    assert cli.main(["train", "Pendulum-v1", "--algo", "oracle", "--backend", "jax", "--out",
                     str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("lili: error:") and len(err.splitlines()) == 1
    assert "'Pendulum-v1' has no JAX version" in err and "lili/PointMass-v0" in err
    assert not (tmp_path / "r").exists()


def test_every_jax_env_observes_as_its_gymnasium_env_for_the_oracles():
    """Each JAX env wrapped for either Oracle observes as many numbers as its Gymnasium env
    wrapped so (what ``JaxRuns`` demands before it trains)."""
    for env_id, cls in JAX_ENVS.items():
        for oracle in ("oracle", "oracle-last", "oracle-last-outcome"):
            wrap_gym, wrap_jax = WRAPPERS[oracle]
            want = wrap_gym(gym.make(env_id).unwrapped).observation_space.shape
            assert wrap_jax(cls()).observation_shape == want, (env_id, oracle)


@pytest.mark.slow
@pytest.mark.parametrize("algo", ["oracle", "oracle-last"])
def test_the_oracles_train_with_the_strategy_in_their_observations(algo):
    """Influence Switch (strategy: the mode's one-hot), 5 interactions of 4 steps; the buffer
    holds what the agent observed: the interaction's strategy (Oracle) or the last one's
    (zeros in interaction 0) and that interaction's last observation and action."""
    runs = JaxRuns(algo, "influence-switch", [0, 1], config_for(algo, TINY))
    rows = runs.train(5)
    obs = np.asarray(runs.stacked.arrays["obs"])
    act = np.asarray(runs.stacked.arrays["act"])
    nxt = np.asarray(runs.stacked.arrays["next_obs"])
    for j in range(2):
        assert "critic_loss" in rows[j][-1]
        modes = [r["strategy_id"] for r in rows[j]]
        for i, row in enumerate(rows[j]):
            n = row["length"]
            if algo == "oracle":
                np.testing.assert_array_equal(obs[j, i, :n, 1:], np.tile(row["strategy"], (n, 1)))
                continue
            m = rows[j][i - 1]["length"] if i else 0
            last = (np.zeros(5, np.float32) if i == 0 else np.concatenate(
                [rows[j][i - 1]["strategy"], nxt[j, i - 1, m - 1, :1],
                 np.asarray(runs.agent.scale_action(act[j, i - 1, m - 1]))]))
            np.testing.assert_allclose(obs[j, i, :n, 1:], np.tile(last, (n, 1)), atol=1e-6)
        assert len(set(modes)) >= 2, modes


def _train(tmp_path: Path, *extra: str, out: str, n: int) -> int:
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump(config_for("oracle", TINY)))
    return cli.main(["train", "point-mass", "--algo", "oracle", "--backend", "jax",
                     "--env-kwarg", "step_noise=0.4", "--seeds", "0-1", "--interactions",
                     str(n), "--config", str(config), "--out", str(tmp_path / out),
                     "--no-progress", *extra])


def _rows(run: Path) -> list[dict[str, str]]:
    with (run / "metrics.csv").open() as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_an_oracle_group_writes_run_folders_that_resume_and_report(tmp_path, capsys):
    """``lili train --algo oracle --backend jax``: stopped at 4 and resumed to 7, each run's
    metrics are those of the group trained to 7 at once; ``lili report`` reads the folders."""
    assert _train(tmp_path, out="whole", n=7) == 0
    assert _train(tmp_path, out="parts", n=4) == 0
    assert _train(tmp_path, "--resume", out="parts", n=7) == 0
    assert "resumed at interaction 4" in capsys.readouterr().out
    for seed in (0, 1):
        whole = tmp_path / "whole" / "PointMass-v0" / "oracle" / f"seed_{seed}"
        parts = _rows(tmp_path / "parts" / "PointMass-v0" / "oracle" / f"seed_{seed}")
        rows = _rows(whole)
        assert len(rows) == len(parts) == 7 and rows[0].keys() == parts[0].keys()
        assert "strategy_0" in rows[0]
        for a, b in zip(rows, parts, strict=True):
            for column in a:
                if column != "wall_time" and a[column] != b[column]:
                    np.testing.assert_allclose(float(b[column]), float(a[column]), rtol=1e-4,
                                               atol=1e-5, err_msg=column)
        config = yaml.safe_load((whole / "config.yaml").read_text())
        assert config["backend"] == "jax" and config["algo"] == "oracle"
        assert json.loads((whole / "summary.json").read_text())["interactions"] == 7
    assert cli.main(["report", str(tmp_path / "whole"), "--out", str(tmp_path / "report")]) == 0
    assert "oracle" in capsys.readouterr().out


def test_the_strategy_part_of_a_jax_oracle_observation_is_the_interaction_strategy():
    """Unjitted, one step: after an interaction's last step the env already holds the next
    strategy; the step's observation still carries the one it was played under."""
    env = StrategyObservation(PointMass())
    params = env.params(horizon=1)
    obs, state = env.reset_with(PointMass().reset_draws(jax.random.PRNGKey(0), params),
                                params)
    before = np.asarray(env.info(state, params)["strategy"])
    np.testing.assert_array_equal(np.asarray(obs)[2:], before)
    nxt, state, _, done, _ = env.step_with(PointMass().update_draws(
        jax.random.PRNGKey(1), params), state, jnp.array([1.0, 0.0]), params)
    after = np.asarray(env.info(state, params)["strategy"])
    assert bool(done) and not np.allclose(before, after)
    np.testing.assert_array_equal(np.asarray(nxt)[2:], before)
    first, _ = env.next_interaction(None, state, params)
    np.testing.assert_array_equal(np.asarray(first)[2:], after)
