"""Driving with steering (``lili/DrivingSteer-v0``): the paper's rules on highway-env's cars."""

from __future__ import annotations

import warnings
from collections.abc import Callable

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

import lili.envs  # noqa: F401 - registers the envs
from lili.envs import OracleObservation
from lili.envs.checker import check_env
from lili.envs.driving_steer import HORIZON, MAX_STEER, SCENARIO, DrivingSteerEnv
from lili.envs.steer_backend import HighwayBackend, SimState, SteerBackend

ENV_ID = "lili/DrivingSteer-v0"
LANE = SCENARIO.lane_width
LEFT, RIGHT = 0, 1
Policy = Callable[[np.ndarray, int], np.ndarray]


def keep_lane(y_target: float) -> Policy:
    """Steer to the lateral position ``y_target`` [m] from the observation (a PD on y/heading)."""

    def policy(obs: np.ndarray, t: int) -> np.ndarray:
        y, vx, vy = obs[1] * 10.0, obs[2] * 10.0, obs[3] * 10.0
        heading_wanted = np.clip(0.1 * (y_target - y), -0.25, 0.25)
        steer = 0.5 * (heading_wanted - np.arctan2(vy, vx))  # rad
        return np.array([np.clip(steer / MAX_STEER, -1.0, 1.0)], dtype=np.float32)

    return policy


def pass_on(side: int) -> Policy:
    """Pass in the left (0) or the right (1) lane."""
    return keep_lane(-LANE if side == LEFT else LANE)


def constant(a: float) -> Policy:
    return lambda obs, t: np.array([a], dtype=np.float32)


def wait_and_react() -> Policy:
    """Drive straight until the opponent moves sideways, then steer to the other side."""
    chosen: dict[str, float] = {}

    def policy(obs: np.ndarray, t: int) -> np.ndarray:
        opp_y = obs[6] * 10.0
        if "y" not in chosen and abs(opp_y) > 0.05:
            chosen["y"] = -np.sign(opp_y) * LANE
        return keep_lane(chosen.get("y", 0.0))(obs, t)

    return policy


def run_interaction(env: gym.Env, policy: Policy):
    """Step ``policy`` until the interaction ends; return observations, rewards, flags, infos."""
    obs_list, rewards, flags, infos = [], [], [], []
    obs = env.unwrapped._obs()
    for t in range(HORIZON + 1):
        obs, reward, terminated, truncated, info = env.step(policy(obs, t))
        obs_list.append(obs)
        rewards.append(reward)
        flags.append((terminated, truncated))
        infos.append(info)
        if terminated or truncated:
            return obs_list, rewards, flags, infos
    raise AssertionError("interaction did not end within the horizon")


def success_rate(choose: Callable[[dict, int], Policy], n: int = 40, seed: int = 0,
                 history: int = 1) -> tuple[float, list[int]]:
    """Play ``n`` interactions, picking each one's policy by ``choose(info, i)``."""
    env = gym.make(ENV_ID, history=history)
    _, info = env.reset(seed=seed)
    wins, strategies = [], []
    for i in range(n):
        strategies.append(info["strategy_id"])
        *_, infos = run_interaction(env, choose(info, i))
        wins.append(infos[-1]["success"])
        _, info = env.reset()
    return float(np.mean(wins)), strategies


# -- the Gymnasium API and the contract ----------------------------------------------------------


def test_gymnasium_checker_passes_without_warnings() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = gym.make(ENV_ID, render_mode="rgb_array")
        gym_check_env(env.unwrapped)  # includes the render checks
    assert env.unwrapped.spec.id == ENV_ID
    assert env.unwrapped.horizon == HORIZON == 20


def test_contract_checker_passes() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the strategy must vary, so the leak check really runs
        check_env(gym.make(ENV_ID))
        check_env("driving-steer", n_interactions=8, seed=3)


def test_spaces_and_first_observation() -> None:
    env = gym.make(ENV_ID)
    assert env.action_space.shape == (1,) and env.observation_space.shape == (10,)
    assert env.unwrapped.strategy_space.shape == (2,)
    obs, info = env.reset(seed=0)
    # Ego at the origin at 20 m/s, opponent 15 m ahead at 14 m/s, both straight in the middle.
    np.testing.assert_allclose(obs, [0, 0, 2.0, 0, 0, 1.5, 0, 1.4, 0, 0], atol=1e-6)
    assert obs.dtype == np.float32
    assert info["strategy"].sum() == 1.0 and info["strategy"][info["strategy_id"]] == 1.0


def test_determinism_under_seed() -> None:
    env = gym.make(ENV_ID)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(6, HORIZON, 1)).astype(np.float32)

    def play(seed: int):
        out = []
        obs, info = env.reset(seed=seed)
        out.append((obs, info["strategy_id"]))
        for i in range(6):
            for a in actions[i]:
                obs, reward, terminated, truncated, info = env.step(a)
                out.append((obs, reward))
                if terminated or truncated:
                    break
            obs, info = env.reset()
            out.append((obs, info["strategy_id"]))
        return out

    first, again = play(7), play(7)
    assert len(first) == len(again)
    for (o1, x1), (o2, x2) in zip(first, again, strict=True):
        np.testing.assert_array_equal(o1, o2)
        assert x1 == x2
    starts = {play(seed)[0][1] for seed in range(8)}
    assert starts == {LEFT, RIGHT}  # the first target is drawn from the seed


