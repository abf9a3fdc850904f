"""The JAX-native envs (``lili.envs.jax``) against their Gymnasium references.

The equivalence tests play the Gymnasium env and the JAX env side by side, step by step, with
the same actions (random, partly outside [-1, 1] so that clipping is exercised, with a drift per
interaction so that interactions end on both sides of what the partner reacts to), over several
interactions: Point Mass with the default partner, the noisy partner, the history partner and
the mirrored rule, Driving (2D) with the default and the history partner, and the influence
suite's Drift and Switch.

Aligned: the partner's *random numbers*. NumPy and JAX generators differ, so the JAX env is
driven through ``reset_with`` / ``step_with`` with the numbers the Gymnasium env's partner
generator draws: the first strategy's grid index (read off the Gymnasium partner after
``reset(seed)``) and, before every step, the draws of an update taken from a *copy* of the
Gymnasium env's partner generator (the Gymnasium partner then draws the same numbers from the
original when the interaction ends). Everything downstream of those numbers is computed by each
env on its own and compared: observations (after reset, every step and every new
interaction), rewards, ``terminated``, ``truncated``, the strategy and strategy id in ``info``
(so the whole sequence of strategies, i.e. every partner update: direction, majority vote,
noise scaling, drift, returns, mode table), the ``interaction`` and ``t`` counters and the
``outcome`` and ``success`` (where defined) at each interaction's end. Floats to 1e-5 (JAX
works in float32, the references in float64); everything else exactly.

Not compared there: how the JAX env draws its own random numbers from a key (``reset`` /
``step``); the separate tests below check that those draws have the references' ranges and
distributions, that ``step`` is ``step_with`` of ``update_draws``, and that jit, vmap and scan
give the same numbers as single steps.
"""

from __future__ import annotations

import copy

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from lili.envs.driving2d import Driving2DEnv
from lili.envs.influence.drift import InfluenceDriftEnv
from lili.envs.influence.flee import InfluenceFleeEnv
from lili.envs.influence.switch import InfluenceSwitchEnv
from lili.envs.jax import (
    Driving2D,
    InfluenceDrift,
    InfluenceFlee,
    InfluenceSwitch,
    PointMass,
    UniformPolicy,
    make,
    rollout,
    rollout_many,
    stack,
)
from lili.envs.jax import drift as jdrift
from lili.envs.jax import driving2d as jdriving
from lili.envs.jax import flee as jflee
from lili.envs.jax import point_mass as jpm
from lili.envs.jax import switch as jswitch
from lili.envs.jax.core import JaxRepeatedEnv
from lili.envs.point_mass import STEP, PointMassEnv

# One compiled function per env class and shapes, shared by the cases (the env is static).
# Called on the env (not JaxRepeatedEnv's functions): the Oracles' wrappers are played too.
reset_with = jax.jit(lambda env, *args: env.reset_with(*args), static_argnums=0)
step_with = jax.jit(lambda env, *args: env.step_with(*args), static_argnums=0)
next_interaction = jax.jit(lambda env, *args: env.next_interaction(*args), static_argnums=0)
step = jax.jit(JaxRepeatedEnv.step, static_argnums=0)
rollout_one = jax.jit(rollout, static_argnums=(0, 1, 4, 5))


def _pm_reset(env):
    return jpm.ResetDraws(index=jnp.asarray(round(env.partner.theta / STEP), jnp.int32))


def _pm_update(rng):
    return jpm.UpdateDraws(z=jnp.asarray(rng.standard_normal(), jnp.float32))


def _drift_update(rng):
    u = rng.random()
    return jdrift.UpdateDraws(u=jnp.asarray(u, jnp.float32),
                              side=jnp.asarray(rng.integers(2), jnp.int32))


PM = (PointMassEnv, PointMass(), _pm_reset, _pm_update)
DRIFT = (InfluenceDriftEnv, InfluenceDrift(),
         lambda env: jdrift.ResetDraws(index=jnp.asarray(env.partner.index, jnp.int32)),
         _drift_update)
