"""The influence suite: rules, registration, the contract, and the scripted policies' ranking."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import lili.envs  # noqa: F401
from lili.envs import resolve_env_id
from lili.envs.checker import check_env
from lili.envs.influence import SUITE, InfluenceDriftEnv, InfluenceSwitchEnv, make_scripted, play
from lili.envs.influence.drift import GOALS, known_returns
from lili.envs.influence.switch import LEFT, MIDDLE, NEXT_MODE, RIGHT

NEW_ENVS = {"influence-drift": "lili/InfluenceDrift-v0",
            "influence-switch": "lili/InfluenceSwitch-v0"}


def _returns(env_id: str, n: int, last: int, seed: int = 0) -> dict[str, float]:
    return {name: play(gym.make(env_id), make_scripted(env_id, name, seed), n, seed)
            .last(last).mean_return() for name in ("no-information", "greedy", "influencer")}


@pytest.mark.parametrize("alias, env_id", sorted(NEW_ENVS.items()))
def test_registered_and_pass_the_checkers(alias, env_id) -> None:
    assert resolve_env_id(alias) == env_id
    check_env(gym.make(env_id))
    # ... and from the shell, as users run it.
    out = subprocess.run([sys.executable, "-m", "lili.cli", "check-env", alias],
                         capture_output=True, text=True)
    assert out.returncode == 0 and "passes" in out.stdout, out.stderr


def test_drift_scripted_policies_meet_their_derived_returns() -> None:
    # The partner's returns are random: average 3000 interactions (~150 renewal cycles).
    r = _returns("lili/InfluenceDrift-v0", 3000, 2900)
    known = SUITE["lili/InfluenceDrift-v0"][1]
    assert known["greedy"] == pytest.approx(-0.32716, abs=1e-5)
    assert r["influencer"] == pytest.approx(known["influencer"], abs=1e-6)
    for name in ("greedy", "no-information"):
        assert r[name] == pytest.approx(known[name], abs=0.02), name
    assert r["influencer"] >= r["greedy"] + 0.12
    assert r["greedy"] >= r["no-information"] + 0.25


def test_drift_policies_that_read_only_the_last_interaction_lose_the_returns_and_no_more() -> None:
    env_id = "lili/InfluenceDrift-v0"
    told = _returns(env_id, 3000, 2900)
    last = {name: play(gym.make(env_id), make_scripted(env_id, f"{name} (last interaction)", 0),
                       3000, 0).last(2900).mean_return() for name in ("greedy", "influencer")}
    # Missing a return costs; the drift itself is fully predicted (without returns they are
    # the told policies from the second interaction on).
    assert last["greedy"] == pytest.approx(-0.47, abs=0.02)
    assert last["influencer"] == pytest.approx(-0.20, abs=0.01)
    assert told["influencer"] > last["influencer"] > last["greedy"] + 0.25
    assert told["greedy"] > last["greedy"] > told["no-information"]
    for name in ("greedy", "influencer"):
        first = play(gym.make(env_id, returns=0.0),
                     make_scripted(env_id, f"{name} (last interaction)", 0), 60, 0)
        assert first.last(50).mean_return() == pytest.approx(known_returns(0.0)[name], abs=1e-6)


def test_drift_without_returns_is_the_first_version_where_only_influence_pays() -> None:
    assert known_returns(0.0) == {"no-information": -0.375, "greedy": -0.375,
                                  "influencer": -0.175}
    env_id = "lili/InfluenceDrift-v0"
    r = {name: play(gym.make(env_id, returns=0.0), make_scripted(env_id, name, 0), 60, 0)
         .last(50).mean_return() for name in ("no-information", "greedy", "influencer")}
    for name, value in r.items():
        assert value == pytest.approx(known_returns(0.0)[name], abs=1e-6), name


def test_switch_scripted_policies_meet_their_derived_returns() -> None:
    r = _returns("lili/InfluenceSwitch-v0", 60, 50)
    known = SUITE["lili/InfluenceSwitch-v0"][1]
    for name, value in r.items():
        assert value == pytest.approx(known[name], abs=0.01), name
    assert r["influencer"] >= r["greedy"] + 0.4
    assert r["greedy"] >= r["no-information"] + 1.0


def test_point_mass_scripted_influencer_beats_greedy_beats_no_information() -> None:
    r = _returns("lili/PointMass-v0", 120, 100)
    assert r["influencer"] == pytest.approx(SUITE["lili/PointMass-v0"][1]["influencer"], abs=0.01)
    assert r["no-information"] == pytest.approx(-5.01, abs=0.05)
    # Greedy's target random-walks round the circle, so over 100 interactions its mean depends
    # on where the walk went; it cannot reach the influencer's cheapest targets on average.
    assert r["influencer"] >= r["greedy"] + 0.05
    assert r["greedy"] >= r["no-information"] + 3.0


def test_point_mass_last_interaction_influencer_is_the_influencer_without_noise() -> None:
    """Told only what the last interaction predicts, the influencer matches the one told the
    target when the partner's step is exact, and loses to it once the step is noisy."""
    from lili.envs.influence.point_mass import LastInteractionInfluencer, influencer
    from lili.envs.point_mass import PointMassEnv

    def mean_return(policy, noise: float) -> float:
        return play(PointMassEnv(step_noise=noise), policy, 120, 3).last(100).mean_return()

    exact = mean_return(LastInteractionInfluencer(), 0.0)
    # Equal up to the rounding of recovering the angle from the target (arctan2).
    assert exact == pytest.approx(mean_return(influencer, 0.0), abs=1e-6)
    assert exact > -0.11
    assert mean_return(LastInteractionInfluencer(), 0.6) < mean_return(influencer, 0.6) - 0.2


