"""Air hockey in MuJoCo: the striker's mode table, blocks, the left bonus, physics, rendering."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

import lili.envs  # noqa: F401
from lili.envs.air_hockey.env import (
    EGO_Y,
    HALF_WIDTH,
    LEFT,
    MIDDLE,
    PUCK_RADIUS,
    RIGHT,
    TARGET_X,
    AirHockeyEnv,
)
from lili.envs.checker import check_env


def _shot(env: AirHockeyEnv, mode: int, policy) -> dict:
    """Play one shot of ``mode`` with ``policy(env) -> action``; record the puck's path."""
    if env.interaction < 0:
        env.reset(seed=0)
    env.partner.mode = mode
    env.reset()
    xs, ret = [], 0.0
    while True:
        obs, r, term, trunc, info = env.step(np.array([policy(env)], np.float32))
        xs.append(env.puck[0])
        ret += r
        if term or trunc:
            break
    return {"ret": ret, "r_last": r, "success": info["success"], "xs": np.array(xs),
            "puck": env.puck, "paddle": env.paddle_x, "steps": env.t, "term": term}


def _go_to(x: float):
    return lambda env: np.clip(10.0 * (x - env.paddle_x), -1.0, 1.0)


@pytest.mark.parametrize("mode, side, nxt", [
    (LEFT, -1, MIDDLE), (LEFT, +1, RIGHT),
    (MIDDLE, -1, LEFT), (MIDDLE, +1, RIGHT),
    (RIGHT, -1, MIDDLE), (RIGHT, +1, LEFT),
])
def test_mode_table_with_the_puck_placed_by_hand(mode, side, nxt) -> None:
    env = AirHockeyEnv(aim_noise=0.0)
    env.reset(seed=0)
    env.partner.mode = mode
    d = env.data
    d.qpos[env._ego_q] = 0.1
    d.qpos[env._puck_q] = [0.1 + side * 0.2, EGO_Y]
    outcome = env._outcome()
    assert outcome == side
    env.partner.update(outcome, np.random.default_rng(0))
    assert env.partner.mode == nxt


def test_mode_table_end_to_end() -> None:
    env = AirHockeyEnv(aim_noise=0.0)
    # A middle shot with the paddle moved to the right: the puck passes left of it -> left.
    _shot(env, MIDDLE, _go_to(0.3))
    assert env.partner.mode == LEFT


def test_each_mode_arrives_in_its_own_region_and_banks_stay_on_the_table() -> None:
    env = AirHockeyEnv(aim_noise=0.0)
    for mode in (LEFT, MIDDLE, RIGHT):
        away = 0.4 if mode != RIGHT else -0.4  # out of the shot's way
        rec = _shot(env, mode, _go_to(away))
        assert not rec["success"] and rec["term"]
        assert rec["puck"][0] == pytest.approx(TARGET_X[mode], abs=0.05)
        assert np.all(np.abs(rec["xs"]) <= HALF_WIDTH - PUCK_RADIUS + 0.01)
        assert 10 <= rec["steps"] <= 30  # decisions per shot
    # The bank shots really bounce: the puck's lateral motion reverses once.
    rec = _shot(env, LEFT, _go_to(0.4))
    assert rec["xs"].min() < -0.4 and rec["xs"][-1] > rec["xs"].min() + 0.1


def test_block_detection_and_the_left_bonus() -> None:
    env = AirHockeyEnv(aim_noise=0.0)
    rewards = {}
    for mode in (LEFT, MIDDLE, RIGHT):
        rec = _shot(env, mode, _go_to(TARGET_X[mode]))
        assert rec["success"] and rec["term"]
        rewards[mode] = rec["r_last"]
    assert rewards[MIDDLE] == pytest.approx(1.0, abs=0.01)
    assert rewards[RIGHT] == pytest.approx(1.0, abs=0.01)
    assert rewards[LEFT] == pytest.approx(2.0, abs=0.01)
    # A still paddle in the middle blocks the middle shot only.
    assert [_shot(env, m, lambda e: 0.0)["success"] for m in (LEFT, MIDDLE, RIGHT)] == [
        False, True, False]