SWITCH = (InfluenceSwitchEnv, InfluenceSwitch(),
          lambda env: jswitch.ResetDraws(mode=jnp.asarray(env.partner.mode, jnp.int32)),
          lambda rng: ())


def _flee_reset(env):
    k = env.partner.k  # the draw's index: slots below home first, then those above
    return jflee.ResetDraws(index=jnp.asarray(k + 4 if k < 0 else k + 3, jnp.int32))


FLEE = (InfluenceFleeEnv, InfluenceFlee(), _flee_reset, lambda rng: ())

DRIVING = (Driving2DEnv, Driving2D(),
           lambda env: jdriving.ResetDraws(right=jnp.asarray(env.partner.lane > 0)),
           lambda rng: ())

CASES = {
    "point-mass": (PM, {}, 5),
    "noise": (PM, {"step_noise": 0.6, "horizon": 10}, 12),
    "history": (PM, {"history": 3, "horizon": 10}, 16),
    "history-noise-mirrored": (PM, {"history": 4, "step_noise": 0.2, "horizon": 10,
                                    "inside_turn": "counterclockwise"}, 16),
    "drift": (DRIFT, {}, 30),
    "drift-returns": (DRIFT, {"returns": 0.5, "horizon": 5}, 30),
    "switch": (SWITCH, {}, 40),
    "flee": (FLEE, {}, 60),
    "flee-horizon": (FLEE, {"horizon": 6}, 40),
    "driving-2d": (DRIVING, {}, 12),
    "driving-2d-history": (DRIVING, {"history": 3}, 20),
}


def _close(a, b, what):
    np.testing.assert_allclose(np.asarray(a, np.float64), np.asarray(b, np.float64), atol=1e-5,
                               rtol=0, err_msg=what)


def _play_both(case: str, seed: int = 3, wrap_gym=None, wrap_jax=None):
    """Play both envs side by side (see the module docstring); return the per-interaction
    outcomes, successes and strategies for the checks that the case exercised something.
    ``wrap_gym`` / ``wrap_jax``: what an agent observes of each (the Oracles' wrappers), whose
    observations are then the ones compared."""
    (gym_cls, jenv, reset_draws, update_draws), kwargs, n = CASES[case]
    inner = gym_cls(**kwargs)
    genv = wrap_gym(inner) if wrap_gym else inner
    jenv = wrap_jax(jenv) if wrap_jax else jenv
    params = jenv.params(**kwargs)
    rng = np.random.default_rng(seed)
    g_obs, g_info = genv.reset(seed=seed)
    j_obs, state = reset_with(jenv, reset_draws(inner), params)
    outcomes, successes, strategies = [], [], []
    for i in range(n):
        if i:
            g_obs, g_info = genv.reset()
            j_obs, state = next_interaction(jenv, jax.random.PRNGKey(0), state, params)
        _close(j_obs, g_obs, f"{case}: first obs of interaction {i}")
        info = jenv.info(state, params)
        _close(info["strategy"], g_info["strategy"], f"{case}: strategy at start of {i}")
        assert int(info["strategy_id"]) == g_info["strategy_id"]
        assert int(info["interaction"]) == g_info["interaction"] == i
        strategies.append(np.asarray(g_info["strategy"]))
        # A drift that ends some interactions a long way out and others near the start.
        drift = rng.uniform(-1, 1, genv.action_space.shape) * min(1.0, 10 / inner.horizon)
        while True:
            action = np.clip(drift + rng.uniform(-1, 1, drift.shape), -1.5, 1.5).astype(
                np.float32)
            draws = update_draws(copy.deepcopy(inner._partner_rng))
            g_obs, g_r, g_term, g_trunc, g_info = genv.step(action)
            j_obs, state, j_r, j_done, j_info = step_with(jenv, draws, state, action, params)
            where = f"{case}: interaction {i} step {g_info['t']}"
            _close(j_obs, g_obs, where + " obs")
            _close(j_r, g_r, where + " reward")
            assert (bool(j_info["terminated"]), bool(j_info["truncated"]), bool(j_done)) \
                == (g_term, g_trunc, g_term or g_trunc), where
            _close(j_info["strategy"], g_info["strategy"], where + " strategy")
            assert int(j_info["strategy_id"]) == g_info["strategy_id"], where
            assert (int(j_info["interaction"]), int(j_info["t"])) \
                == (g_info["interaction"], g_info["t"]), where
            assert bool(j_info["active"])
            if g_term or g_trunc:
                assert j_info["outcome"].item() == g_info["outcome"], where + " outcome"
                assert ("success" in j_info) == ("success" in g_info), where
                if "success" in g_info:
                    assert bool(j_info["success"]) == g_info["success"], where + " success"
                outcomes.append(g_info["outcome"])
                successes.append(g_info.get("success"))
                break
    return outcomes, successes, np.array(strategies)


