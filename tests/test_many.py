"""Many runs in one program (``lili.many``, ``lili train --seeds``): each run of a group equals
the same run trained alone (bit for bit on a CPU, where the suite runs), interactions that end
early wait, the update block of a group equals each seed's own, a killed group resumes to the
same numbers, and a group that cannot share one program is refused before anything is written."""

from __future__ import annotations

import csv
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml
from gymnasium import spaces

from lili import cli
from lili.agents import make_agent
from lili.agents.multiseed import stack, unstack, update_blocks
from lili.agents.registry import config_for
from lili.buffer import _available_memory, buffer_nbytes
from lili.config import AgentConfig
from lili.envs import RepeatedInteractionEnv
from lili.many import check_group, group_streams, train_many
from lili.runs import RunLogger
from lili.train import Stream, interaction_keys, train

FAST = {"hidden": [32, 32], "enc_hidden": [16, 16], "latent_dim": 3, "warmup_interactions": 3,
        "checkpoint_every": 4, "batch_interactions": 8, "per_interaction": 4,
        "random_interactions": 0.3}
CONFIG = AgentConfig.from_dict(FAST)
SEEDS = (0, 1, 2)
# On a CPU the group maps its runs one after another (lili.agents.multiseed.over_seeds): its
# numbers are the runs' alone, bit for bit; on an accelerator vmap agrees to float tolerance.
EXACT = jax.default_backend() == "cpu"


def _same_rows(alone: list[dict], together: list[dict]) -> None:
    assert [r["interaction"] for r in alone] == [r["interaction"] for r in together]
    for a, b in zip(alone, together, strict=True):
        assert a.keys() == b.keys()
        for k in a:
            if k == "wall_time":
                continue
            if EXACT:
                assert np.array_equal(np.asarray(b[k]), np.asarray(a[k])), k
            elif isinstance(a[k], float):
                np.testing.assert_allclose(b[k], a[k], rtol=1e-3, atol=1e-5, err_msg=k)
            elif isinstance(a[k], np.ndarray):
                np.testing.assert_allclose(b[k], a[k], rtol=1e-4, atol=1e-5, err_msg=k)
            else:
                assert a[k] == b[k], k


def _same_state(a: Any, b: Any) -> None:
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        if EXACT:
            assert np.array_equal(np.asarray(y), np.asarray(x))
        else:
            np.testing.assert_allclose(np.asarray(y), np.asarray(x), rtol=1e-3, atol=1e-4)


def _alone_and_together(algo: str, env: Any, n: int):
    alone = []
    for seed in SEEDS:
        agent = make_agent(algo, env(), config_for(algo, CONFIG), seed)
        alone.append((agent, train(agent, Stream.for_agent(agent, agent.env), n)))
    agents = [make_agent(algo, env(), config_for(algo, CONFIG), seed) for seed in SEEDS]
    rows = train_many(agents, group_streams(agents), n)
    return alone, agents, rows


# LILI by default: its programs (one run, a group of three, on Driving (2D) with FAST) are the
# ones test_a_killed_group_resumes_to_the_same_numbers trains through `lili train`, so this file
# compiles them once. SAC's group meets its runs alone by default in
# test_interactions_that_end_early_wait_for_the_group; SAC here and LILAC are slow.
@pytest.mark.parametrize("algo", [pytest.param("sac", marks=pytest.mark.slow), "lili",
                                  pytest.param("lilac", marks=pytest.mark.slow)])
def test_each_run_of_a_group_equals_the_run_trained_alone(algo):
    alone, agents, rows = _alone_and_together(algo, lambda: "lili/Driving2D-v0", 5)
    for (single, single_rows), agent, group_rows in zip(alone, agents, rows, strict=True):
        _same_rows(single_rows, group_rows)
        _same_state(single.state, agent.state)
        assert agent.stream.count == single.stream.count == 5
    # The runs are different runs (seeds), not one run copied.
    first = [np.asarray(jax.tree_util.tree_leaves(a.state.actor)[0]) for a in agents]
    assert not np.allclose(first[0], first[1])


