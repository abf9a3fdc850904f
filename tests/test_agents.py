"""Agents: the critic target at the interaction boundary, acting, save/load, bad input."""

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import lili.envs  # noqa: F401  (registers the envs)
from lili.agents import LILI, SAC, CheckpointError, Oracle, make_agent
from lili.agents.registry import config_for
from lili.config import AgentConfig, load_config
from lili.dists import tanh_gaussian

SMALL = AgentConfig(hidden=(32, 32), enc_hidden=(16, 16), latent_dim=3)
SMALL_SAC = config_for("sac", SMALL)  # SAC and the Oracle read no latent field
GAMMA = SMALL.gamma


def _batch(agent, rng):
    """A hand-made batch: 2 interactions x 3 transitions; transition 2 is each one's last."""
    b, m, h, od, ad = 2, 3, agent.horizon, agent.obs_dim, agent.act_dim
    f = lambda *s: jnp.asarray(rng.normal(size=s), jnp.float32)  # noqa: E731
    t = jnp.broadcast_to(jnp.arange(h), (b, 2, h))
    window = {"obs": f(b, 2, h, od), "act": f(b, 2, h, ad), "rew": f(b, 2, h),
              "next_obs": f(b, 2, h, od), "valid": jnp.ones((b, 2, h), bool), "t": t,
              "last": t == h - 1, "weight": jnp.ones((b, 2, h))}
    return {"obs": f(b, m, od), "act": f(b, m, ad), "rew": f(b, m), "next_obs": f(b, m, od),
            "t": jnp.array([[3, 10, h - 1], [0, 7, h - 1]]),
            "last": jnp.array([[False, False, True], [False, False, True]]),
            "next_first_obs": f(b, od), "index": jnp.array([5, 9]), "window": window}


def _manual_target(agent, state, batch, key, boundary_latent):
    """y computed from first principles for each transition (see DESIGN 'LILI semantics')."""
    core, norm = agent.core, state.norm
    h = agent.horizon
    enc_t = state.target["encoder"]
    prev = {k: v[:, 0:1] for k, v in batch["window"].items()}
    cur = {k: v[:, 1:2] for k, v in batch["window"].items()}
    z_k = core.encoder.apply(enc_t, core._features(norm, prev), prev["weight"])
    z_k1 = core.encoder.apply(enc_t, core._features(norm, cur), cur["weight"])
    rows = []
    for i in range(2):
        row = []
        for j in range(3):
            if batch["last"][i, j]:
                s, phase = batch["next_first_obs"][i], 0.0
                z = {"influence": z_k1, "same_z": z_k}.get(boundary_latent, z_k)[i]
            else:
                s, phase = batch["next_obs"][i, j], (batch["t"][i, j] + 1) / h
                z = z_k[i]
            s = (s - norm.obs_mean) / norm.obs_std
            row.append(jnp.concatenate([s, jnp.array([phase]), z]))
        rows.append(jnp.stack(row))
    x = jnp.stack(rows)
    mean, log_std = core.actor.apply(state.actor, x)
    a, logp = tanh_gaussian(mean, log_std, key)
    v = core.critic.apply(state.target["critic"], x, a).min(0) - jnp.exp(
        state.log_alpha) * logp
    y = batch["rew"] + GAMMA * v
    if boundary_latent == "cut":
        y = jnp.where(batch["last"], batch["rew"], y)
    return y


@pytest.mark.parametrize("influence", [True, False])
def test_critic_target_at_the_boundary(influence):
    env = gym.make("lili/PointMass-v0")
    agent = LILI(env, SMALL, seed=1, influence=influence)
    assert agent.boundary == ("influence" if influence else "cut")
    # Make the target encoder differ from the online one: the target must use the target copy.
    state = agent.state.replace(target=dict(agent.state.target, encoder=jax.tree_util.tree_map(
        lambda p: p * 1.5 + 0.1, agent.state.target["encoder"])))
    batch = _batch(agent, np.random.default_rng(0))
    key = jax.random.PRNGKey(7)
    y = np.asarray(agent.core.critic_target(state, batch, key))
    want = _manual_target(agent, state, batch, key, "influence" if influence else "cut")
    np.testing.assert_allclose(y, np.asarray(want), rtol=1e-5, atol=1e-5)
    if not influence:
        # LILI (no influence) is greedy: the return stops at the end of the interaction.
        np.testing.assert_array_equal(y[:, 2], np.asarray(batch["rew"][:, 2]))
    else:
        # The influence path: at the boundary the latent is E(tau^k), not the unchanged z^k.
        other = _manual_target(agent, state, batch, key, "same_z")
        assert not np.allclose(y[:, 2], np.asarray(other[:, 2]))
        np.testing.assert_allclose(y[:, :2], np.asarray(other[:, :2]), rtol=1e-5, atol=1e-5)


def test_same_z_reading_is_available_as_an_option():
    env = gym.make("lili/PointMass-v0")
    agent = LILI(env, SMALL.replace(boundary="same_z"), seed=1, influence=False)
    batch = _batch(agent, np.random.default_rng(0))
    key = jax.random.PRNGKey(2)
    y = agent.core.critic_target(agent.state, batch, key)
    want = _manual_target(agent, agent.state, batch, key, "same_z")
    np.testing.assert_allclose(np.asarray(y), np.asarray(want), rtol=1e-5, atol=1e-5)