@pytest.mark.parametrize("case", list(CASES))
def test_jax_env_follows_the_gymnasium_env(case: str) -> None:
    outcomes, successes, strategies = _play_both(case)
    # The case exercised the partner: both kinds of ending, and the strategy moved.
    assert len(set(outcomes)) >= (3 if case.startswith(("switch", "flee")) else 2), outcomes
    if case.startswith("driving"):
        assert len(set(successes)) == 2, successes
    if case == "flee":  # home, both sides, and a slip past from a wall
        g = strategies[:, 0]
        assert (g == 0).any() and (g > 0).any() and (g < 0).any()
        assert (np.abs(np.diff(g)) > 1).any()
    assert len({tuple(s) for s in strategies}) >= 2
    kwargs = CASES[case][1]
    if kwargs.get("step_noise"):  # noisy steps leave the 0.2 grid
        theta = np.arctan2(strategies[:, 1] + 0.05, strategies[:, 0]) / STEP
        assert np.abs(theta - np.round(theta)).max() > 0.05
    if kwargs.get("history", 1) > 1:  # the majority overruled the last outcome at least once
        n, votes = kwargs["history"], np.asarray(outcomes) > 0  # inside / right
        majority = [np.mean(votes[max(0, k - n + 1):k + 1]) for k in range(len(votes))]
        assert any(m != 0.5 and (m > 0.5) != o for m, o in zip(majority, votes, strict=True))


def test_step_is_step_with_its_own_draws() -> None:
    env, params = PointMass(), PointMass().params(step_noise=0.5, horizon=3)
    key = jax.random.PRNGKey(7)
    _, state = jax.jit(env.reset)(key, params)
    assert np.isclose(float(state.partner.theta), STEP * int(env.reset_draws(key, params).index))
    for k in jax.random.split(key, 3):
        a = jnp.array([0.4, -0.9])
        got = step(env, k, state, a, params)
        want = step_with(env, env.update_draws(k, params), state, a, params)
        jax.tree.map(lambda x, y: np.testing.assert_allclose(x, y, atol=1e-6), got, want)
        state = got[1]
    assert bool(state.done) and int(state.partner.votes.n) == 1


@jax.jit
def _draws(keys):
    """Many draws of each partner (one program: the test stays fast)."""
    pm, drift, switch, flee = PointMass(), InfluenceDrift(), InfluenceSwitch(), InfluenceFlee()
    noisy = pm.params(step_noise=0.5)
    partner = pm.partner_reset(jpm.ResetDraws(jnp.asarray(5)), noisy)
    returns = drift.params(returns=0.3)

    def one(k):
        return {"pm_index": pm.reset_draws(k, noisy).index,
                # outcome False: counter-clockwise, by a step of 0.2 with sd 0.5 * 0.2
                "pm_theta": pm.partner_update(partner, jnp.asarray(False),
                                              pm.update_draws(k, noisy), noisy).theta,
                "drift_index": drift.reset_draws(k, returns).index,
                # from index 0 with the ego ending right: index 1, or 3 / 4 when it returns
                "drift_next": drift.partner_update(jnp.asarray(0), jnp.asarray(1),
                                                   drift.update_draws(k, returns), returns),
                "switch_mode": switch.reset_draws(k, None).mode,
                "flee_slot": flee.partner_reset(flee.reset_draws(k, None), None),
                "driving_right": Driving2D().reset_draws(k, None).right}

    return jax.vmap(one)(keys)


