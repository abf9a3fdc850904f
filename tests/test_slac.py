"""SLAC: sequence batches, the latent model's ELBO, acting = training inputs, save/load, resume."""

import csv
import shutil

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import yaml

import lili.envs  # noqa: F401  (registers the envs)
from lili import cli
from lili.agents import SLAC, ActingState, LatentState, load_agent, make_agent
from lili.agents.slac import LatentModel, sample_sequences
from lili.buffer import InteractionBuffer
from lili.config import AgentConfig
from lili.metrics_file import EXTRAS, read_extras
from lili.runs import RunLogger, load_checkpoint
from lili.train import train

K = 8
TINY = {"z1_dim": 4, "z2_dim": 8, "feature_dim": 8, "model_hidden": [16], "model_batch": 8,
        "pretrain_steps": 5, "lr_model": 1e-3}
FAST = {"hidden": [16, 16], "warmup_interactions": 3, "checkpoint_every": 4,
        "batch_interactions": 4, "per_interaction": 4, "extra": {"slac": TINY}}


def _tiny(slac=None, **changes):
    cfg = {**FAST, **changes, "extra": {"slac": {**TINY, **(slac or {})}}}
    return SLAC(gym.make("lili/PointMass-v0"), AgentConfig.from_dict(cfg))


def _labelled_buffer(lengths, horizon=12):
    """Interaction k, step s has obs (k, s), next_obs (k, s + 1), act (k, s), rew k + s / 100."""
    buf = InteractionBuffer(len(lengths) + 1, horizon, 2, 2)
    for k, n in enumerate(lengths):
        s = np.arange(n, dtype=np.float32)
        col = np.full(n, k, np.float32)
        buf.add({"obs": np.stack([col, s], -1), "act": np.stack([col, s], -1),
                 "rew": k + s / 100, "next_obs": np.stack([col, s + 1], -1)},
                np.array([k + 1, 0], np.float32))
    return buf


def test_sequence_batches_never_cross_an_interaction():
    lengths = [12, 5, 12, 9, 3, 12]  # early terminations shorter than K among them
    buf = _labelled_buffer(lengths)
    batch = jax.jit(sample_sequences, static_argnums=(3, 4, 5))(
        buf.arrays, buf.count, jax.random.PRNGKey(0), 64, 6, K)
    b = {k: np.asarray(v) for k, v in batch.items()}
    assert b["hist_obs"].shape == (64, 6, K + 1, 2) and b["hist_act"].shape == (64, 6, K, 2)
    assert b["win_obs"].shape == (64, 6, K + 1, 2) and b["win_rew"].shape == (64, 6, K)
    k_of = np.broadcast_to(b["index"][:, None], b["t"].shape)
    length = np.asarray(lengths)[k_of]
    assert (b["t"] < length).all() and (b["obs"][..., 0] == k_of).all()
    # The actor's history: frames t-K+1 .. t+1, valid from the interaction's start on.
    assert (b["hist_t"] == b["t"][..., None] + np.arange(-K + 1, 2)).all()
    assert (b["hist_valid"] == (b["hist_t"] >= 0)).all()
    v = b["hist_valid"]
    assert (b["hist_obs"][..., 0][v] == np.broadcast_to(k_of[..., None], v.shape)[v]).all()
    assert (b["hist_obs"][..., 1][v] == b["hist_t"][v]).all()
    # Actions before the start are zero; the rest belong to the same interaction and step.
    va = v[..., :-1]
    assert (b["hist_act"][~va] == 0).all()
    assert (b["hist_act"][..., 1][va] == b["hist_t"][..., :-1][va]).all()
    assert (b["hist_act"][..., 0][va] == np.broadcast_to(k_of[..., None], va.shape)[va]).all()
    # The filter's window: K+1 frames from max(0, t-K+1), masked past the interaction's end.
    assert (b["win_t"][..., 0] == np.maximum(b["t"] - K + 1, 0)).all()
    assert (np.take_along_axis(b["win_t"], b["pos"][..., None], -1)[..., 0] == b["t"]).all()
    w = b["win_valid"]
    assert (w == (b["win_t"] <= length[..., None])).all()
    assert (b["win_obs"][..., 0][w] == np.broadcast_to(k_of[..., None], w.shape)[w]).all()
    assert (b["win_obs"][..., 1][w] == b["win_t"][w]).all()  # frame L is the final next_obs
    ws = b["win_step_valid"]
    np.testing.assert_allclose(b["win_rew"][ws],
                               (k_of[..., None] + b["win_t"][..., :-1] / 100)[ws], rtol=1e-6)
    assert (~w).any() and (~v).any()  # the lengths above exercise both masks