def test_sac_bootstraps_from_the_next_interaction():
    env = gym.make("lili/PointMass-v0")
    agent = SAC(env, SMALL_SAC, seed=0)
    batch = _batch(agent, np.random.default_rng(1))
    batch.pop("window")
    key = jax.random.PRNGKey(3)
    y = np.asarray(agent.core.critic_target(agent.state, batch, key))
    st, core = agent.state, agent.core
    x = jnp.concatenate([batch["next_first_obs"], jnp.zeros((2, 1))], -1)  # phase 0
    x = jnp.broadcast_to(x[:, None], (2, 3, 3))
    x_in = jnp.concatenate([batch["next_obs"], ((batch["t"] + 1) / agent.horizon)[..., None]], -1)
    x = jnp.where(batch["last"][..., None], x, x_in)
    mean, log_std = core.actor.apply(st.actor, x)
    a, logp = tanh_gaussian(mean, log_std, key)
    v = core.critic.apply(st.target["critic"], x, a).min(0) - jnp.exp(st.log_alpha) * logp
    np.testing.assert_allclose(y, np.asarray(batch["rew"] + GAMMA * v), rtol=1e-5, atol=1e-5)
    # boundary_discount="horizon": an interaction that ended at step 20 of H still discounts
    # the next one as if it had run to H; a full-length one (t = H - 1) as before.
    early = dict(batch, t=batch["t"].at[1, 2].set(20))
    padded = SAC(env, SMALL_SAC.replace(boundary_discount="horizon"), seed=0)
    y_p = np.asarray(padded.core.critic_target(padded.state, early, key))
    discount = np.full((2, 3), GAMMA)
    discount[1, 2] = GAMMA ** (agent.horizon - 20)
    assert agent.horizon - 20 > 10  # the extra discount is large enough to see
    np.testing.assert_allclose(y_p, np.asarray(batch["rew"]) + discount * np.asarray(v),
                               rtol=1e-5, atol=1e-5)
    y_step = np.asarray(agent.core.critic_target(agent.state, early, key))
    np.testing.assert_allclose(y_step, y, rtol=1e-6)  # the paper's discount ignores t there


def test_oracle_sees_the_strategy_and_lili_does_not():
    env = gym.make("lili/PointMass-v0")
    oracle = Oracle(env, SMALL_SAC)
    assert oracle.obs_dim == 4
    assert LILI(gym.make("lili/PointMass-v0"), SMALL).obs_dim == 2


def test_load_rejects_corrupt_and_mismatched_files(tmp_path):
    env = gym.make("lili/PointMass-v0")
    path = SAC(env, SMALL_SAC).save(tmp_path / "sac.msgpack")
    with pytest.raises(CheckpointError, match="holds a 'sac' agent"):
        LILI.load(path, env)
    with pytest.raises(CheckpointError, match="obs_dim=2"):
        SAC.load(path, gym.make("lili/Driving2D-v0"))
    bad = tmp_path / "bad.msgpack"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="corrupt"):
        SAC.load(bad, env)
    truncated = tmp_path / "trunc.msgpack"
    truncated.write_bytes(path.read_bytes()[:-100])
    with pytest.raises(CheckpointError, match="corrupt"):
        SAC.load(truncated, env)
    with pytest.raises(CheckpointError, match="does not exist"):
        SAC.load(tmp_path / "missing.msgpack", env)


@pytest.mark.parametrize("bad, match", [
    ({"gamma": 1.5}, "gamma=1.5"),
    ({"boundary_discount": "episode"}, r"boundary_discount='episode'.*step or horizon"),
    ({"hidden": [0]}, "hidden"),
    ({"boundary": "sideways"}, "boundary='sideways'"),
    ({"latent_dim": 0}, "latent_dim=0"),
    ({"random_interactions": 1.5}, r"random_interactions=1.5.*\[0, 1\]"),
    ({"lr_actor": "fast"}, "lr_actor='fast'"),
    ({"warmup": 3}, "unknown config key"),
])
def test_bad_config_values_are_named(bad, match):
    with pytest.raises(ValueError, match=match):
        AgentConfig.from_dict(bad)


def test_load_config_errors(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("gamma: [1, 2\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_config(p)
    p.write_text("- 1\n- 2\n")
    with pytest.raises(ValueError, match="mapping"):
        load_config(p)
    p.write_text("gamma: 0.9\nhidden: [64, 64]\n")
    assert load_config(p).hidden == (64, 64)


def test_bad_env_and_algo():
    with pytest.raises(ValueError, match="unknown algo 'ppo'"):
        make_agent("ppo", gym.make("lili/PointMass-v0"))
    with pytest.raises(ValueError, match="action space"):
        SAC(gym.make("CartPole-v1"))
    with pytest.raises(ValueError, match="seed=-1"):
        SAC(gym.make("lili/PointMass-v0"), seed=-1)
