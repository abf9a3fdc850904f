"""Agents: the critic target at the interaction boundary, acting, save/load, bad input."""

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import lili.envs  # noqa: F401  (registers the envs)
from lili.agents import LILI, SAC, CheckpointError, Oracle, make_agent
from lili.agents.lili import PROBES, bottleneck_kl, decoder_loss, window_part
from lili.config import AgentConfig, load_config
from lili.dists import tanh_gaussian

SMALL = AgentConfig(hidden=(32, 32), enc_hidden=(16, 16), latent_dim=3)
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


def _point_mass_lili(**changes):
    """A small Point Mass LILI (seed 3) with the config ``changes``, its core, its state and a
    hand-made batch."""
    agent = LILI(gym.make("lili/PointMass-v0"), SMALL.replace(**changes), seed=3)
    return agent, agent.core, agent.state, _batch(agent, np.random.default_rng(1))


def test_categorical_latent_is_one_hot_and_the_encoder_learns_through_it():
    agent, core, state, batch = _point_mass_lili(latent_kind="categorical")
    z, zbar, zbar_next = core._latents(state.model, state.target, state.norm, batch)
    for latent in (z, zbar, zbar_next):
        latent = np.asarray(latent)
        np.testing.assert_array_equal(latent.sum(-1), 1.0)
        assert set(np.unique(latent)) <= {0.0, 1.0}
    # The one-hot names the encoder's largest output ...
    prev = window_part(batch["window"], slice(None, -1))
    logits = core.encoder.apply(state.model["encoder"], core._features(state.norm, prev),
                                prev["weight"])
    np.testing.assert_array_equal(np.argmax(np.asarray(z), -1), np.argmax(np.asarray(logits), -1))
    # ... and J_rep's gradient reaches the encoder through it (straight-through).
    grads = jax.grad(lambda enc: core._rep_loss(
        state.model, state.norm, batch,
        core._latents(dict(state.model, encoder=enc), state.target, state.norm, batch)[0]))(
        state.model["encoder"])
    assert any(float(jnp.abs(g).max()) > 0 for g in jax.tree_util.tree_leaves(grads))
    # Acting holds the same one-hot the updates use.
    first = {k: v[0] for k, v in prev.items()}
    acting = np.asarray(core.jit_latent(state.model, state.norm, first))
    np.testing.assert_array_equal(acting, np.asarray(z)[0])


def test_quantised_latent_is_a_codebook_vector_and_both_sides_learn():
    env = gym.make("lili/PointMass-v0")
    agent = LILI(env, SMALL.replace(latent_kind="quantised", latent_codes=5), seed=3)
    core, state = agent.core, agent.state
    codebook = np.asarray(state.model["encoder"]["params"]["codebook"])
    assert codebook.shape == (5, SMALL.latent_dim)
    assert "codebook" in state.target["encoder"]["params"]  # the Polyak copy carries it
    batch = _batch(agent, np.random.default_rng(1))
    z, zbar, zbar_next = core._latents(state.model, state.target, state.norm, batch)
    prev = window_part(batch["window"], slice(None, -1))
    e = np.asarray(core._encoder_out(state.model["encoder"], state.norm, prev))
    nearest = codebook[((e[:, None] - codebook) ** 2).sum(-1).argmin(-1)]
    np.testing.assert_allclose(np.asarray(z), nearest, rtol=1e-6, atol=1e-6)
    for latent in (zbar, zbar_next):  # every latent is a row of the codebook
        d = ((np.asarray(latent)[:, None] - codebook) ** 2).sum(-1).min(-1)
        np.testing.assert_allclose(d, 0.0, atol=1e-10)
    # J_rep moves the encoder (straight-through and commitment) and the codebook.
    grads = jax.grad(lambda enc: core._rep_loss(
        dict(state.model, encoder=enc), state.norm, batch,
        core._latents(dict(state.model, encoder=enc), state.target, state.norm, batch)[0]))(
        state.model["encoder"])
    assert float(np.abs(np.asarray(grads["params"]["codebook"])).max()) > 0
    assert any(float(jnp.abs(g).max()) > 0
               for g in jax.tree_util.tree_leaves(grads["params"]["Encoder_0"]))
    # Only the codes that name an output move.
    used = set(((e[:, None] - codebook) ** 2).sum(-1).argmin(-1).tolist())
    moved = {k for k in range(5) if np.abs(np.asarray(grads["params"]["codebook"])[k]).max() > 0}
    assert moved == used
    first = {k: v[0] for k, v in prev.items()}
    np.testing.assert_allclose(np.asarray(core.jit_latent(state.model, state.norm, first)),
                               np.asarray(z)[0], rtol=1e-6, atol=1e-6)


