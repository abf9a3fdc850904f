"""LILAC: posterior and prior, the ELBO, acting with the prior, save/load, train and resume."""


import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import lili.envs  # noqa: F401  (registers the envs)
from lili.agents import ALGOS, LILAC, load_agent, make_agent
from lili.buffer import InteractionBuffer, sample
from lili.config import AgentConfig

N = 2
SMALL = AgentConfig(hidden=(32, 32), enc_hidden=(16, 16), latent_dim=3, warmup_interactions=3,
                    batch_interactions=8, per_interaction=4, extra={"lilac": {"prior_window": N}})
L = SMALL.latent_dim


@pytest.fixture(scope="module")
def agent():
    """A LILAC agent that has played (and learnt from) a few Point Mass interactions."""
    a = LILAC(gym.make("lili/PointMass-v0"), SMALL, seed=3)
    a.learn(6)
    return a


def _batch(agent, seed=0, buf=None):
    """A training batch from ``buf`` (default: the buffer the agent learnt on)."""
    buf = agent.stream.buffer if buf is None else buf
    a = buf.arrays
    cfg = agent.config
    return sample({k: jnp.asarray(v) for k, v in a.items()}, jnp.asarray(buf.count),
                  jax.random.PRNGKey(seed), cfg.batch_interactions, cfg.per_interaction,
                  agent.history, cfg.encoder_transitions)


def _leaves_norm(tree):
    return float(sum(jnp.abs(x).sum() for x in jax.tree_util.tree_leaves(tree)))


def test_registered_and_defaults():
    assert "lilac" in ALGOS
    cfg = SMALL.replace(extra={}, warmup_interactions=5)
    a = make_agent("lilac", gym.make("lili/PointMass-v0"), cfg)
    assert isinstance(a, LILAC) and a.algo == "lilac"
    # Defaults: a 2-interaction prior window, the critic on the prior's latent, bootstrapping
    # at the boundary with the latent of the next interaction.
    assert a.history == 2 and a.options.critic_latent == "prior" and a.boundary == "influence"


def test_posterior_and_prior_shapes(agent):
    batch = _batch(agent)
    b, w = SMALL.batch_interactions, N + 1
    core, model, norm = agent.core, agent.state.model, agent.state.norm
    q_mean, q_log_std = core.posterior_params(model["encoder"], norm, batch["window"])
    assert q_mean.shape == q_log_std.shape == (b, w, L)
    present = jnp.ones((b, w), bool)
    p_mean, p_log_std = core.prior_params(model["encoder"], q_mean, present)
    assert p_mean.shape == p_log_std.shape == (b, w + 1, L)
    z, zbar, zbar_next = core._latents(model, agent.state.target, norm, batch)
    assert z.shape == zbar.shape == zbar_next.shape == (b, L)
    # The critic's latent for interaction k is the prior's prediction from k-N..k-1.
    np.testing.assert_allclose(np.asarray(z), np.asarray(p_mean[:, N]), rtol=1e-5, atol=1e-6)


def test_elbo_terms_are_finite_and_decrease_on_a_fixed_batch(agent):
    batch = _batch(agent, seed=1)
    key = jax.random.PRNGKey(0)
    core, norm = agent.core, agent.state.norm

    def terms(state):
        return {k: float(v) for k, v in
                core.elbo_terms(state.model, norm, batch, key).items()}

    @jax.jit
    def steps(state):
        def body(s, i):
            s, m = core.update(s, batch, jax.random.fold_in(key, i))
            return s, m
        return jax.lax.scan(body, state, jnp.arange(300))

    before = terms(agent.state)
    state, metrics = steps(agent.state)
    after = terms(state)
    assert all(np.isfinite(v) for v in (*before.values(), *after.values()))
    assert np.all(np.isfinite(np.asarray(metrics["critic_loss"])))
    assert after["loss"] < 0.7 * before["loss"], (before, after)
    assert after["recon"] < before["recon"], (before, after)
    # The prior moved towards the posteriors it is trained on.
    assert np.mean(np.asarray(metrics["rep_loss"][-20:])) < np.mean(
        np.asarray(metrics["rep_loss"][:20]))


def test_prior_learns_only_from_the_kl(agent):
    batch = _batch(agent, seed=2)
    core, model, norm = agent.core, agent.state.model, agent.state.norm
    key = jax.random.PRNGKey(5)

    def grad_of(term):
        return jax.jit(jax.grad(lambda m: core.elbo_terms(m, norm, batch, key)[term]))(model)

    g_kl, g_recon, g_ctx = grad_of("kl"), grad_of("recon"), grad_of("kl_context")
    assert _leaves_norm(g_kl["encoder"]["prior"]) > 0
    assert _leaves_norm(g_kl["encoder"]["posterior"]) > 0  # the q side of the KL
    # The earlier interactions' KLs train the prior on shorter contexts, not their posteriors.
    assert _leaves_norm(g_ctx["encoder"]["prior"]) > 0
    assert _leaves_norm(g_ctx["encoder"]["posterior"]) == 0
    assert _leaves_norm(g_recon["encoder"]["prior"]) == 0
    assert _leaves_norm(g_recon["encoder"]["posterior"]) > 0
    # The critic's latent is the prior's prediction, detached: the RL losses shape neither the
    # prior nor the posterior (no path to learn the ego's influence).
    g_critic = jax.jit(jax.grad(
        lambda m: core._latents(m, agent.state.target, norm, batch)[0].sum()))(model)
    assert _leaves_norm(g_critic["encoder"]) == 0


