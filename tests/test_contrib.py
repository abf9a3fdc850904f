"""The variants of LILI in lili.contrib: what each changes in the maths, that each is an algo of
the registry that trains, saves and resumes like the core's, and that run folders written when
they were AgentConfig fields load at their defaults or name the algo to use. (lili-critic-ln on
the JAX-native path: tests/test_jax_train.py.)"""

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_agents import SMALL, _batch
from test_contract import Asymmetric, _numbers, _run

import lili.envs  # noqa: F401  (registers the envs)
from lili.agents import LILI, make_agent
from lili.agents.latent import decoder_loss, window_part
from lili.agents.registry import AGENTS, ALGOS, CONTRIB_ALGOS, TABLE, check_config, load_agent
from lili.config import RETIRED_FIELDS, AgentConfig
from lili.contrib.latents import PROBES, bottleneck_kl


def _point_mass_lili(algo, **changes):
    """A small Point Mass ``algo`` (seed 3) with the config ``changes``, its core, its state
    and a hand-made batch."""
    agent = make_agent(algo, gym.make("lili/PointMass-v0"), SMALL.replace(**changes), seed=3)
    return agent, agent.core, agent.state, _batch(agent, np.random.default_rng(1))


@pytest.mark.slow
def test_categorical_latent_is_one_hot_and_the_encoder_learns_through_it():
    agent, core, state, batch = _point_mass_lili("lili-categorical")
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
    agent = make_agent("lili-quantised", env, SMALL.replace(extra={"lili-quantised": {"codes": 5}}),
                       seed=3)
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


@pytest.mark.slow
def test_bottleneck_feeds_the_decoder_a_noisy_latent_and_prices_its_size():
    env = gym.make("lili/PointMass-v0")
    beta = 0.3
    agent = make_agent("lili-bottleneck", env,
                       SMALL.replace(extra={"lili-bottleneck": {"weight": beta}}), seed=3)
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
    agent = make_agent("lili-posterior", env, SMALL, seed=3)
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
    agent, core, state, batch = _point_mass_lili("lili-prediction-critic")
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
    code_next = np.asarray(core.critic_code(state.model, zbar_next))
    np.testing.assert_allclose(np.asarray(x_next[:, 2, -width:]), code_next, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(x_next_pi[:, 2, -3:]), np.asarray(zbar_next),
                               rtol=1e-6)
    # The critic loss no longer reaches E (with the default it does).
    for kind, reaches in (("lili-prediction-critic", False), ("lili", True)):
        a = _point_mass_lili(kind, rep_weight=0.0)[0]
        y = a.core.critic_target(a.state, batch, jax.random.PRNGKey(0))

        def critic_loss(model, a=a, y=y):
            x = a.core._inputs(model, a.state, batch)[0]
            return ((a.core.critic.apply(model["critic"], x, batch["act"]) - y) ** 2).mean()

        grads = jax.grad(critic_loss)(a.state.model)["encoder"]
        assert any(float(jnp.abs(g).max()) > 0 for g in jax.tree_util.tree_leaves(grads)) \
            == reaches, kind
    new, metrics = core.update(state, batch, jax.random.PRNGKey(0))
    assert np.isfinite(float(metrics["critic_loss"]))


def test_set_encoder_maps_the_pooled_features_by_an_mlp_and_stays_permutation_invariant():
    agent, core, state, batch = _point_mass_lili("lili-set-encoder")
    # Two layers per width: one before the pooling (as LILI's E), one after; then z's map.
    assert len(state.model["encoder"]["params"]) == 2 * len(SMALL.enc_hidden) + 1
    prev = window_part(batch["window"], slice(None, -1))
    z = np.asarray(core._encode(state.model["encoder"], state.norm, prev))
    # The steps of an interaction are a set: reversing their order leaves z as it was.
    flipped = {k: (v[:, :, ::-1] if v.ndim >= 3 else v) for k, v in prev.items()}
    np.testing.assert_allclose(np.asarray(core._encode(state.model["encoder"], state.norm,
                                                       flipped)), z, rtol=1e-5, atol=1e-6)