def test_the_partners_draws_have_the_references_distributions() -> None:
    d = jax.tree.map(np.asarray, _draws(jax.random.split(jax.random.PRNGKey(0), 4096)))
    assert set(d["pm_index"].tolist()) == set(range(jpm.N_ANGLES))  # rng.integers(0, 32)
    steps = d["pm_theta"] - 5 * STEP
    assert abs(steps.mean() - STEP) < 0.005 and abs(steps.std() - 0.1) < 0.005
    counts = np.bincount(d["drift_next"], minlength=8) / len(steps)
    assert abs(counts[3] + counts[4] - 0.3) < 0.03 and abs(counts[3] - counts[4]) < 0.03
    assert abs(counts[1] - 0.7) < 0.03
    assert set(d["drift_index"].tolist()) == set(range(8))
    assert set(d["switch_mode"].tolist()) == {0, 1, 2}
    # rng.integers(0, 8) over the slots away from home
    assert set(d["flee_slot"].tolist()) == {-4, -3, -2, -1, 1, 2, 3, 4}
    assert np.bincount(d["flee_slot"] + 4, minlength=9).max() < 4096 / 8 * 1.15
    assert abs(d["driving_right"].mean() - 0.5) < 0.03  # rng.choice([-1, 1])


def test_rollout_vmaps_over_seeds_and_params_and_equals_single_runs() -> None:
    env = PointMass()
    params = [env.params(), env.params(step_noise=0.4, history=3, horizon=6),
              env.params(history=5, inside_turn="counterclockwise", horizon=4)]
    keys = jax.random.split(jax.random.PRNGKey(1), 3)
    policy = UniformPolicy((2,))
    obs, state, tr = rollout_many(env, policy, keys, stack(params), 6, 5)
    assert tr.reward.shape == (3, 5, 6) and tr.obs.shape == (3, 5, 6, 2)
    for k in range(3):
        one = rollout_one(env, policy, keys[k], params[k], 6, 5)
        jax.tree.map(lambda x, y, k=k: np.testing.assert_allclose(x[k], y, atol=1e-6),
                     (obs, state, tr), one)
    # Run 0 (horizon 50) plays 6-step pieces of abandoned interactions: the partner never
    # updates. Run 2 (horizon 4) ends each interaction after 4 steps; 2 inactive steps follow.
    assert not tr.done[0].any() and np.all(np.diff(tr.info["strategy"][0, :, 0], axis=0) == 0)
    assert np.all(tr.done[1, :, -1]) and np.all(tr.info["truncated"][1, :, -1])
    active = np.asarray(tr.info["active"][2])
    assert active[:, :4].all() and not active[:, 4:].any()
    assert np.all(tr.reward[2, :, 4:] == 0) and np.all(tr.info["truncated"][2, :, 3])
    assert np.all(state.interaction == 5)


def test_a_step_after_the_end_changes_nothing() -> None:
    env = InfluenceSwitch()
    params = env.params()
    obs, state = jax.jit(env.reset)(jax.random.PRNGKey(0), params)
    for _ in range(4):
        obs, state, _, done, _ = step(env, jax.random.PRNGKey(0), state, jnp.array([1.0]), params)
    assert bool(done)
    obs2, state2, reward, done2, info = step(env, jax.random.PRNGKey(0), state, jnp.array([-1.0]),
                                             params)
    jax.tree.map(np.testing.assert_array_equal, (obs2, state2), (obs, state))
    assert float(reward) == 0 and bool(done2) and not bool(info["active"])
    assert not bool(info["terminated"]) and not bool(info["truncated"])


def test_the_jax_switch_greedy_policy_earns_its_known_return() -> None:
    """A policy told the strategy, in the scan: greedy cycles the modes, -0.5 per interaction
    (:mod:`lili.envs.influence.switch`)."""
    env = InfluenceSwitch()

    def greedy(key, obs, info):
        goal = jnp.asarray(jswitch.GOALS)[info["strategy_id"]]
        return jnp.clip((goal - obs) / env.speed, -1.0, 1.0)

    _, _, tr = rollout_one(env, greedy, jax.random.PRNGKey(0), env.params(), 4, 30)
    returns = np.asarray(tr.reward.sum(axis=1))
    assert np.allclose(returns.mean(), -0.5, atol=1e-6)