def test_posterior_critic_option_sends_the_critic_gradient_to_the_posterior():
    cfg = SMALL.replace(extra={"lilac": {"prior_window": N, "critic_latent": "posterior"}})
    a = LILAC(gym.make("lili/PointMass-v0"), cfg, seed=0)
    buf = InteractionBuffer(cfg.buffer_capacity, a.horizon, a.obs_dim, a.act_dim)
    rng = np.random.default_rng(0)
    for _ in range(N + 2):
        n = 50
        buf.add({"obs": rng.normal(size=(n, 2)), "act": rng.uniform(-1, 1, (n, 2)),
                      "rew": rng.normal(size=n), "next_obs": rng.normal(size=(n, 2))},
                     rng.normal(size=2))
    batch = _batch(a, buf=buf)
    core, model, norm = a.core, a.state.model, a.state.norm
    z, _, _ = core._latents(model, a.state.target, norm, batch)
    q_mean, _ = core.posterior_params(model["encoder"], norm, batch["window"])
    np.testing.assert_allclose(np.asarray(z), np.asarray(q_mean[:, N]), rtol=1e-6)
    g = jax.grad(lambda m: core._latents(m, a.state.target, norm, batch)[0].sum())(model)
    assert _leaves_norm(g["encoder"]["posterior"]) > 0
    assert _leaves_norm(g["encoder"]["prior"]) == 0


def test_acts_with_the_prior_prediction_from_previous_posteriors(agent):
    buf, core = agent.stream.buffer, agent.core
    model, norm = agent.state.model, agent.state.norm
    enc = model["encoder"]
    steps = agent.config.encoder_transitions

    def manual(end):
        """Prior mean for interaction end+1 from the posterior means of end-N+1..end."""
        win = buf.window(end, N, steps)
        x = core._features(norm, {k: jnp.asarray(v) for k, v in win.items()})
        out = core.posterior.apply(enc["posterior"], x[:, None], jnp.asarray(win["weight"])[:,
                                   None])
        q_mean = out[:, :L]
        p_mean, _ = core.prior.apply(enc["prior"], q_mean[None], jnp.ones((1, N), bool))
        return np.asarray(p_mean[0, -1]), np.asarray(q_mean)

    z_next = agent.next_state(buf).z
    want, _ = manual(buf.count - 1)
    np.testing.assert_allclose(z_next, want, rtol=1e-5, atol=1e-6)

    # The latent the newest interaction i was played with comes from i-N..i-1 only, and is not
    # the posterior of tau^i (which did not exist while acting).
    z_played, _ = manual(buf.count - 2)
    _, q_newest = manual(buf.count - 1)
    assert not np.allclose(z_played, q_newest[-1], atol=1e-3)
    np.testing.assert_allclose(agent.next_latent_state(_prefix(buf, buf.count - 1)).z, z_played,
                               rtol=1e-5, atol=1e-6)

    # The boundary target of interaction k uses exactly the latent LILAC acts with in k+1.
    k = buf.count - 1
    win = {key: jnp.asarray(v)[None] for key, v in buf.window(k, N + 1, steps).items()}
    batch = {"window": win}
    _, _, zbar_next = core._latents(model, {"encoder": enc}, norm, batch)
    np.testing.assert_allclose(np.asarray(zbar_next[0]), z_next, rtol=1e-5, atol=1e-6)


def _prefix(buf, count):
    """A copy of ``buf`` holding only its first ``count`` interactions."""
    out = InteractionBuffer(buf.capacity, buf.horizon, buf.obs_dim, buf.act_dim)
    for k, v in buf.arrays.items():
        out.arrays[k] = v.copy()
    out.count = count
    return out


def test_first_interaction_uses_the_unconditional_prior(agent):
    z0 = agent.initial_state().z
    p_mean, _ = agent.core.prior.apply(agent.state.model["encoder"]["prior"],
                                       jnp.zeros((1, 0, L)), jnp.zeros((1, 0), bool))
    np.testing.assert_allclose(z0, np.asarray(p_mean[0, 0]), rtol=1e-6, atol=1e-7)


def test_save_load_round_trip(agent, tmp_path):
    path = agent.save(tmp_path / "lilac.msgpack")
    loaded = LILAC.load(path, gym.make("lili/PointMass-v0"))
    assert isinstance(load_agent(path, gym.make("lili/PointMass-v0")), LILAC)
    assert loaded.config == agent.config and loaded.options == agent.options
    for a, b in zip(jax.tree_util.tree_leaves(agent.state),
                    jax.tree_util.tree_leaves(loaded.state), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    st = agent.next_latent_state(agent.stream.buffer)
    np.testing.assert_array_equal(loaded.next_latent_state(agent.stream.buffer).z, st.z)
    np.testing.assert_array_equal(loaded.initial_state().z, agent.initial_state().z)
    for obs in (np.array([0.01, -0.02], np.float32), np.array([0.1, 0.05], np.float32)):
        np.testing.assert_array_equal(agent.predict(obs, st)[0], loaded.predict(obs, st)[0])


@pytest.mark.parametrize("extra, match", [
    ({"lilac": {"prior_window": 0}}, "prior_window=0"),
    ({"lilac": {"kl_weight": -1}}, "kl_weight=-1"),
    ({"lilac": {"critic_latent": "both"}}, "critic_latent='both'"),
    ({"lilac": {"window": 3}}, "unknown lilac option"),
    ({"lilac": [1]}, "extra.lilac"),
    ({"lilac": {"prior_window": 3}}, "warmup_interactions=3 is invalid for LILAC"),
    ({"lilac": {"prior_window": True}}, "prior_window=True"),
])
def test_bad_options_are_named(extra, match):
    with pytest.raises(ValueError, match=match):
        LILAC(gym.make("lili/PointMass-v0"), SMALL.replace(extra=extra))