def test_flat_encoder_reads_every_step_in_its_place_and_ignores_padding():
    agent, core, state, batch = _point_mass_lili("lili-flat-encoder")
    assert core.window_steps is None
    prev = window_part(batch["window"], slice(None, -1))
    enc = state.model["encoder"]
    first = enc["params"]["MLP_0"]["Dense_0"]["kernel"]
    assert first.shape == (agent.history * agent.horizon * core.feat_dim, SMALL.enc_hidden[0])
    z = np.asarray(core._encode(enc, state.norm, prev))
    # Places matter: reversing the steps moves z (LILI's pooled E would keep it).
    flipped = {k: (v[:, :, ::-1] if v.ndim >= 3 else v) for k, v in prev.items()}
    assert not np.allclose(np.asarray(core._encode(enc, state.norm, flipped)), z, atol=1e-4)
    # A padded step (weight 0) is not read, whatever it holds.
    w = prev["weight"].at[:, :, -5:].set(0.0)
    masked = dict(prev, weight=w)
    junk = dict(masked, obs=masked["obs"].at[:, :, -5:].set(1e3))
    np.testing.assert_allclose(np.asarray(core._encode(enc, state.norm, junk)),
                               np.asarray(core._encode(enc, state.norm, masked)), rtol=1e-6)
    # Updates draw whole interactions in order for E (encoder_transitions is not read).
    buffer = agent.learn(3).stream.buffer  # the warm-up's interactions, no update yet
    drawn = core._batch(state, buffer.arrays, jnp.asarray(buffer.count), jax.random.PRNGKey(0))
    assert drawn["window"]["t"].shape[-1] == agent.horizon
    np.testing.assert_array_equal(np.asarray(drawn["window"]["t"][0, 0]), np.arange(agent.horizon))
    with pytest.raises(ValueError, match="encoder_transitions"):
        check_config("lili-flat-encoder", AgentConfig(encoder_transitions=8))


def test_critic_layer_norm_normalises_both_q_networks_and_changes_nothing_else():
    agent, core, state, batch = _point_mass_lili("lili-critic-ln")
    (pair,) = state.model["critic"]["params"].values()  # the two Q networks, stacked
    assert sorted(k for k in pair if k.startswith("LayerNorm")) == ["LayerNorm_0", "LayerNorm_1"]
    for i, width in enumerate(SMALL.hidden):  # one per hidden layer, each Q its own
        assert pair[f"LayerNorm_{i}"]["scale"].shape == (2, width)
    assert jax.tree.structure(state.target["critic"]) == jax.tree.structure(state.model["critic"])
    # The norm acts: scaling the first layer's weights and bias leaves every Q value as it was
    # (LayerNorm divides the scale out), where LILI's plain critic scales its Q with them.
    x, _, _ = core._inputs(state.model, state, batch)
    plain = LILI(gym.make("lili/PointMass-v0"), SMALL, seed=3)

    def q_scaled(critic, params, c):
        (name,) = params["params"]
        dense = params["params"][name]["Dense_0"]
        scaled = jax.tree.map(lambda v: c * v, dense)
        p = {"params": {name: {**params["params"][name], "Dense_0": scaled}}}
        return np.asarray(critic.apply(p, x, batch["act"]))

    np.testing.assert_allclose(q_scaled(core.critic, state.model["critic"], 10.0),
                               q_scaled(core.critic, state.model["critic"], 1.0), rtol=1e-4,
                               atol=1e-5)
    assert not np.allclose(q_scaled(plain.core.critic, plain.state.model["critic"], 10.0),
                           q_scaled(plain.core.critic, plain.state.model["critic"], 1.0),
                           rtol=1e-2)
    # Everything but the critic starts as LILI's at the same seed.
    for a, b in ((state.actor, plain.state.actor),
                 (state.model["encoder"], plain.state.model["encoder"]),
                 (state.model["decoder"], plain.state.model["decoder"])):
        for u, v in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
            np.testing.assert_array_equal(np.asarray(u), np.asarray(v))
    # One update: the same numbers twice, not LILI's.
    key = jax.random.PRNGKey(0)
    _, m1 = core.update(state, batch, key)
    _, m2 = core.update(state, batch, key)
    _, m0 = plain.core.update(plain.state, batch, key)
    assert {k: float(v) for k, v in m1.items()} == {k: float(v) for k, v in m2.items()}
    assert np.isfinite(float(m1["critic_loss"]))
    assert float(m1["q"]) != float(m0["q"]) and float(m1["critic_loss"]) != float(m0["critic_loss"])


# One variant in the default suite; the others run the same code path (slow).
@pytest.mark.parametrize("algo", [a if a == CONTRIB_ALGOS[0] else
                                  pytest.param(a, marks=pytest.mark.slow) for a in CONTRIB_ALGOS])
def test_every_variant_trains_saves_and_resumes_like_the_core(algo, tmp_path):
    assert algo in ALGOS
    agent, rows, _ = _run(algo, tmp_path, n=4)
    again, resumed, _ = _run(algo, tmp_path, n=4, stop_at=2)
    np.testing.assert_array_equal(_numbers(rows), _numbers(resumed))
    assert np.isfinite(_numbers(rows)[-1][2])  # it learned: the last block has an actor loss
    loaded = load_agent(agent.save(tmp_path / "agent.msgpack"), Asymmetric())
    assert type(loaded) is type(agent) and loaded.algo == algo
    core_algo = next(a.variant_of for a in TABLE if a.name == algo)
    assert isinstance(agent, AGENTS[core_algo][0]) and core_algo in ALGOS


