"""The contract every agent keeps, one test class per algo (as Stable-Baselines3's tests
run one list of models through the same checks): save/load round trip, same seed same numbers
and resume equivalence, another seed other numbers, action bounds, predict shapes, a bad
observation, and a run folder that the report reader reads back."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest
from gymnasium import spaces

from lili.agents import ActingState, load_agent, make_agent
from lili.agents.registry import CORE_ALGOS as ALGOS  # the contrib algos: tests/test_contrib.py
from lili.agents.registry import config_for
from lili.config import AgentConfig
from lili.envs import RepeatedInteractionEnv
from lili.report import load_run
from lili.runs import RunLogger, metric_columns, resume_run
from lili.train import Stream, train

TINY_SLAC = {"z1_dim": 4, "z2_dim": 4, "feature_dim": 4, "model_hidden": [8],
             "sequence_length": 2, "model_batch": 4, "pretrain_steps": 2}
# Tiny networks and a short warm-up: the checks are about plumbing, not learning.
CONFIG = AgentConfig(hidden=(16, 16), enc_hidden=(8, 8), latent_dim=2, warmup_interactions=2,
                     batch_interactions=4, per_interaction=2, encoder_transitions=3,
                     checkpoint_every=2,
                     extra={"slac": TINY_SLAC, "slac-obs-critic": TINY_SLAC,
                            "slac-frame-actor": TINY_SLAC, "slac-mean-critic": TINY_SLAC,
                            "slac-frame-critic": TINY_SLAC,
                            "lilac": {"prior_window": 1}})
"""One config for every algo; each is made with the part it reads (``config_for``)."""
N = 5  # interactions per run


class Side:
    """The partner waits on one side and moves to the side the ego ended on."""

    strategy_space = spaces.Box(-1, 1, (1,), np.float32)

    def reset(self, rng):
        self.side = float(rng.choice([-1.0, 1.0]))

    def strategy(self):
        return np.array([self.side], np.float32)

    def strategy_id(self):
        return int(self.side > 0)

    def update(self, outcome, rng):
        self.side = 1.0 if outcome > 0 else -1.0


class Asymmetric(RepeatedInteractionEnv):
    """Two-dimensional actions with bounds that are neither symmetric nor [-1, 1]."""

    def __init__(self, render_mode=None):
        super().__init__(render_mode)
        self.horizon, self.partner = 4, Side()
        self.observation_space = spaces.Box(-5, 5, (2,), np.float32)
        self.action_space = spaces.Box(np.array([-2.0, 0.0], np.float32),
                                       np.array([1.0, 3.0], np.float32))

    def _begin(self):
        self.x = np.zeros(2, np.float32)
        return self.x.copy()

    def _step(self, action):
        self.x = np.clip(self.x + 0.1 * (action - np.array([-0.5, 1.5])), -5, 5).astype(
            np.float32)
        return self.x.copy(), -float(abs(self.x[0] - self.partner.side)), False

    def _outcome(self):
        return float(self.x[0])


def _run(algo, tmp, seed=0, n=N, stop_at=None):
    """Train ``n`` interactions with a run folder under ``tmp``; with ``stop_at``, train that
    many, then resume from the folder in a fresh agent for the rest. Returns (agent, rows)."""
    folder = tmp / f"{algo}_{seed}_{stop_at}"
    agent = make_agent(algo, Asymmetric(), config_for(algo, CONFIG), seed)
    stream = Stream.for_agent(agent, agent.env)
    sd = 1
    first = stop_at if stop_at is not None else n
    logger = RunLogger(folder, {"algo": algo}, sd, CONFIG.checkpoint_every)
    rows = train(agent, stream, first, logger=logger)
    logger.close()
    if stop_at is None:
        return agent, rows, folder
    again = make_agent(algo, Asymmetric(), config_for(algo, CONFIG), seed)
    stream2 = Stream.for_agent(again, again.env)
    start = resume_run(folder, again, stream2, sd)
    assert start == stop_at // CONFIG.checkpoint_every * CONFIG.checkpoint_every
    logger = RunLogger(folder, {"algo": algo}, sd, CONFIG.checkpoint_every, start)
    rows = rows[:start] + train(again, stream2, n - start, logger=logger)
    logger.close()
    return again, rows, folder


def _numbers(rows):
    keys = ("return", "critic_loss", "actor_loss", "alpha", "rep_loss", "q", "entropy")
    return [[r.get(k, np.nan) for k in keys] for r in rows]


@pytest.fixture(scope="class")
def run(request, tmp_path_factory):
    """The class's algo trained for ``N`` interactions: (agent, rows, run folder)."""
    algo = request.cls.algo
    return _run(algo, tmp_path_factory.mktemp(f"contract_{algo}"))