def test_point_mass_influencer_reading_the_last_n_interactions_is_the_influencer() -> None:
    """Against the partner that follows the majority of the last N ends, reading the last N
    interactions predicts the target exactly; reading only the last one does not."""
    from lili.envs.influence.point_mass import LastInteractionInfluencer, influencer
    from lili.envs.point_mass import PointMassEnv

    def mean_return(policy) -> float:
        return play(PointMassEnv(history=5), policy, 120, 3).last(100).mean_return()

    told = mean_return(influencer)
    assert mean_return(LastInteractionInfluencer(history=5)) == pytest.approx(told, abs=1e-6)
    assert mean_return(LastInteractionInfluencer()) < told - 0.2


def test_drift_rules() -> None:
    env = InfluenceDriftEnv(returns=0.0)
    obs, info = env.reset(seed=0)
    env.partner.index = 4  # g = +0.125
    obs, info = env.reset()
    assert obs.tolist() == [0.0] and info["strategy"][0] == pytest.approx(0.125)
    rewards = []
    for a in (1.0, 1.0, 1.0, 1.0):  # run right: x = 0.5, 1, 1, 1
        obs, r, term, trunc, info = env.step(np.array([a], np.float32))
        rewards.append(r)
    assert not term and trunc and env.t == 4
    assert rewards == pytest.approx([-0.375, -0.875, -0.875, -0.875])
    assert env.partner.goal() == pytest.approx(0.375)  # ended right of 0: one step right
    env.reset()
    for _ in range(4):
        env.step(np.array([-1.0], np.float32))
    assert env.partner.goal() == pytest.approx(0.125)  # ended left: one step left
    # Clipped at the outermost goals.
    env.partner.index = 0
    env.reset()
    for _ in range(4):
        env.step(np.array([-1.0], np.float32))
    assert env.partner.goal() == GOALS[0]