def test_the_actor_input_is_zero_padded_at_the_start_of_an_interaction():
    agent = _tiny()
    core = agent.core
    state = agent.initial_state()
    norm = agent.state.norm
    history_x = jax.jit(core.history_x)
    for t in range(K + 2):
        obs = np.array([t + 1.0, -1.0 - t], np.float32)  # no frame is zero by chance
        x = np.asarray(history_x(norm, *core.acting_input(obs, state)))
        fx = x[: K * core.x_dim].reshape(K, core.x_dim)
        n_pad = max(K - 1 - t, 0)
        assert (fx[:n_pad] == 0).all() and (np.abs(fx[n_pad:]).sum(-1) > 0).all()
        acts = x[K * core.x_dim:].reshape(K - 1, agent.act_dim)
        assert (acts[:n_pad] == 0).all()
        _, state = agent.predict(obs, state, deterministic=False, key=jax.random.PRNGKey(t))
    # SLAC's acting state carries the interaction's history (the last K-1 frames and actions).
    assert isinstance(state, ActingState) and state.t == K + 2
    assert state.memory["obs"].shape == (K - 1, agent.obs_dim)
    assert state.memory["act"].shape == (K - 1, agent.act_dim)


@pytest.fixture(scope="module")
def trained_run():
    """A tiny SLAC after 3 warm-up interactions, model pretraining and 2 learning blocks, and
    the loop's rows.

    Shared: every agent compiles its update block anew, which dominates these tests' time.
    """
    agent = _tiny()
    rows = []
    agent.learn(5, callback=rows.append)
    return agent, rows


@pytest.fixture(scope="module")
def trained(trained_run):
    return trained_run[0]


def test_elbo_terms_are_finite_and_the_loss_decreases_on_a_fixed_batch(trained_run):
    agent, rows = trained_run
    core, buf = agent.core, agent.stream.buffer
    # Pretraining ran before the first block only, and its losses are those of every step.
    first = FAST["warmup_interactions"] - 1
    assert np.isfinite(rows[first]["pretrain_first"]) and np.isfinite(
        rows[first]["pretrain_last"])
    assert not any("pretrain_first" in r for j, r in enumerate(rows) if j != first)
    _, pretrain_losses = core.pretrain(agent.state, buf, TINY["pretrain_steps"],
                                       jax.random.PRNGKey(2))
    assert pretrain_losses.shape == (TINY["pretrain_steps"],)
    seq = core.jit_model_batch(buf.arrays, jnp.asarray(buf.count), jax.random.PRNGKey(3))
    params, opt, norm = agent.state.aux["slac"], agent.state.aux["opt_slac"], agent.state.norm
    losses = []
    for _ in range(100):  # the same batch and noise every step
        params, opt, terms = core.jit_model_step(params, opt, norm, seq, jax.random.PRNGKey(4))
        assert all(np.isfinite(float(v)) for v in terms.values()) and float(terms["kl"]) >= 0
        np.testing.assert_allclose(float(terms["loss"]), float(
            terms["obs_nll"] + terms["rew_nll"] + terms["kl"]), rtol=1e-5)
        losses.append(float(terms["loss"]))
    assert losses[-1] < 0.7 * losses[0], losses[::10]


