"""Several seeds in one program (``jax.vmap`` of the pure update block) agree with single-seed
runs to float tolerance."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from lili.agents import make_agent
from lili.agents.multiseed import stack, unstack, update_blocks
from lili.agents.registry import config_for
from lili.config import AgentConfig
from lili.train import Stream, interaction_keys, train

CONFIG = AgentConfig(hidden=(32, 32), enc_hidden=(16, 16), latent_dim=3, warmup_interactions=3,
                     batch_interactions=8, per_interaction=4, updates_per_step=0.2)


# LILI is slow: its vmapped block meets the single-seed one by default in tests/test_many.py
# (a LILI group against the runs alone).
@pytest.mark.parametrize("algo", ["sac", pytest.param("lili", marks=pytest.mark.slow)])
def test_two_seeds_in_one_program_match_two_single_seed_runs(algo):
    config = config_for(algo, CONFIG)
    agents = [make_agent(algo, "lili/PointMass-v0", config, seed) for seed in (0, 1)]
    streams = [Stream.for_agent(a, a.env) for a in agents]
    for a, s in zip(agents, streams, strict=True):
        train(a, s, 4)  # warm-up, normaliser, one block each
    states = [a.state for a in agents]
    core = agents[0].core
    assert core == agents[1].core  # same maths: one compiled program serves both
    stacked = stack(states)
    arrays = stack([s.buffer.arrays for s in streams])
    counts = jnp.array([s.count for s in streams], jnp.int32)
    single = list(states)
    for block in range(3):
        keys = [interaction_keys(a.seed, 10 + block)[1] for a in agents]
        stacked, metrics = update_blocks(core, stacked, arrays, counts, jnp.stack(keys))
        for j, s in enumerate(streams):
            single[j], m = core.jit_block(single[j], s.buffer.arrays, jnp.int32(s.count),
                                          keys[j])
            np.testing.assert_allclose(np.asarray(metrics["critic_loss"][j]),
                                       np.asarray(m["critic_loss"]), rtol=1e-4, atol=1e-6)
    for j, state in enumerate(unstack(stacked, 2)):
        for got, want in zip(jax.tree_util.tree_leaves(state),
                             jax.tree_util.tree_leaves(single[j]), strict=True):
            np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-4, atol=1e-5)
    # The two seeds really are different runs.
    assert not np.allclose(np.asarray(jax.tree_util.tree_leaves(single[0].actor)[0]),
                           np.asarray(jax.tree_util.tree_leaves(single[1].actor)[0]))