def test_drift_partner_returns_near_the_start_at_the_given_rate() -> None:
    env = InfluenceDriftEnv(returns=0.25)
    env.reset(seed=3)
    right = lambda o, i: np.array([1.0], np.float32)  # noqa: E731 - drifts right but for returns
    ids = play(env, right, 4000, seed=3).strategy_ids
    nxt = ids[1:][ids[:-1] == 7]  # after the right wall: the wall again or a return
    assert set(nxt.tolist()) <= {3, 4, 7}
    assert np.mean(nxt != 7) == pytest.approx(0.25, abs=0.04)
    assert abs(np.mean(nxt == 3) - np.mean(nxt == 4)) < 0.06
    always = InfluenceDriftEnv(returns=1.0)
    assert set(play(always, right, 50, seed=0).strategy_ids[1:].tolist()) <= {3, 4}


@pytest.mark.parametrize("mode, last_action, nxt", [
    (LEFT, 0.0, MIDDLE), (LEFT, -0.5, RIGHT), (LEFT, 0.5, MIDDLE),
    (MIDDLE, 0.05, RIGHT), (MIDDLE, -0.2, MIDDLE), (MIDDLE, 0.2, LEFT),
    (RIGHT, -0.1, LEFT), (RIGHT, -0.11, LEFT), (RIGHT, 0.11, MIDDLE),
])
def test_switch_rules(mode, last_action, nxt) -> None:
    env = InfluenceSwitchEnv()
    env.reset(seed=0)
    env.partner.mode = mode
    env.reset()
    for _ in range(3):
        env.step(np.array([0.3], np.float32))  # earlier actions do not matter
    *_, trunc, info = env.step(np.array([last_action], np.float32))
    assert trunc
    assert env.partner.mode == nxt == NEXT_MODE[(mode, int(np.sign(last_action))
                                                 if abs(last_action) > 0.1 else 0)]


def test_reset_seed_replays_and_the_first_strategy_comes_from_the_seed() -> None:
    for cls in (InfluenceDriftEnv, InfluenceSwitchEnv):
        firsts = {cls().reset(seed=s)[1]["strategy_id"] for s in range(20)}
        assert len(firsts) >= 3
        a = play(cls(), lambda o, i: np.array([0.4], np.float32), 5, seed=7)
        b = play(cls(), lambda o, i: np.array([0.4], np.float32), 5, seed=7)
        assert a.returns.tolist() == b.returns.tolist()
        assert a.strategy_ids.tolist() == b.strategy_ids.tolist()


def test_render() -> None:
    env = gym.make("lili/InfluenceSwitch-v0", render_mode="rgb_array")
    env.reset(seed=0)
    a = env.render()
    env.step(np.array([1.0], np.float32))
    b = env.render()
    assert a.shape == (40, 200, 3) and a.dtype == np.uint8 and (a != b).any()


@pytest.mark.parametrize("cls, kwargs, match", [
    (InfluenceDriftEnv, {"horizon": 2}, "horizon=2"),
    (InfluenceDriftEnv, {"horizon": 4.0}, "horizon=4.0"),
    (InfluenceDriftEnv, {"returns": 1.5}, r"returns=1.5 is invalid; allowed: a number in \[0, 1\]"),
    (InfluenceDriftEnv, {"returns": True}, "returns=True"),
    (InfluenceDriftEnv, {"returns": "0.1"}, "returns='0.1'"),
    (InfluenceSwitchEnv, {"horizon": 3}, "horizon=3.*integer >= 4"),
    (InfluenceSwitchEnv, {"render_mode": "human"}, "render_mode='human'"),
])
def test_bad_kwargs(cls, kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        cls(**kwargs)


def test_make_scripted_rejects_unknown_names() -> None:
    with pytest.raises(ValueError, match="'lili/Nope-v0'.*allowed: lili/InfluenceDrift-v0"):
        make_scripted("lili/Nope-v0", "greedy")
    allowed = r"allowed: no-information, greedy, influencer, greedy \(last interaction\)"
    with pytest.raises(ValueError, match=f"'smart' for lili/InfluenceDrift-v0.*{allowed}"):
        make_scripted("lili/InfluenceDrift-v0", "smart")