def test_action_moves_the_paddle_through_the_actuator() -> None:
    env = AirHockeyEnv()
    env.reset(seed=0)
    x0 = env.paddle_x
    env.step(np.array([1.0], np.float32))
    assert env.data.ctrl[env._ego_act] > 0
    x1 = env.paddle_x
    # A velocity servo accelerates the paddle: it moves, but no further than full speed allows.
    assert 0 < x1 - x0 <= env._ego_speed * env.dt + 1e-6
    for _ in range(3):
        env.step(np.array([-1.0], np.float32))
    assert env.paddle_x < x1


def test_reset_seed_replays_the_sequence() -> None:
    def play(seed: int) -> list:
        env = AirHockeyEnv(aim_noise=0.05)
        env.reset(seed=seed)
        out = []
        for _ in range(4):
            done = False
            while not done:
                obs, r, term, trunc, info = env.step(np.array([0.3], np.float32))
                done = term or trunc
            out.append((info["strategy_id"], r, tuple(obs)))
            env.reset()
        return out

    assert play(3) == play(3)
    assert play(3) != play(4)


def test_lapses_leave_the_table_and_lapse_zero_is_the_appendix_striker() -> None:
    from lili.envs.air_hockey.env import NEXT_MODE, StrikerPartner

    def modes(partner: StrikerPartner, outcomes) -> list:
        rng = np.random.default_rng(5)
        partner.reset(rng)
        out = [partner.mode]
        for o in outcomes:
            partner.update(o, rng)
            out.append((partner.mode, partner.aim_offset))
        return out

    outcomes = [(-1) ** k for k in range(600)]
    plain = modes(StrikerPartner(0.05), outcomes)
    assert modes(StrikerPartner(0.05, lapse=0.0), outcomes) == plain  # the same stream
    lapsing = modes(StrikerPartner(0.05, lapse=0.3), outcomes)
    follows = [NEXT_MODE[(prev if k == 0 else prev[0], o)] == nxt[0]
               for k, (prev, nxt, o) in enumerate(zip(lapsing[:-1], lapsing[1:], outcomes,
                                                      strict=True))]
    # A lapse draws uniformly, so the table's mode still comes 1/3 of the time: 0.7 + 0.1.
    assert 0.72 < np.mean(follows) < 0.88
    always = modes(StrikerPartner(0.0, lapse=1.0), outcomes)
    counts = np.bincount([m if k == 0 else m[0] for k, m in enumerate(always)], minlength=3)
    assert counts.min() > 150


def test_checkers_and_render() -> None:
    gym_check_env(AirHockeyEnv(), skip_render_check=True)
    check_env(gym.make("lili/AirHockey-v0"))
    check_env(gym.make("lili/AirHockey-v0", lapse=0.1, aim_noise=0.03))
    env = AirHockeyEnv(render_mode="rgb_array")
    env.reset(seed=0)
    a = env.render()
    for _ in range(5):
        env.step(np.array([1.0], np.float32))
    b = env.render()
    assert a.shape == (440, 240, 3) and a.dtype == np.uint8 and (a != b).any()
    env.close()


def test_reveal_side_shows_the_outcome_in_the_last_observation_only() -> None:
    plain, shown = AirHockeyEnv(aim_noise=0.03), AirHockeyEnv(aim_noise=0.03, reveal_side=True)
    assert shown.observation_space.shape == (3,)
    check_env(gym.make("lili/AirHockey-v0", reveal_side=True))
    rng = np.random.default_rng(0)
    sides = set()
    for k in range(12):
        (a, ia), (b, ib) = (e.reset(seed=3) if k == 0 else e.reset() for e in (plain, shown))
        assert ia["strategy_id"] == ib["strategy_id"] and b[2] == 0.0
        np.testing.assert_array_equal(a, b[:2])
        while True:
            act = rng.uniform(-1, 1, 1).astype(np.float32)
            (a, ra, ta, ua, _), (b, rb, tb, ub, info) = plain.step(act), shown.step(act)
            np.testing.assert_array_equal(a, b[:2])
            assert (ra, ta, ua) == (rb, tb, ub)  # the same game, only one more number
            if tb or ub:
                break
            assert b[2] == 0.0
        assert b[2] == info["outcome"]
        sides.add(info["outcome"])
    assert sides == {-1, 1}