def test_rgb_array_render_headless() -> None:
    env = gym.make(ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    frames = [env.render()]
    for _ in range(6):
        env.step(np.array([-0.5], dtype=np.float32))
        frames.append(env.render())
    for frame in frames:
        assert frame.shape == (384, 128, 3) and frame.dtype == np.uint8
    blue = [np.argwhere(np.all(f == (40, 90, 220), axis=-1)) for f in frames]
    red = [np.argwhere(np.all(f == (220, 60, 60), axis=-1)) for f in frames]
    assert all(len(b) > 50 for b in blue) and len(red[0]) > 50
    # Steering left moves the ego's pixels left on screen; the view follows the ego forwards, so
    # the slower opponent moves down the image.
    assert blue[-1][:, 1].mean() < blue[0][:, 1].mean() - 5
    assert red[4][:, 0].mean() > red[0][:, 0].mean() + 5
    plain = gym.make(ENV_ID)
    plain.reset(seed=0)
    assert plain.render() is None  # no render_mode: no frames


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"history": 0}, "history=0"),
        ({"history": 1.5}, "history=1.5"),
        ({"render_mode": "human"}, "'human'"),
        ({"backend": "carla"}, "backend='carla'"),
    ],
)
def test_bad_kwargs_raise_value_error_naming_the_value(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        DrivingSteerEnv(**kwargs)


def test_oracle_observation_appends_the_one_hot_lane() -> None:
    env = OracleObservation(gym.make(ENV_ID))
    obs, info = env.reset(seed=1)
    assert obs.shape == (12,)
    np.testing.assert_array_equal(obs[10:], info["strategy"])


# -- the rules -----------------------------------------------------------------------------------


def test_opponent_blocks_the_side_the_ego_ended_on() -> None:
    env = gym.make(ENV_ID)
    _, info = env.reset(seed=0)
    for side in [LEFT, RIGHT, RIGHT, LEFT, LEFT]:
        *_, infos = run_interaction(env, pass_on(side))
        assert infos[-1]["strategy_id"] == info["strategy_id"]  # fixed during the interaction
        _, info = env.reset()
        assert info["strategy_id"] == side
        expected = np.zeros(2, dtype=np.float32)
        expected[side] = 1.0
        np.testing.assert_array_equal(info["strategy"], expected)


def test_opponent_swerves_into_its_target_lane_after_holding_the_middle() -> None:
    env = gym.make(ENV_ID)
    _, info = env.reset(seed=2)
    for _ in range(4):
        free = RIGHT if info["strategy_id"] == LEFT else LEFT
        obs, *_ = run_interaction(env, pass_on(free))
        opp_y = np.array([o[6] * 10.0 for o in obs])
        assert np.all(np.abs(opp_y[:7]) < 1e-6)  # straight for 7 steps (1.4 s)...
        target_y = -LANE if info["strategy_id"] == LEFT else LANE
        assert abs(opp_y[8] - target_y) < 0.5 * LANE  # ...more than half way within 0.4 s
        assert abs(opp_y[-1] - target_y) < 0.3
        _, info = env.reset()


def test_side_ended_on_is_the_sign_of_the_final_lateral_position() -> None:
    env = DrivingSteerEnv()
    env.reset(seed=0)
    obs, *_ = run_interaction(env, constant(1.0))  # hard right: off the road to the right
    assert obs[-1][1] > 0
    _, info = env.reset()
    assert info["strategy_id"] == RIGHT
    run_interaction(env, constant(-1.0))
    _, info = env.reset()
    assert info["strategy_id"] == LEFT


def test_passing_on_the_free_side_succeeds_with_zero_reward_over_the_full_horizon() -> None:
    env = gym.make(ENV_ID)
    _, info = env.reset(seed=1)
    for _ in range(4):
        free = RIGHT if info["strategy_id"] == LEFT else LEFT
        obs, rewards, flags, infos = run_interaction(env, pass_on(free))
        assert len(rewards) == HORIZON and rewards == [0.0] * HORIZON
        assert flags[-1] == (False, True) and all(f == (False, False) for f in flags[:-1])
        assert infos[-1]["success"] is True
        assert all("success" not in i for i in infos[:-1])
        assert not any(i["collision"] or i["off_road"] for i in infos)
        gap = (obs[-1][0] - obs[-1][5]) * 10.0
        assert gap >= SCENARIO.car_length  # the ego is past the opponent
        # Passing takes most of the interaction: the ego is not yet past 4 steps before the end.
        assert (obs[-5][0] - obs[-5][5]) * 10.0 < SCENARIO.car_length
        _, info = env.reset()


def test_passing_on_the_blocked_side_ends_early_in_a_collision() -> None:
    env = gym.make(ENV_ID)
    _, info = env.reset(seed=1)
    _, rewards, flags, infos = run_interaction(env, pass_on(info["strategy_id"]))
    assert len(rewards) < HORIZON
    assert rewards[-1] == -1.0 and all(r == 0.0 for r in rewards[:-1])
    assert flags[-1] == (True, False)
    assert infos[-1]["collision"] is True and infos[-1]["off_road"] is False
    assert infos[-1]["success"] is False


def test_driving_straight_rear_ends_the_opponent() -> None:
    env = gym.make(ENV_ID)
    env.reset(seed=0)
    _, rewards, flags, infos = run_interaction(env, constant(0.0))
    assert 6 <= len(rewards) < HORIZON and rewards[-1] == -1.0 and flags[-1] == (True, False)
    assert infos[-1]["collision"] is True and infos[-1]["success"] is False


@pytest.mark.parametrize("a", [1.0, -1.0])
def test_leaving_the_road_ends_early_with_minus_one(a: float) -> None:
    env = gym.make(ENV_ID)
    env.reset(seed=0)
    obs, rewards, flags, infos = run_interaction(env, constant(a))
    assert len(rewards) == 5  # the shortest interaction: the appendix's "5 to 20 steps"
    assert rewards == [0.0] * 4 + [-1.0] and flags[-1] == (True, False)
    assert infos[-1]["off_road"] is True and infos[-1]["collision"] is False
    assert infos[-1]["success"] is False
    # A corner crossed the edge at 6 m; the centre is still on the road.
    assert 4.0 < abs(obs[-1][1] * 10.0) < 6.0


def test_history_follows_majority_of_last_three() -> None:
    env = gym.make(ENV_ID, history=3)
    env.reset(seed=0)
    sides = [LEFT, LEFT, RIGHT, RIGHT, LEFT]
    expected = [LEFT, LEFT, LEFT, RIGHT, RIGHT]
    for side, sid in zip(sides, expected, strict=True):
        run_interaction(env, constant(-1.0 if side == LEFT else 1.0))
        _, info = env.reset()
        assert info["strategy_id"] == sid


# -- solvable, and not trivially ------------------------------------------------------------------


def test_oracle_scripted_policy_nearly_always_succeeds() -> None:
    rate, strategies = success_rate(lambda info, i: pass_on(1 - info["strategy_id"]))
    assert rate >= 0.9
    assert set(strategies) == {LEFT, RIGHT}


def test_a_fixed_side_succeeds_only_against_the_other_target() -> None:
    # Over targets that alternate (as they do against the oracle), always passing left succeeds
    # exactly when the target is right: half the time.
    env = gym.make(ENV_ID)
    wins = {LEFT: [], RIGHT: []}
    for seed in range(6):
        _, info = env.reset(seed=seed)
        *_, infos = run_interaction(env, pass_on(LEFT))
        wins[info["strategy_id"]].append(infos[-1]["success"])
    assert wins[LEFT] and wins[RIGHT]
    assert not any(wins[LEFT]) and all(wins[RIGHT])
    # Against the reacting opponent it is blocked every time after the first interaction.
    rate, strategies = success_rate(lambda info, i: pass_on(LEFT), n=12)
    assert rate <= 1 / 12 and strategies[1:] == [LEFT] * 11


def test_ignoring_the_past_succeeds_about_half_the_time() -> None:
    rng = np.random.default_rng(0)
    rate, _ = success_rate(lambda info, i: pass_on(int(rng.integers(0, 2))), n=80)
    assert 0.3 <= rate <= 0.7


def test_waiting_to_see_the_swerve_is_too_late() -> None:
    rate, _ = success_rate(lambda info, i: wait_and_react(), n=10)
    assert rate == 0.0


def test_alternating_sides_models_the_opponent_and_succeeds() -> None:
    # It never looks at the strategy: it succeeds because its own last side predicts the next
    # target (what LILI has to learn). Only the first interaction is a guess.
    rate, _ = success_rate(lambda info, i: pass_on(i % 2), n=20)
    assert rate >= 0.9


# -- the backend interface (its speed: benchmarks/envs.py) ---------------------------------------


class CountingBackend:
    """A backend of its own (delegating to highway-env) to show the env needs only the protocol."""

    def __init__(self) -> None:
        self.inner = HighwayBackend()
        self.targets: list[int] = []
        self.steers: list[float] = []

    def reset(self, scenario, target_lane: int) -> SimState:
        self.targets.append(target_lane)
        return self.inner.reset(scenario, target_lane)

    def step(self, steer: float) -> SimState:
        self.steers.append(steer)
        return self.inner.step(steer)


def test_any_steer_backend_plugs_in() -> None:
    backend = CountingBackend()
    assert isinstance(backend, SteerBackend) and isinstance(HighwayBackend(), SteerBackend)
    env = DrivingSteerEnv(backend=backend)
    _, info = env.reset(seed=0)
    run_interaction(env, constant(0.5))
    assert backend.targets == [0 if info["strategy_id"] == LEFT else SCENARIO.n_lanes - 1]
    assert backend.steers[0] == pytest.approx(0.5 * MAX_STEER)
