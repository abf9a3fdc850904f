"""Air hockey in MuJoCo: the striker's mode table, blocks, the left bonus, physics, rendering."""

from __future__ import annotations

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


def test_checkers_and_render() -> None:
    gym_check_env(AirHockeyEnv(), skip_render_check=True)
    check_env(gym.make("lili/AirHockey-v0"))
    env = AirHockeyEnv(render_mode="rgb_array")
    env.reset(seed=0)
    a = env.render()
    for _ in range(5):
        env.step(np.array([1.0], np.float32))
    b = env.render()
    assert a.shape == (440, 240, 3) and a.dtype == np.uint8 and (a != b).any()
    env.close()


@pytest.mark.parametrize("kwargs, match", [
    ({"aim_noise": -0.1}, "aim_noise=-0.1"),
    ({"aim_noise": 1.0}, "aim_noise=1.0"),
    ({"bank_shots": "yes"}, "bank_shots='yes'"),
])
def test_bad_kwargs(kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        AirHockeyEnv(**kwargs)
