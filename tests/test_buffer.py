"""InteractionBuffer: storage, windows and the pure-JAX sampler."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from lili.buffer import InteractionBuffer, sample

# The agents call ``sample`` inside their jitted updates; jitted here too, each test compiles it
# once instead of dispatching (and compiling) its dozens of ops one by one on every call.
_sample_jit = jax.jit(sample, static_argnums=(3, 4, 5, 6))


def _traj(k: int, n: int, obs_dim: int = 2, act_dim: int = 1) -> dict:
    """Interaction k with n steps; every value encodes (k, t) so samples can be traced back."""
    t = np.arange(n, dtype=np.float32)
    obs = np.stack([np.full(n, k, np.float32), t] + [t] * (obs_dim - 2), -1)
    return {"obs": obs, "act": np.full((n, act_dim), k, np.float32), "rew": 1000 * k + t,
            "next_obs": obs + 0.5}


def _filled(count: int, capacity: int = 8, horizon: int = 5, lengths=None) -> InteractionBuffer:
    buf = InteractionBuffer(capacity, horizon, 2, 1)
    for k in range(count):
        n = horizon if lengths is None else lengths[k % len(lengths)]
        buf.add(_traj(k, n), np.array([k + 1, 0], np.float32))
    return buf


def _sample(buf, key, history, b=64, m=4):
    arrays = {k: jnp.asarray(v) for k, v in buf.arrays.items()}
    return jax.tree_util.tree_map(np.asarray, _sample_jit(arrays, jnp.int32(buf.count), key, b, m,
                                                          history))


def test_sample_shapes_and_consistency():
    buf = _filled(6, lengths=[5, 3, 4])
    batch = _sample(buf, jax.random.PRNGKey(0), history=1)
    assert batch["obs"].shape == (64, 4, 2) and batch["rew"].shape == (64, 4)
    k, t = batch["index"], batch["t"]
    # Interaction indices: k >= history, never beyond what is stored.
    assert k.min() >= 1 and k.max() <= 5
    # Each transition belongs to interaction k at step t, and t stays inside its length.
    np.testing.assert_array_equal(batch["rew"], 1000 * k[:, None] + t)
    lengths = np.array([5, 3, 4])[k % 3]
    assert (t < lengths[:, None]).all()
    np.testing.assert_array_equal(batch["last"], t == lengths[:, None] - 1)
    np.testing.assert_array_equal(batch["next_first_obs"][:, 0], k + 1)
    # The window holds interactions k-1 and k with their validity masks.
    win = batch["window"]
    assert win["obs"].shape == (64, 2, 5, 2)
    np.testing.assert_array_equal(win["obs"][:, 0, 0, 0], k - 1)
    np.testing.assert_array_equal(win["obs"][:, 1, 0, 0], k)
    np.testing.assert_array_equal(win["valid"][:, 1].sum(-1), lengths)


def test_sample_covers_all_steps_including_last_at_natural_rate():
    buf = _filled(4, horizon=10)
    batch = _sample(buf, jax.random.PRNGKey(1), history=0, b=512, m=8)
    counts = np.bincount(batch["t"].ravel(), minlength=10) / batch["t"].size
    assert set(np.unique(batch["index"])) == {0, 1, 2, 3}
    # Uniform over steps: the boundary is not oversampled (natural rate 1/H).
    np.testing.assert_allclose(counts, 0.1, atol=0.02)


def test_sample_is_a_function_of_the_key():
    buf = _filled(6)
    a = _sample(buf, jax.random.PRNGKey(3), 1)
    b = _sample(buf, jax.random.PRNGKey(3), 1)
    c = _sample(buf, jax.random.PRNGKey(4), 1)
    np.testing.assert_array_equal(a["rew"], b["rew"])
    assert not np.array_equal(a["rew"], c["rew"])


def test_ring_buffer_never_samples_evicted_predecessors():
    buf = _filled(20, capacity=8)
    batch = _sample(buf, jax.random.PRNGKey(0), history=2, b=256)
    k = batch["index"]
    # Stored: 12..19; with history 2 only k >= 14 has both predecessors stored.
    assert k.min() >= 14 and k.max() <= 19
    np.testing.assert_array_equal(batch["window"]["obs"][:, 0, 0, 0], k - 2)
    assert batch["window"]["valid"][:, 0].all()


def test_window_masks_missing_interactions():
    buf = _filled(2)
    w = buf.window(1, 3)
    assert w["obs"].shape == (3, 5, 2)
    assert not w["valid"][0].any() and w["valid"][1:].all()


def test_state_dict_round_trip_and_bad_length():
    buf = _filled(11, capacity=8)
    other = InteractionBuffer(8, 5, 2, 1)
    other.load_state_dict(buf.state_dict())
    assert other.count == 11
    for k in buf.arrays:
        np.testing.assert_array_equal(other.arrays[k], buf.arrays[k])
    with pytest.raises(ValueError, match="outside 1..5"):
        buf.add(_traj(0, 6), np.zeros(2, np.float32))
    with pytest.raises(ValueError, match="shape"):
        InteractionBuffer(8, 6, 2, 1).load_state_dict(buf.state_dict())


def test_subsampled_window_always_holds_the_last_step():
    buf = _filled(6, horizon=10, lengths=[10, 4, 1])
    arrays = {k: jnp.asarray(v) for k, v in buf.arrays.items()}
    batch = _sample_jit(arrays, jnp.int32(buf.count), jax.random.PRNGKey(5), 64, 2, 1, 5)
    win = jax.tree_util.tree_map(np.asarray, batch["window"])
    k = np.asarray(batch["index"])
    lengths = np.array([10, 4, 1])[np.stack([k - 1, k], -1) % 3]
    assert win["obs"].shape == (64, 2, 5, 2)
    # The last of the S steps is the interaction's last step; the others come before it.
    np.testing.assert_array_equal(win["t"][..., -1], lengths - 1)
    assert win["last"][..., -1].all()
    assert (win["t"][..., :-1] <= np.maximum(lengths - 2, 0)[..., None]).all()
    # Each gathered transition really is step t of its interaction.
    np.testing.assert_array_equal(win["rew"] % 1000, win["t"])
    owner = np.broadcast_to(np.stack([k - 1, k], -1)[..., None], win["t"].shape)
    np.testing.assert_array_equal(win["obs"][..., 0], owner)


def test_full_window_weights_match_the_expected_training_sample():
    from lili.buffer import pooling_weights

    buf = _filled(3, horizon=10, lengths=[10, 4, 1])
    w = buf.window(2, 3, steps=5)["weight"]
    # Interaction 0: 9 early steps share 4/5, the last weighs 1/5 (relative to a total of 5).
    np.testing.assert_allclose(w[0], [4 / 9] * 9 + [1.0])
    np.testing.assert_allclose(w[1], [4 / 3] * 3 + [1.0] + [0.0] * 6)
    np.testing.assert_allclose(w[2], [1.0] + [0.0] * 9)
    np.testing.assert_array_equal(buf.window(2, 3)["weight"], buf.window(2, 3)["valid"])
    # Monte Carlo: the mean over sampled windows matches the weighted mean over the full one.
    arrays = {k: jnp.asarray(v) for k, v in buf.arrays.items()}
    rews, idx = [], []
    for s in range(300):
        b = _sample_jit(arrays, jnp.int32(3), jax.random.PRNGKey(s), 8, 1, 1, 5)
        rews.append(np.asarray(b["window"]["rew"])[:, 1])
        idx.append(np.asarray(b["index"]))
    rews, idx = np.concatenate(rews), np.concatenate(idx)
    full = buf.window(2, 3, steps=5)
    for k in (1, 2):
        sampled = rews[idx == k]
        assert len(sampled) > 50
        want = (full["rew"][k] * full["weight"][k]).sum() / full["weight"][k].sum()
        np.testing.assert_allclose(sampled.mean(), want, rtol=0.02)
    assert pooling_weights(np.ones((1, 4), bool), np.array([[0, 0, 0, 1]], bool), None).sum() == 4
