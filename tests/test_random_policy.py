"""The random baseline: uniform actions from the caller's key, no learning, same run folder."""

from __future__ import annotations

import gymnasium as gym
import jax
import numpy as np

import lili.envs  # noqa: F401
from lili.agents import make_agent
from lili.train import Stream, train


def test_random_policy_is_uniform_reproducible_and_never_learns() -> None:
    agent = make_agent("random", gym.make("lili/Driving2D-v0"), {"warmup_interactions": 2}, 0)
    before = jax.tree_util.tree_map(np.asarray, agent.state.actor)
    rows = train(agent, Stream.for_agent(agent, agent.env), 6)
    assert all("critic_loss" not in r for r in rows)  # no update ever ran
    after = jax.tree_util.tree_map(np.asarray, agent.state.actor)
    assert all(np.array_equal(a, b) for a, b in zip(jax.tree_util.tree_leaves(before),
                                                      jax.tree_util.tree_leaves(after),
                                                      strict=True))
    obs = np.zeros(agent.obs_dim, np.float32)
    keys = jax.random.split(jax.random.PRNGKey(3), 400)
    acts = np.array([agent.predict(obs, key=k)[0] for k in keys]).ravel()
    assert acts.min() >= -1.0 and acts.max() <= 1.0
    # U(-1, 1) has mean 0 and standard deviation 1/sqrt(3) = 0.577.
    assert abs(acts.mean()) < 0.1 and abs(acts.std() - 0.577) < 0.05
    assert np.array_equal(agent.predict(obs, key=keys[0])[0], agent.predict(obs, key=keys[0])[0])
    again = make_agent("random", gym.make("lili/Driving2D-v0"), {"warmup_interactions": 2}, 0)
    rows_again = train(again, Stream.for_agent(again, again.env), 6)
    assert [r["return"] for r in rows_again] == [r["return"] for r in rows]