def test_acting_sees_what_training_sees_for_the_same_step(trained):
    agent = trained  # learnt parameters and a fitted normaliser
    core, env, norm = agent.core, gym.make("lili/PointMass-v0"), agent.state.norm
    obs, _ = env.reset(seed=5)
    seen = []  # the actor's input at every acting step of one interaction

    history_x = jax.jit(core.history_x)

    def x_of(obs, hist):
        return np.asarray(history_x(norm, *core.acting_input(obs, hist)))

    traj = {"obs": [], "act": [], "rew": [], "next_obs": []}
    acting = agent.initial_state()
    for t in range(agent.horizon):
        seen.append(x_of(obs, acting))  # the state acting returned at the step before
        a, acting = agent.act(obs, acting, jax.random.PRNGKey(t), False)
        nxt, r, term, trunc, _ = env.step(agent.scale_action(a))
        for k_, v in zip(traj, (obs, a, r, nxt), strict=True):
            traj[k_].append(v)
        obs = nxt
        if term or trunc:
            break
    first, _ = env.reset()
    first_x = x_of(first, agent.initial_state())
    buf = InteractionBuffer(2, agent.horizon, agent.obs_dim, agent.act_dim)
    buf.add({k_: np.asarray(v, np.float32) for k_, v in traj.items()}, first)
    batch = jax.jit(core._batch)(agent.state, buf.arrays, jnp.asarray(1), jax.random.PRNGKey(0))
    t = np.asarray(batch["t"])
    assert len(np.unique(t)) > 5
    for i, j in np.ndindex(t.shape):
        np.testing.assert_allclose(batch["x_actor"][i, j], seen[t[i, j]], atol=1e-6)
        want_next = first_x if t[i, j] == len(seen) - 1 else seen[t[i, j] + 1]
        np.testing.assert_allclose(batch["x_actor_next"][i, j], want_next, atol=1e-6)


def test_predict_wants_the_acting_state_that_carries_the_history():
    """A state without SLAC's history (a latent agent's, or one made by hand) is refused.

    (Steps out of order, which the old hidden rollout history had to refuse, cannot happen:
    the history travels in the state that acting returns.)
    """
    agent = _tiny()
    obs = np.zeros(agent.obs_dim, np.float32)
    key = jax.random.PRNGKey(0)
    _, state = agent.predict(obs, agent.initial_state(), key=key)
    agent.predict(obs, state, key=key)
    with pytest.raises(ValueError, match="state=.* is invalid for slac; allowed: None or the "
                                         "ActingState"):
        agent.predict(obs, LatentState(np.zeros(0), 3))


def test_save_load_round_trip_gives_identical_actions(trained, tmp_path):
    agent = trained
    path = agent.save(tmp_path / "slac.msgpack")
    loaded = load_agent(path, gym.make("lili/PointMass-v0"))
    assert isinstance(loaded, SLAC) and loaded.options == agent.options
    obs = np.array([0.3, -0.2], np.float32)
    s1, s2 = None, None
    for t in range(K + 3):
        a1, s1 = agent.predict(obs, s1, deterministic=False, key=jax.random.PRNGKey(t))
        a2, s2 = loaded.predict(obs, s2, deterministic=False, key=jax.random.PRNGKey(t))
        np.testing.assert_array_equal(a1, a2)
        obs = obs + 0.1 * a1


@pytest.mark.parametrize("bad, match", [
    ({"extra": {"slac": {"z3_dim": 4}}}, "unknown slac option\\(s\\) 'z3_dim'"),
    ({"extra": {"slac": {"sequence_length": 0}}}, "sequence_length=0 is invalid"),
    ({"extra": {"slac": {"model_hidden": []}}}, "model_hidden=\\[\\] is invalid"),
    ({"extra": {"slac": {"lr_model": -1}}}, "lr_model=-1 is invalid"),
    ({"boundary": "influence"}, "boundary='influence' is invalid for SLAC"),
])
def test_bad_options_name_the_value_and_what_is_allowed(bad, match):
    with pytest.raises(ValueError, match=match):
        make_agent("slac", gym.make("lili/PointMass-v0"), AgentConfig.from_dict(bad))


def test_a_restored_checkpoint_continues_like_the_uninterrupted_run(trained, tmp_path):
    """Checkpoint, go on, restore the checkpoint, go on again: the same numbers (API level,
    reusing the compiled agent; the CLI version below runs fresh agents and is slow)."""
    agent = trained
    stream = agent.stream
    logger = RunLogger(tmp_path, {}, 0, checkpoint_every=1000)
    logger.checkpoint(agent, stream)
    logger.close()
    before = agent.num_interactions

    def numbers(rows):
        return [{k: v for k, v in r.items() if k not in ("wall_time", "strategy")} for r in rows]

    first = numbers(train(agent, stream, 3))
    assert load_checkpoint(tmp_path, agent, stream) == before
    assert agent.num_interactions == before
    again = numbers(train(agent, stream, 3))
    assert first == again and "rep_loss" in first[-1]