def test_the_jax_flee_partner_moves_as_the_reference_from_every_slot_and_end() -> None:
    """Every (slot, end slot) pair, the home's stay included, which random play rarely meets."""
    from lili.envs.influence.flee import fled

    k, k_end = np.meshgrid(np.arange(-4, 5), np.arange(-4, 5))
    got = np.asarray(jax.jit(jflee.fled)(jnp.asarray(k), jnp.asarray(k_end)))
    want = np.vectorize(fled)(k, k_end)
    np.testing.assert_array_equal(got, want)
    assert want[4, 4] == 0  # home, the ego stopped on it: it stays


def test_the_jax_flee_greedy_and_influencer_earn_their_known_returns() -> None:
    """Told the strategy, in the scan: greedy cycles the eight slots away from home (-0.625),
    the influencer, one slot beyond the partner on the last step, holds it home (0)
    (:mod:`lili.envs.influence.flee`)."""
    env = InfluenceFlee()

    def policy(beyond: float):
        def act(key, obs, info):
            g = info["strategy"]
            target = jnp.clip(g + jnp.where(info["t"] == 3, beyond, 0.0) * jnp.sign(g), -1, 1)
            return jnp.clip((target - obs) / env.speed, -1.0, 1.0)
        return act

    for beyond, known, held in ((0.0, -0.625, 0.0), (0.25, 0.0, 1.0)):
        _, _, tr = rollout_one(env, policy(beyond), jax.random.PRNGKey(2), env.params(), 4, 60)
        returns = np.asarray(tr.reward.sum(axis=1))[-48:]
        assert np.allclose(returns.mean(), known, atol=1e-6)
        home = np.asarray(tr.info["strategy_id"][-48:, 0]) == 4
        assert home.mean() == held


@pytest.mark.parametrize(("call", "message"), [
    (lambda: PointMass().params(history=17), "history=17 is invalid; allowed: an integer from 1"),
    (lambda: PointMass().params(step_noise=-1.0), "step_noise=-1.0 is invalid"),
    (lambda: PointMass().params(inside_turn="up"), "inside_turn='up' is invalid"),
    (lambda: InfluenceDrift().params(returns=2), "returns=2 is invalid"),
    (lambda: InfluenceSwitch().params(horizon=3), "horizon=3 is invalid; allowed: an integer >= 4"),
    (lambda: InfluenceFlee().params(horizon=3), "horizon=3 is invalid; allowed: an integer >= 4"),
    (lambda: make("influence-flee", returns=0.1),
     r"env kwargs \['returns'\] are not taken by the JAX lili/InfluenceFlee-v0; allowed: horizon"),
    (lambda: Driving2D().params(history=0), "history=0 is invalid; allowed: an integer >= 1"),
    (lambda: make("lunar-lander"), "env 'lunar-lander' has no JAX version; allowed:"),
    (lambda: make("point-mass", sigma=0.2), r"env kwargs \['sigma'\] are not taken"),
    (lambda: PointMass().step(jax.random.PRNGKey(0), PointMass().reset(
        jax.random.PRNGKey(0), PointMass().params())[1], jnp.zeros(3), PointMass().params()),
     r"action has shape \(3,\); expected \(2,\)"),
])
def test_bad_input_gets_one_clear_error(call, message) -> None:
    with pytest.raises(ValueError, match=message):
        call()


def test_make_takes_the_gymnasium_kwargs() -> None:
    env, params = make("point-mass", step_noise=0.2, history=3)
    assert isinstance(env, PointMass) and int(params.history) == 3
    env, params = make("lili/InfluenceDrift-v0", returns=0.1)
    assert isinstance(env, InfluenceDrift) and np.isclose(float(params.returns), 0.1)