class _EarlyEnd(RepeatedInteractionEnv):
    """Walk on a line; the interaction ends as soon as |x| > 0.5 or after 6 steps, so runs of
    one group end their interactions at different steps."""

    def __init__(self) -> None:
        super().__init__()
        self.horizon = 6
        self.observation_space = spaces.Box(-3.0, 3.0, shape=(1,), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.partner = _Flip()
        self.x = 0.0

    def _begin(self) -> np.ndarray:
        self.x = float(self.np_random.uniform(-0.1, 0.1))
        return np.array([self.x], np.float32)

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        self.x = float(np.clip(self.x + 0.3 * action[0], -3.0, 3.0))
        return np.array([self.x], np.float32), -abs(self.x - self.partner.z), abs(self.x) > 0.5

    def _outcome(self) -> Any:
        return self.x > 0


class _Flip:
    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def reset(self, rng: np.random.Generator) -> None:
        self.z = 1.0 if rng.random() < 0.5 else -1.0

    def strategy(self) -> np.ndarray:
        return np.array([self.z], np.float32)

    def strategy_id(self) -> int:
        return int(self.z > 0)

    def update(self, outcome: Any, rng: np.random.Generator) -> None:
        self.z = -self.z


def test_interactions_that_end_early_wait_for_the_group():
    alone, agents, rows = _alone_and_together("sac", _EarlyEnd, 6)
    for (single, single_rows), agent, group_rows in zip(alone, agents, rows, strict=True):
        _same_rows(single_rows, group_rows)
        _same_state(single.state, agent.state)
    lengths = np.array([[r["length"] for r in run] for run in rows])
    # Within some interaction the runs ended at different steps, and some ended early.
    assert (lengths.min(0) != lengths.max(0)).any() and lengths.min() < 6


# On the programs the tests above compiled: SAC's on the early-ending env, LILI's on Driving (2D).
@pytest.mark.parametrize("algo", ["sac", "lili"])
def test_update_blocks_match_each_seeds_own_block(algo):
    """:func:`lili.agents.multiseed.update_blocks`, the vmapped block `train_many` runs, against
    each seed's own :meth:`SACCore.block` for three blocks: the same losses and states."""
    env = _EarlyEnd if algo == "sac" else (lambda: "lili/Driving2D-v0")
    agents = [make_agent(algo, env(), config_for(algo, CONFIG), seed) for seed in SEEDS]
    streams = [Stream.for_agent(a, a.env) for a in agents]
    for a, s in zip(agents, streams, strict=True):
        train(a, s, 4)  # warm-up, normaliser, one block each
    core = agents[0].core
    assert all(a.core == core for a in agents)  # same maths: one compiled program serves all
    stacked = stack([a.state for a in agents])
    arrays = stack([s.buffer.arrays for s in streams])
    counts = jnp.array([s.count for s in streams], jnp.int32)
    single = [a.state for a in agents]
    for block in range(3):
        keys = [interaction_keys(a.seed, 10 + block)[1] for a in agents]
        stacked, metrics = update_blocks(core, stacked, arrays, counts, jnp.stack(keys))
        for j, s in enumerate(streams):
            single[j], m = core.jit_block(single[j], s.buffer.arrays, jnp.int32(s.count),
                                          keys[j])
            np.testing.assert_allclose(np.asarray(metrics["critic_loss"][j]),
                                       np.asarray(m["critic_loss"]), rtol=0 if EXACT else 1e-4,
                                       atol=0 if EXACT else 1e-6)
    for state, want in zip(unstack(stacked, len(SEEDS)), single, strict=True):
        _same_state(want, state)
    # The seeds really are different runs.
    assert not np.allclose(np.asarray(jax.tree_util.tree_leaves(single[0].actor)[0]),
                           np.asarray(jax.tree_util.tree_leaves(single[1].actor)[0]))


def _csv_rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(f)]


def _train(out, cfg_file, extra=(), n=9):
    return cli.main(["train", "driving-2d", "--algo", "lili", "--interactions", str(n),
                     "--out", str(out), "--config", str(cfg_file), "--no-progress", *extra])