def test_the_model_terms_and_pretraining_losses_reach_block_extras_and_tensorboard(
        trained_run, tmp_path):
    """They are no column of metrics.csv (the ELBO's terms are SLAC's own, the pretraining
    losses come once), so the run folder keeps them in block_extras.jsonl; a resume keeps the
    lines of the interactions it keeps."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    agent, rows = trained_run
    first = FAST["warmup_interactions"] - 1
    dim = len(rows[0]["strategy"])
    logger = RunLogger(tmp_path, {}, dim, checkpoint_every=1000)
    for r in rows:
        logger.log(r, agent, agent.stream)
    logger.close()
    lines = read_extras(tmp_path / EXTRAS)
    assert [line["interaction"] for line in lines] == list(range(first, len(rows)))
    for line in lines:
        r = rows[line["interaction"]]
        assert {k: v for k, v in line.items() if k != "interaction"} == {
            k: r[k] for k in ("kl", "obs_nll", "rew_nll", "pretrain_first", "pretrain_last")
            if k in r}
    assert "pretrain_first" in lines[0] and not any("pretrain_first" in x for x in lines[1:])
    assert "kl" not in (tmp_path / "metrics.csv").read_text()
    # Resumed after the first block: its line stays, in the file and TensorBoard.
    logger = RunLogger(tmp_path, {}, dim, checkpoint_every=1000, start=first + 1)
    summary = logger.finish(agent, agent.stream, {"env": "e", "algo": "slac", "seed": 0})
    assert read_extras(tmp_path / EXTRAS) == lines[:1]
    assert summary["block_extras"] == {k: v for k, v in lines[0].items() if k != "interaction"}
    acc = EventAccumulator(str(tmp_path / "tb"), purge_orphaned_data=False)
    acc.Reload()
    assert [(e.step, e.value) for e in acc.Scalars("train/pretrain_last")] == [
        (first, pytest.approx(rows[first]["pretrain_last"], rel=1e-6))]
    # Resumed before it: the first block runs again, so its line goes, and with it the file.
    RunLogger(tmp_path, {}, dim, checkpoint_every=1000, start=first).close()
    assert not (tmp_path / EXTRAS).exists()


def test_an_edited_block_extras_line_is_named(tmp_path):
    path = tmp_path / EXTRAS
    path.write_text('{"interaction": 2, "pretrain_first": 1.5}\n{"interaction": "x"}\n')
    with pytest.raises(ValueError, match=r"line 2 .*integer 'interaction'"):
        read_extras(path)
    assert read_extras(path.with_name("absent.jsonl")) == []


def _rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(f)]


@pytest.mark.slow
def test_cli_train_and_resume_give_the_numbers_of_an_uninterrupted_run(tmp_path, monkeypatch):
    """One uninterrupted CLI run; a copy of its folder taken at the checkpoint after
    interaction 4 (learning and pretraining already under way) is resumed to the end."""
    cfg = tmp_path / "fast.yaml"
    cfg.write_text(yaml.safe_dump(FAST))
    run = tmp_path / "full" / "Driving2D-v0" / "slac" / "seed_0"
    copy = tmp_path / "cut" / "Driving2D-v0" / "slac" / "seed_0"
    original_log = RunLogger.log

    def copying_log(self, row, agent, stream):
        original_log(self, row, agent, stream)
        if row["interaction"] == 3:  # just checkpointed at 4 interactions
            shutil.copytree(run, copy)

    def lili_train(out, *extra):
        return cli.main(["train", "driving-2d", "--algo", "slac", "--interactions", "8",
                         "--out", str(out), "--config", str(cfg), "--no-progress", *extra])

    monkeypatch.setattr(RunLogger, "log", copying_log)
    assert lili_train(tmp_path / "full") == 0
    monkeypatch.setattr(RunLogger, "log", original_log)
    assert len(_rows(copy / "metrics.csv")) == 4
    assert lili_train(tmp_path / "cut", "--resume") == 0
    full = _rows(run / "metrics.csv")
    assert full[-1]["critic_loss"] != "" and full[-1]["rep_loss"] != ""
    assert _rows(copy / "metrics.csv") == full
    assert read_extras(copy / EXTRAS) == read_extras(run / EXTRAS) != []
    assert lili_train(tmp_path / "full") == 2  # an existing run is not overwritten


def _variant_batches(algo: str):
    """A tiny SLAC variant ``algo`` (same model as a tiny SLAC's), and the RL batches it and SLAC
    build from one labelled buffer with one key (model batches left out)."""
    variant = make_agent(algo, gym.make("lili/PointMass-v0"),
                         AgentConfig.from_dict({**FAST, "extra": {algo: TINY}}))
    plain = _tiny()
    assert isinstance(variant, SLAC) and variant.algo == algo
    jax.tree.map(np.testing.assert_array_equal, variant.state.aux["slac"], plain.state.aux["slac"])
    buf = _labelled_buffer([12, 5, 12, 9, 3, 12], horizon=plain.core.horizon)
    args = (buf.arrays, jnp.asarray(buf.count), jax.random.PRNGKey(5))
    return variant, *({k: np.asarray(v) for k, v in agent.core._batch(agent.state, *args).items()
                       if k != "model"} for agent in (variant, plain))


def _frames_at_t_and_next(variant, out):
    """The network frames of the batch's observations at t and at t + 1 (the next interaction's
    first after an interaction's last step), from the labelled buffer's (k, s) observations."""
    core, norm = variant.core, variant.state.norm
    k_of = np.broadcast_to(out["index"][:, None], out["t"].shape).astype(np.float32)
    t = out["t"].astype(np.float32)
    at_t = core._x(norm, jnp.stack([k_of, t], -1), t)
    nxt = np.where(out["last"][..., None], core._x(norm, jnp.stack([k_of + 1, 0 * t], -1), 0.0),
                   core._x(norm, jnp.stack([k_of, t + 1], -1), t + 1))
    assert out["last"].any() and (~out["last"]).any()
    return np.asarray(at_t), nxt


def test_the_obs_critic_variant_reads_slacs_critic_input_and_the_frame_at_t():
    """slac-obs-critic (lili.contrib.slac): its critic input is SLAC's ([z, phase]) followed by
    the network frame of the observation at t; the target's, by the frame at t + 1, or the next
    interaction's first frame after an interaction's last step."""
    variant, out, ref = _variant_batches("slac-obs-critic")
    dx = variant.core.x_dim
    assert out["x_critic"].shape[-1] == ref["x_critic"].shape[-1] + dx
    assert variant.core._input_dims()[0] == out["x_critic"].shape[-1]
    np.testing.assert_array_equal(out["x_critic"][..., :-dx], ref["x_critic"])
    np.testing.assert_array_equal(out["x_critic_next"][..., :-dx], ref["x_critic_next"])
    at_t, nxt = _frames_at_t_and_next(variant, out)
    np.testing.assert_allclose(out["x_critic"][..., -dx:], at_t, rtol=1e-6)
    np.testing.assert_allclose(out["x_critic_next"][..., -dx:], nxt, rtol=1e-6)


def test_the_frame_critic_variant_reads_the_frame_at_t_and_no_latent():
    """slac-frame-critic (lili.contrib.slac): its critic reads the network frame at t (the
    target's at t + 1, or the next interaction's first), as SAC's; its actor inputs are SLAC's."""
    variant, out, ref = _variant_batches("slac-frame-critic")
    assert variant.core._input_dims() == (variant.core.x_dim, ref["x_actor"].shape[-1])
    at_t, nxt = _frames_at_t_and_next(variant, out)
    np.testing.assert_allclose(out["x_critic"], at_t, rtol=1e-6)
    np.testing.assert_allclose(out["x_critic_next"], nxt, rtol=1e-6)
    for key in ("x_actor", "x_actor_next"):
        np.testing.assert_array_equal(out[key], ref[key])


def test_posterior_without_sampling_is_the_filter_on_means():
    """``posterior(..., sample=False)``: each z1 is q(z1)'s mean and each z2 the transition's
    mean given the z1 and z2 before it; the key changes nothing."""
    agent = _tiny()
    core, params = agent.core, agent.state.aux["slac"]
    rng = np.random.default_rng(0)
    x = jnp.asarray(rng.normal(size=(3, 4, core.x_dim)), jnp.float32)
    a = jnp.asarray(rng.uniform(-1, 1, size=(3, 3, core.act_dim)), jnp.float32)
    z1, z2, m1, _ = core.posterior(params, x, a, jax.random.PRNGKey(0), sample=False)
    again = core.posterior(params, x, a, jax.random.PRNGKey(1), sample=False)
    jax.tree.map(np.testing.assert_array_equal, (z1, z2), again[:2])
    np.testing.assert_array_equal(z1, m1)
    m2, _ = core.lvm.apply(params, z1[:, 1], z2[:, 0], a[:, 0], method=LatentModel.z2_transition)
    np.testing.assert_allclose(z2[:, 1], m2, rtol=1e-6)
    sampled = core.posterior(params, x, a, jax.random.PRNGKey(0))
    assert not np.allclose(sampled[0], z1)


def test_the_mean_critic_variant_reads_the_filter_on_means():
    """slac-mean-critic (lili.contrib.slac): its critic reads z_t of the filter run on means over
    the same window SLAC's samples from, with the phase; its actor inputs are SLAC's."""
    variant, out, ref = _variant_batches("slac-mean-critic")
    core = variant.core
    assert out["x_critic"].shape == ref["x_critic"].shape
    assert not np.allclose(out["x_critic"], ref["x_critic"])
    for key in ("x_actor", "x_actor_next"):
        np.testing.assert_array_equal(out[key], ref[key])
    # Rebuild the batch's windows as _batch draws them (its first key of four).
    buf = _labelled_buffer([12, 5, 12, 9, 3, 12], horizon=core.horizon)
    k_rl = jax.random.split(jax.random.PRNGKey(5), 4)[0]
    seq = sample_sequences(buf.arrays, jnp.asarray(buf.count), k_rl, FAST["batch_interactions"],
                           FAST["per_interaction"], K)
    norm, (b, m) = variant.state.norm, seq["t"].shape
    x_win = core._frames_x(norm, seq["win_obs"], seq["win_t"], seq["win_valid"])
    z1, z2, _, _ = core.posterior(variant.state.aux["slac"], x_win.reshape(b * m, K + 1, -1),
                                  seq["win_act"].reshape(b * m, K, -1), jax.random.PRNGKey(9),
                                  sample=False)
    z = jnp.concatenate([z1, z2], -1).reshape(b, m, K + 1, -1)
    z_t = jnp.take_along_axis(z, seq["pos"][..., None, None], 2)[..., 0, :]
    np.testing.assert_array_equal(out["t"], np.asarray(seq["t"]))
    np.testing.assert_allclose(out["x_critic"][..., :-1], np.asarray(z_t), rtol=1e-5, atol=1e-6)


def test_the_frame_actor_variant_reads_the_current_frame_and_keeps_slacs_model_and_critic():
    """slac-frame-actor (lili.contrib.slac): its actor reads the last of SLAC's K frames and no
    action, in training and acting alike; its critic inputs and model are SLAC's."""
    variant, out, ref = _variant_batches("slac-frame-actor")
    core, dx = variant.core, variant.core.x_dim
    assert core._input_dims() == (ref["x_critic"].shape[-1], dx)
    for key in ("x_critic", "x_critic_next"):
        np.testing.assert_array_equal(out[key], ref[key])
    for key in ("x_actor", "x_actor_next"):  # SLAC's: K frames, then K - 1 actions
        np.testing.assert_array_equal(out[key], ref[key][..., (K - 1) * dx:K * dx])
    state = variant.initial_state()
    for t in range(3):
        obs = np.array([t + 1.0, -1.0 - t], np.float32)
        x = core.history_x(variant.state.norm, *core.acting_input(obs, state))
        np.testing.assert_array_equal(np.asarray(x), np.asarray(
            core._x(variant.state.norm, jnp.asarray(obs), jnp.asarray(float(t)))))
        _, state = variant.predict(obs, state, deterministic=False, key=jax.random.PRNGKey(t))