@pytest.mark.parametrize("kwargs, match", [
    ({"aim_noise": -0.1}, "aim_noise=-0.1"),
    ({"aim_noise": 1.0}, "aim_noise=1.0"),
    ({"bank_shots": "yes"}, "bank_shots='yes'"),
    ({"reveal_side": 1}, "reveal_side=1 is invalid; allowed: True or False"),
])
def test_bad_kwargs(kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        AirHockeyEnv(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"aim_noise": float("nan")}, "aim_noise=nan"),
    ({"aim_noise": True}, "aim_noise=True"),
    ({"aim_noise": "0.1"}, "aim_noise='0.1'"),
    ({"lapse": 1.5}, "lapse=1.5 is invalid; allowed: a number in \\[0, 1\\]"),
    ({"lapse": True}, "lapse=True"),
])
def test_more_bad_kwargs(kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        AirHockeyEnv(**kwargs)


def _rates(policy, n: int, seed: int) -> tuple[float, np.ndarray]:
    """Block rate and mode frequencies over ``n`` interactions of ``policy(obs, mode)``."""
    env = AirHockeyEnv()
    _, info = env.reset(seed=seed)
    blocks, modes = 0, []
    for i in range(n):
        if i:
            _, info = env.reset()
        mode = info["strategy_id"]
        modes.append(mode)
        obs = np.array([env.paddle_x], np.float32)
        while True:
            obs, _, term, trunc, step_info = env.step(policy(obs, mode))
            if term or trunc:
                break
        blocks += step_info["success"]
    return blocks / n, np.bincount(modes, minlength=3) / n


def test_a_policy_that_knows_the_mode_blocks_and_a_still_paddle_blocks_about_a_third() -> None:
    def knows(obs, mode):  # a P-controller to the mode's arrival point, from the observation
        return np.array([np.clip((TARGET_X[mode] - obs[0]) / 0.04, -1, 1)], np.float32)

    rate, _ = _rates(knows, 150, seed=1)
    assert rate >= 0.9
    rate, freq = _rates(lambda obs, mode: np.zeros(1, np.float32), 150, seed=1)
    # A still paddle blocks only middle shots; the table then sends the striker
    # middle -> left/right, left -> middle, right -> left, so middle is 2/5 of the shots.
    assert 0.25 <= rate <= 0.5
    assert rate == pytest.approx(freq[MIDDLE], abs=0.02)


def test_noisy_shots_land_in_disjoint_regions_and_noise_replays() -> None:
    env = AirHockeyEnv()  # default aim noise
    arrivals = {LEFT: [], MIDDLE: [], RIGHT: []}
    for mode in (LEFT, MIDDLE, RIGHT):
        for _ in range(8):
            away = 0.45 if mode != RIGHT else -0.45
            arrivals[mode].append(_shot(env, mode, _go_to(away))["puck"][0])
    for mode, xs in arrivals.items():
        xs = np.array(xs)
        assert xs.std() > 0.005  # the noise is there
        # Within half the 0.3 m spacing of the targets: the three regions cannot overlap.
        assert np.all(np.abs(xs - TARGET_X[mode]) < 0.15), (mode, xs)

    def offsets(seed: int) -> list[float]:
        e = AirHockeyEnv(aim_noise=0.05)
        e.reset(seed=seed)
        out = [e.partner.aim_offset]
        for _ in range(3):
            while True:
                *_, term, trunc, _ = e.step(np.zeros(1, np.float32))
                if term or trunc:
                    break
            e.reset()
            out.append(e.partner.aim_offset)
        return out

    first = offsets(7)
    assert first == offsets(7) and len(set(first)) == len(first)
    assert first != offsets(8)


def test_bank_shots_stay_inside_the_walls_at_every_mujoco_step() -> None:
    import mujoco

    env = AirHockeyEnv(aim_noise=0.0)
    env.reset(seed=0)
    for mode, side in ((LEFT, -1.0), (RIGHT, 1.0)):
        env.partner.mode = mode
        env.reset()
        env.data.ctrl[env._striker_act] = 0.0
        xs, vxs = [], []
        while env.puck[1] > EGO_Y:
            mujoco.mj_step(env.model, env.data)
            xs.append(env.puck[0])
            vxs.append(env.data.qvel[env._puck_q[0]])
        xs, vxs = np.array(xs), np.array(vxs)
        # Soft contacts let the puck sink a few millimetres into the wall, never through it.
        assert np.max(side * xs) <= HALF_WIDTH - PUCK_RADIUS + 0.006
        assert side * vxs[5] > 0 and side * vxs[-1] < 0  # toward the wall, then back


def test_a_blocked_interaction_ends_at_the_touch() -> None:
    env = AirHockeyEnv(aim_noise=0.0)
    rec = _shot(env, RIGHT, _go_to(TARGET_X[RIGHT]))
    assert rec["success"] and rec["term"]
    gap = np.hypot(rec["puck"][0] - rec["paddle"], rec["puck"][1] - EGO_Y)
    assert gap <= 0.09 + 1e-3  # puck and paddle radii: in contact, not after the rebound
    assert rec["puck"][1] > EGO_Y  # stopped before the line


def test_registration_spaces_and_render_modes() -> None:
    from lili.envs import resolve_env_id

    assert resolve_env_id("air-hockey") == "lili/AirHockey-v0"
    env = gym.make("lili/AirHockey-v0")
    obs, info = env.reset(seed=0)
    assert obs.shape == (2,) and obs.dtype == np.float32
    assert info["strategy"].dtype == np.float32 and info["strategy"].sum() == 1.0
    assert info["strategy"][info["strategy_id"]] == 1.0
    assert env.unwrapped.render() is None  # no render_mode
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rendering = gym.make("lili/AirHockey-v0", render_mode="rgb_array")
        gym_check_env(rendering.unwrapped)  # with the render checks this time
    rendering.close()


def test_the_scripted_influencer_beats_the_greedy_blocker_by_a_tenth() -> None:
    # The default game is one where influence pays (the env's docstring has the full table): the
    # influencer drives the striker into the left/middle cycle, the greedy blocker leaves the
    # modes to the aim noise. Both are told the mode and block (almost) every shot.
    from lili.envs.air_hockey.scripted import GreedyBlocker, InfluencingBlocker
    from lili.envs.influence.scripted import play

    greedy = play(AirHockeyEnv(), GreedyBlocker(), 250, seed=0).last(200)
    influencer = play(AirHockeyEnv(), InfluencingBlocker(), 250, seed=0).last(200)
    assert influencer.mean_return() >= greedy.mean_return() + 0.1
    assert influencer.success_rate() >= 0.98 and greedy.success_rate() >= 0.98
    left, middle, right = influencer.strategy_frequencies(3)
    assert left >= 0.45 and right <= 0.05
    # Greedy leaves the striker near uniform: no mode above 45% or below 22%.
    freq = greedy.strategy_frequencies(3)
    assert freq.max() <= 0.45 and freq.min() >= 0.22, freq


def test_the_predictor_told_the_last_mode_and_side_blocks_all_but_the_lapses() -> None:
    # The striker's next mode is the table's function of the last mode and side, so without
    # lapses the predictor blocks as the told greedy blocker does (it holds the middle on the
    # first shot, with nothing to predict from); with lapses it loses about 2/3 of them.
    from lili.envs.air_hockey.scripted import PredictingBlocker
    from lili.envs.influence.scripted import play
    from lili.envs.wrappers import LastInteractionObservation

    def rate(**kwargs) -> float:
        env = LastInteractionObservation(AirHockeyEnv(**kwargs), outcome=True)
        return play(env, PredictingBlocker(), 150, seed=1).last(149).success_rate()

    assert rate() >= 0.98
    assert 0.75 <= rate(lapse=0.3) <= 0.9
    with pytest.raises(ValueError, match="needs the 9 numbers .* shape \\(2,\\)"):
        PredictingBlocker()(np.zeros(2, np.float32), {})


def test_the_old_game_is_one_kwarg_away() -> None:
    assert AirHockeyEnv().partner.aim_noise == 0.01
    assert AirHockeyEnv(aim_noise=0.02).partner.aim_noise == 0.02


def test_contact_points_lie_on_the_wall_side_of_the_crossing_points() -> None:
    from lili.envs.air_hockey.scripted import contact_points

    left, middle, right = contact_points(True)
    assert middle == pytest.approx(0.0, abs=1e-3) and left == pytest.approx(-right, abs=1e-3)
    # A bank shot comes back from the wall at an angle, so it touches 1-5 cm before it crosses.
    assert 0.01 < TARGET_X[LEFT] - left < 0.05