def test_variant_options_are_checked_by_name_and_value():
    env = gym.make("lili/PointMass-v0")
    with pytest.raises(ValueError, match=r"unknown lili-quantised option\(s\) 'code'.*codes"):
        make_agent("lili-quantised", env, SMALL.replace(extra={"lili-quantised": {"code": 3}}))
    with pytest.raises(ValueError, match=r"extra.lili-quantised.codes=1 .*integer >= 2"):
        check_config("lili-quantised", SMALL.replace(extra={"lili-quantised": {"codes": 1}}))
    with pytest.raises(ValueError, match=r"extra.lili-quantised is invalid: it is not read by "
                                         r"lili \(it would be ignored\)"):
        check_config("lili", SMALL.replace(extra={"lili-quantised": {"codes": 4}}))
    with pytest.raises(ValueError, match=r"config critic_to_encoder=0.5 is not read by "
                                         r"lili-prediction-critic"):
        check_config("lili-prediction-critic", SMALL.replace(critic_to_encoder=0.5))
    with pytest.raises(ValueError, match=r"extra.lili-bottleneck.weight=0 .*> 0"):
        check_config("lili-bottleneck", SMALL.replace(extra={"lili-bottleneck": {"weight": 0}}))
    with pytest.raises(ValueError, match=r"extra.lili-categorical.balance=-1 .*>= 0"):
        check_config("lili-categorical", SMALL.replace(extra={"lili-categorical": {"balance": -1}}))
    with pytest.raises(ValueError, match=r"option\(s\) 'x' in config extra.lili-posterior; "
                                         r"allowed: none$"):
        check_config("lili-posterior", SMALL.replace(extra={"lili-posterior": {"x": 1}}))


OLD_DEFAULTS = {name: default for name, (default, _) in RETIRED_FIELDS.items()}


def test_old_configs_load_at_the_retired_fields_defaults():
    """config.yaml of s0-s24 holds every retired field at its default: the same config."""
    assert AgentConfig.from_dict({**OLD_DEFAULTS, "gamma": 0.9}) == AgentConfig(gamma=0.9)
    assert "latent_kind" not in AgentConfig().to_dict()


@pytest.mark.parametrize("field, value, match", [
    ("latent_kind", "categorical", "use --algo lili-categorical$"),
    ("latent_kind", "quantised", "use --algo lili-quantised$"),
    ("latent_target", "posterior", "use --algo lili-posterior$"),
    ("critic_latent", "prediction", "use --algo lili-prediction-critic$"),
    ("latent_bottleneck", 0.1, r"use --algo lili-bottleneck with extra: "
                               r"\{lili-bottleneck: \{weight: 0.1\}\}"),
    ("latent_codes", 8, r"lili-quantised with extra: \{lili-quantised: \{codes: 8\}\}"),
    ("boundary_gamma", 0.3, "is no longer supported.*boundary_discount='horizon'"),
    ("latent_kind", "discrete", "is invalid.*lili-categorical, lili-quantised\\)$"),
])
def test_old_configs_with_a_variant_name_the_algo_to_use(field, value, match):
    with pytest.raises(ValueError, match=f"^config {field}={value!r} .*{match}"):
        AgentConfig.from_dict({**OLD_DEFAULTS, field: value})


def test_contrib_is_told_by_variant_of_alone_and_names_a_core_algo():
    from lili.agents.registry import CORE_ALGOS, Algo

    assert CONTRIB_ALGOS and all(a.module.startswith("lili.contrib.") for a in TABLE
                                 if a.name in CONTRIB_ALGOS)
    assert {a.variant_of for a in TABLE if a.variant_of} <= set(CORE_ALGOS)
    for module, variant_of in (("lili.contrib.latents", ""), ("lili.agents.lili", "lili")):
        with pytest.raises(ValueError, match="variant_of"):
            Algo("x", module, frozenset(), variant_of=variant_of)


def test_flat_encoder_critic_ln_has_the_flat_encoder_and_the_layer_normed_critic():
    agent, core, state, batch = _point_mass_lili("lili-flat-encoder-critic-ln")
    flat = make_agent("lili-flat-encoder", gym.make("lili/PointMass-v0"), SMALL, seed=3)
    ln = make_agent("lili-critic-ln", gym.make("lili/PointMass-v0"), SMALL, seed=3)
    assert core.window_steps is None
    # Each network has the structure of the variant it is taken from, and not the other's.
    for part, same, other in (("encoder", flat, ln), ("critic", ln, flat)):
        mine = jax.tree.structure(state.model[part])
        assert mine == jax.tree.structure(same.state.model[part])
        assert mine != jax.tree.structure(other.state.model[part])
    _, metrics = core.update(state, batch, jax.random.PRNGKey(0))
    assert np.isfinite(float(metrics["critic_loss"])) and np.isfinite(float(metrics["rep_loss"]))
    with pytest.raises(ValueError, match="encoder_transitions"):
        check_config("lili-flat-encoder-critic-ln", AgentConfig(encoder_transitions=8))