def test_a_killed_group_resumes_to_the_same_numbers(tmp_path, monkeypatch):
    cfg = tmp_path / "fast.yaml"
    cfg.write_text(yaml.safe_dump(FAST))
    assert _train(tmp_path / "full", cfg, ["--seeds", "0-2"]) == 0
    original_log = RunLogger.log

    def dying_log(self, row, agent, stream):
        original_log(self, row, agent, stream)
        if row["interaction"] == 6 and agent.seed == 2:  # two after the checkpoint at 4
            raise KeyboardInterrupt

    monkeypatch.setattr(RunLogger, "log", dying_log)
    assert _train(tmp_path / "cut", cfg, ["--seeds", "0-2"]) == 130
    monkeypatch.setattr(RunLogger, "log", original_log)
    assert _train(tmp_path / "cut", cfg, ["--seeds", "0-2", "--resume"]) == 0
    for seed in SEEDS:
        run = f"Driving2D-v0/lili/seed_{seed}/metrics.csv"
        assert _csv_rows(tmp_path / "cut" / run) == _csv_rows(tmp_path / "full" / run)
    # And a run of the group is the run `lili train --seed` gives alone (bit for bit on a CPU).
    assert _train(tmp_path / "one", cfg, ["--seed", "1"]) == 0
    one = _csv_rows(tmp_path / "one" / "Driving2D-v0/lili/seed_1/metrics.csv")
    group = _csv_rows(tmp_path / "full" / "Driving2D-v0/lili/seed_1/metrics.csv")
    assert [r.keys() for r in one] == [r.keys() for r in group]
    for a, b in zip(one, group, strict=True):
        for k in a:
            if EXACT or a[k] == "" or b[k] == "":
                assert a[k] == b[k], k
            else:
                np.testing.assert_allclose(float(b[k]), float(a[k]), rtol=1e-3, atol=1e-5)


def test_a_group_that_cannot_share_a_program_is_refused():
    sac = make_agent("sac", "lili/PointMass-v0", config_for("sac", CONFIG), 0)
    lili = make_agent("lili", "lili/PointMass-v0", CONFIG, 1)
    with pytest.raises(ValueError, match="shares one algo: 'sac' and 'lili'"):
        check_group([sac, lili])
    short = make_agent("sac", _EarlyEnd(), config_for("sac", CONFIG), 1)
    with pytest.raises(ValueError, match="seed 1 has another observation size than seed 0"):
        check_group([sac, short])


@pytest.mark.parametrize("extra, message", [
    (["--seeds", "3-1"], "--seeds '3-1' is invalid; allowed: seeds and ranges such as 0-7"),
    (["--seeds", "0,0"], "names a seed twice"),
    (["--seeds", "0-99999"], "at most 4096 seeds"),
    (["--seeds", "0-1", "--algo", "slac"], "SLAC pretrains a model"),
    (["--seeds", "0-1", "--seed", "3"], "not allowed with argument"),
])
def test_bad_seeds_are_one_clear_error_and_write_nothing(tmp_path, capsys, extra, message):
    argv = ["train", "point-mass", "--interactions", "3", "--out", str(tmp_path / "out"),
            "--no-progress", *extra]
    assert cli.main(argv) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_group_too_big_for_memory_is_refused_before_it_is_allocated(tmp_path, capsys):
    free = _available_memory()
    per = buffer_nbytes(1, 50, 2, 2)  # Point Mass: horizon 50, 2 observations, 2 actions
    capacity = int(0.3 * free / per)  # one run fits in half the free memory, two do not
    cfg = tmp_path / "big.yaml"
    cfg.write_text(yaml.safe_dump({"buffer_capacity": capacity}))
    assert cli.main(["train", "point-mass", "--seeds", "0-1", "--interactions", "3", "--out",
                     str(tmp_path / "out"), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "a group of 2 runs needs" in err and "at most 1 runs of this size" in err
    assert not (tmp_path / "out").exists()