def test_bottleneck_feeds_the_decoder_a_noisy_latent_and_prices_its_size():
    env = gym.make("lili/PointMass-v0")
    beta = 0.3
    agent = LILI(env, SMALL.replace(latent_bottleneck=beta), seed=3)
    core, state = agent.core, agent.state
    batch = dict(_batch(agent, np.random.default_rng(1)), rep_key=jax.random.PRNGKey(7))
    z = core._latents(state.model, state.target, state.norm, batch)[0]
    eps = jax.random.normal(batch["rep_key"], z.shape)
    want = (decoder_loss(core.decoder, state.model["decoder"], state.norm, batch, z + eps)
            + beta * 0.5 * float((np.asarray(z) ** 2).sum(-1).mean()))
    got = core._rep_loss(state.model, state.norm, batch, z)
    np.testing.assert_allclose(float(got), float(want), rtol=1e-5)
    # Another noise draw is another loss: the decoder really reads z + eps.
    other = core._rep_loss(state.model, state.norm, dict(batch, rep_key=jax.random.PRNGKey(8)), z)
    assert abs(float(other) - float(got)) > 1e-6
    # The price alone pulls z toward 0: its gradient is beta * z.
    g = jax.grad(lambda zz: beta * bottleneck_kl(zz))(z)
    np.testing.assert_allclose(np.asarray(g), beta * np.asarray(z) / z.shape[0], rtol=1e-5)
    # A whole update runs and differs from the run without the bottleneck.
    plain = LILI(env, SMALL, seed=3)
    batch.pop("rep_key")
    s1, _ = core.update(state, batch, jax.random.PRNGKey(0))
    s0, _ = plain.core.update(plain.state, batch, jax.random.PRNGKey(0))
    # (Adam's first step is about lr * sign(gradient) per weight, so compare every weight.)
    assert not all(np.allclose(a, b, atol=0) for a, b in zip(
        jax.tree_util.tree_leaves(s1.model["encoder"]),
        jax.tree_util.tree_leaves(s0.model["encoder"]), strict=True))