class Contract:
    """The checks, for one algo (``algo``); each algo's class is made below.

    One class per algo, not one module fixture training every algo: pytest-xdist's ``--dist
    loadscope`` (``make test``) runs each class whole on one worker, so the algos' runs (mostly
    compiling) spread over both workers instead of queueing on one.
    """

    algo: ClassVar[str]

    def test_save_load_round_trip(self, run, tmp_path):
        agent = run[0]
        path = agent.save(tmp_path / "agent.msgpack")
        loaded = load_agent(path, Asymmetric())
        assert type(loaded) is type(agent) and loaded.algo == agent.algo
        assert loaded.config == agent.config and loaded.num_interactions == N
        import jax

        same = jax.tree_util.tree_map(lambda a, b: bool(np.array_equal(a, b)), agent.state,
                                      loaded.state)
        assert all(jax.tree_util.tree_leaves(same))
        obs = np.linspace(0.3, -0.2, agent.obs_dim).astype(np.float32)  # the Oracle's is longer
        state = agent.next_state(agent.stream.buffer)
        a1, _ = agent.predict(obs, state)
        a2, _ = loaded.predict(obs, state)
        np.testing.assert_array_equal(a1, a2)

    def test_other_seed_other_numbers(self, run, tmp_path):
        """(The same seed giving the same numbers: the resume test below, whose fresh agents of
        the same seed reproduce every number of the run.)"""
        base = _numbers(run[1])
        other = _numbers(_run(self.algo, tmp_path, seed=1)[1])
        assert not np.array_equal(np.asarray(base)[:, 0], np.asarray(other)[:, 0])

    def test_resume_gives_the_numbers_of_an_uninterrupted_run(self, run, tmp_path):
        """A fresh agent of the same seed plays the first interactions, another resumes from its
        checkpoint: every number equals the uninterrupted run's (so the same seed gives the same
        numbers, and resuming changes none)."""
        _, rows, folder = _run(self.algo, tmp_path, stop_at=3)
        np.testing.assert_array_equal(np.asarray(_numbers(rows)), np.asarray(_numbers(run[1])))
        # The folder holds every row once, in order (the killed run's row 3 was cut back).
        assert load_run_like(folder)["interaction"].tolist() == list(range(N))

    def test_actions_stay_in_the_env_bounds_and_shapes_hold(self, run):
        agent = run[0]
        env = Asymmetric()
        rng = np.random.default_rng(0)
        state = agent.initial_state()
        assert isinstance(state, ActingState) and np.asarray(state.z).shape == (agent.latent_dim,)
        if self.algo != "lilac":  # z^1 = 0; LILAC starts from its prior's mean (test_lilac.py)
            assert not np.asarray(state.z).any()
        for t in range(env.horizon):
            action, state = agent.predict(rng.normal(0, 3, agent.obs_dim).astype(np.float32),
                                          state, deterministic=False)
            assert action.shape == (2,) and action.dtype == np.float32
            assert env.action_space.contains(action), action
            assert int(state.t) == t + 1
        state = agent.next_state(agent.stream.buffer)
        assert np.asarray(state.z).shape == (agent.latent_dim,) and int(state.t) == 0

    def test_a_bad_observation_shape_is_one_clear_error(self, run):
        agent = run[0]
        d = agent.obs_dim
        with pytest.raises(ValueError,
                           match=rf"observation has shape \({d + 1},\); expected \({d},\)"):
            agent.predict(np.zeros(d + 1, np.float32))
        with pytest.raises(ValueError, match="state=.* is invalid for .*allowed: None or the "
                                             "ActingState"):
            agent.predict(np.zeros(d, np.float32), state=(0, 1))

    def test_the_report_reader_reads_back_what_the_run_logger_wrote(self, run):
        agent, rows, folder = run
        (folder / "config.yaml").write_text(
            f"env: contract/Asymmetric-v0\nenv_kwargs: {{}}\nalgo: {self.algo}\nseed: 0\n"
            f"interactions: {N}\nagent: {{}}\n")
        loaded = load_run(folder)
        np.testing.assert_allclose(loaded.metrics["return"], [r["return"] for r in rows],
                                   rtol=1e-5)
        assert loaded.metrics["interaction"].tolist() == list(range(N))
        assert list(loaded.metrics)[: len(metric_columns(1))] == metric_columns(1)
        if "critic_loss" in rows[-1]:
            np.testing.assert_allclose(loaded.metrics["critic_loss"][-1],
                                       rows[-1]["critic_loss"], rtol=1e-5)


def load_run_like(folder):
    import csv

    with (folder / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    return {"interaction": np.array([int(r["interaction"]) for r in rows])}


# One test class per algo of the registry (a new algo gets its class without an edit here).
for _algo in ALGOS:
    _name = "Test_" + _algo.replace("-", "_")
    globals()[_name] = type(_name, (Contract,), {"algo": _algo, "__module__": __name__})