def test_posterior_target_regresses_the_encoder_onto_the_next_interactions_own_code():
    env = gym.make("lili/PointMass-v0")
    agent = LILI(env, SMALL.replace(latent_target="posterior"), seed=3)
    core, state = agent.core, agent.state
    assert set(state.model) == {"critic", "encoder", "decoder", "posterior"}
    assert "posterior" not in state.target  # no target copy: only J_rep reads P
    batch = _batch(agent, np.random.default_rng(1))
    z = core._latents(state.model, state.target, state.norm, batch)[0]
    own = window_part(batch["window"], slice(-1, None))
    code = core.posterior.apply(state.model["posterior"], core._features(state.norm, own),
                                own["weight"])
    want = (float(((np.asarray(z) - np.asarray(code)) ** 2).sum(-1).mean())
            + float(decoder_loss(core.decoder, state.model["decoder"], state.norm, batch, code)))
    np.testing.assert_allclose(float(core._rep_loss(state.model, state.norm, batch, z)), want,
                               rtol=1e-5)

    # E learns only the regression (P detached in it); P and D only the decoder's loss.
    def rep(model):
        zz = core._latents(model, state.target, state.norm, batch)[0]
        return core._rep_loss(model, state.norm, batch, zz)

    grads = jax.grad(rep)(state.model)
    moved = {k: any(float(jnp.abs(g).max()) > 0 for g in jax.tree_util.tree_leaves(grads[k]))
             for k in ("encoder", "decoder", "posterior")}
    assert moved == {"encoder": True, "decoder": True, "posterior": True}
    only_e = jax.grad(lambda enc: ((core._latents(dict(state.model, encoder=enc), state.target,
                                                  state.norm, batch)[0] - code) ** 2
                                   ).sum(-1).mean())(state.model["encoder"])
    for a, b in zip(jax.tree_util.tree_leaves(only_e),
                    jax.tree_util.tree_leaves(grads["encoder"]), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-4, atol=1e-7)
    # The default keeps the paper's parameters (no P) and E's and D's initial weights.
    plain = LILI(env, SMALL, seed=3)
    assert set(plain.state.model) == {"critic", "encoder", "decoder"}
    for k in ("encoder", "decoder"):
        for a, b in zip(jax.tree_util.tree_leaves(plain.state.model[k]),
                        jax.tree_util.tree_leaves(state.model[k]), strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    # One whole update runs.
    new, metrics = core.update(state, batch, jax.random.PRNGKey(0))
    assert np.isfinite(float(metrics["rep_loss"]))


def test_prediction_critic_reads_the_decoders_predictions_and_not_z():
    agent, core, state, batch = _point_mass_lili(critic_latent="prediction")
    z, zbar, zbar_next = core._latents(state.model, state.target, state.norm, batch)
    width = PROBES * (agent.obs_dim + 1)
    x_q, x_pi, _ = core._inputs(state.model, state, batch)
    assert x_pi.shape[-1] == core.x_dim and x_q.shape[-1] == core.x_dim - 3 + width
    # The critic's latent part is D's prediction at the probe inputs, for every transition.
    probe_s = jnp.broadcast_to(core.probe_obs, (2, PROBES, agent.obs_dim))
    probe_a = jnp.broadcast_to(core.probe_act, (2, PROBES, agent.act_dim))
    want = core.decoder.apply(state.model["decoder"], probe_s, probe_a,
                              jnp.broadcast_to(z[:, None], (2, PROBES, 3))).reshape(2, -1)
    np.testing.assert_allclose(np.asarray(x_q[:, 1, -width:]), np.asarray(want), rtol=1e-5,
                               atol=1e-6)
    np.testing.assert_array_equal(np.asarray(x_pi[..., -3:]),
                                  np.broadcast_to(np.asarray(z)[:, None], (2, 3, 3)))
    # At the boundary the target's critic reads the prediction of E_target(tau^k).
    x_next, x_next_pi = core._target_inputs(state, batch)
    code_next = np.asarray(core._critic_latent(state.model, zbar_next))
    np.testing.assert_allclose(np.asarray(x_next[:, 2, -width:]), code_next, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(x_next_pi[:, 2, -3:]), np.asarray(zbar_next),
                               rtol=1e-6)
    # The critic loss no longer reaches E (with the default it does).
    for kind, reaches in (("prediction", False), ("latent", True)):
        a = _point_mass_lili(critic_latent=kind, rep_weight=0.0)[0]
        y = a.core.critic_target(a.state, batch, jax.random.PRNGKey(0))

        def critic_loss(model, a=a, y=y):
            x = a.core._inputs(model, a.state, batch)[0]
            return ((a.core.critic.apply(model["critic"], x, batch["act"]) - y) ** 2).mean()

        grads = jax.grad(critic_loss)(a.state.model)["encoder"]
        assert any(float(jnp.abs(g).max()) > 0 for g in jax.tree_util.tree_leaves(grads)) \
            == reaches, kind
    new, metrics = core.update(state, batch, jax.random.PRNGKey(0))
    assert np.isfinite(float(metrics["critic_loss"]))


def test_sac_bootstraps_from_the_next_interaction():
    env = gym.make("lili/PointMass-v0")
    agent = SAC(env, SMALL, seed=0)
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
    # boundary_gamma discounts the last step only; the other steps keep gamma.
    other = SAC(env, SMALL.replace(boundary_gamma=0.3), seed=0)
    y_b = np.asarray(other.core.critic_target(other.state, batch, key))
    discount = np.where(np.asarray(batch["last"]), 0.3, GAMMA)
    np.testing.assert_allclose(y_b, np.asarray(batch["rew"]) + discount * np.asarray(v),
                               rtol=1e-5, atol=1e-5)
    # boundary_discount="horizon": an interaction that ended at step 20 of H still discounts
    # the next one as if it had run to H; a full-length one (t = H - 1) as before.
    early = dict(batch, t=batch["t"].at[1, 2].set(20))
    padded = SAC(env, SMALL.replace(boundary_discount="horizon"), seed=0)
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
    oracle = Oracle(env, SMALL)
    assert oracle.obs_dim == 4
    assert LILI(gym.make("lili/PointMass-v0"), SMALL).obs_dim == 2


def test_load_rejects_corrupt_and_mismatched_files(tmp_path):
    env = gym.make("lili/PointMass-v0")
    path = SAC(env, SMALL).save(tmp_path / "sac.msgpack")
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
    ({"boundary_gamma": 1.0}, r"boundary_gamma=1.0.*\[0, 1\) or null"),
    ({"boundary_discount": "episode"}, r"boundary_discount='episode'.*step or horizon"),
    ({"critic_latent": "z"}, r"critic_latent='z'.*latent or prediction"),
    ({"hidden": [0]}, "hidden"),
    ({"boundary": "sideways"}, "boundary='sideways'"),
    ({"latent_dim": 0}, "latent_dim=0"),
    ({"latent_kind": "discrete"}, "latent_kind='discrete'.*continuous, categorical, quantised"),
    ({"random_interactions": 1.5}, r"random_interactions=1.5.*\[0, 1\]"),
    ({"latent_balance": -1}, "latent_balance=-1"),
    ({"latent_bottleneck": -0.5}, "latent_bottleneck=-0.5"),
    ({"latent_codes": 1}, "latent_codes=1.*integer >= 2"),
    ({"latent_target": "prior"}, "latent_target='prior'.*decoder or posterior"),
    ({"latent_target": "posterior", "latent_kind": "categorical"},
     "latent_target='posterior'.*continuous latent"),
    ({"latent_bottleneck": 1.0, "latent_kind": "categorical"},
     "latent_bottleneck=1.0.*continuous latent"),
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
