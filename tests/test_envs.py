"""The registered envs follow the paper's rules and the environment contract."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

import lili.envs  # noqa: F401 - registers the envs
from lili.envs import OracleObservation
from lili.envs.checker import check_env
from lili.envs.driving2d import Driving2DEnv
from lili.envs.point_mass import CirclePartner, PointMassEnv
from lili.envs.wrappers import LastInteractionObservation

ENV_IDS = ["lili/PointMass-v0", "lili/Driving2D-v0"]
CENTER = np.array([0.0, -0.05])
RADIUS, STEP = 0.1, 0.2


def run_interaction(env: gym.Env, policy) -> tuple[list[np.ndarray], list[float], list[dict]]:
    """Step ``policy(obs, t)`` until the interaction ends; return observations, rewards, infos."""
    obs_list, rewards, infos = [], [], []
    obs = None
    for t in range(1000):
        obs, reward, terminated, truncated, info = env.step(policy(obs, t))
        obs_list.append(obs)
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            return obs_list, rewards, infos
    raise AssertionError("interaction did not end")


def angle(strategy: np.ndarray) -> float:
    """The target's angle on the Point Mass circle, in [0, 2 pi)."""
    rel = np.asarray(strategy, dtype=np.float64) - CENTER
    return float(np.mod(np.arctan2(rel[1], rel[0]), 2 * np.pi))


def wrapped_diff(a: float, b: float) -> float:
    """b - a wrapped into (-pi, pi]."""
    return float(np.angle(np.exp(1j * (b - a))))


def stay(obs, t):
    return np.zeros(2, dtype=np.float32)


def to_corner(obs, t):
    # 15 steps of 0.01 reach (0.15, 0.15), 0.25 from the centre: outside the circle.
    return np.ones(2, dtype=np.float32)


# -- both envs: Gymnasium API and the contract ---------------------------------------------------


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_checker_passes_without_warnings(env_id: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = gym.make(env_id, render_mode="rgb_array")
        gym_check_env(env.unwrapped)  # includes the render checks
    assert env.unwrapped.spec.id == env_id


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_contract_checker_passes(env_id: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the strategy must vary, so the leak check really runs
        check_env(gym.make(env_id))
        check_env(lambda: gym.make(env_id), n_interactions=10, seed=3)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_reset_without_seed_continues_and_seed_restarts(env_id: str) -> None:
    env = gym.make(env_id)
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    _, info = env.reset(seed=5)
    first = [info["strategy"]]
    assert info["interaction"] == 0
    for i in range(1, 4):
        truncated = False
        while not truncated:
            _, _, _, truncated, _ = env.step(action)
        _, info = env.reset()
        assert info["interaction"] == i
        first.append(info["strategy"])
    _, info = env.reset(seed=5)
    assert info["interaction"] == 0
    np.testing.assert_array_equal(info["strategy"], first[0])


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_step_after_end_or_before_reset_raises(env_id: str) -> None:
    env = gym.make(env_id).unwrapped
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(action)
    env.reset(seed=0)
    for _ in range(env.horizon):
        env.step(action)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(action)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_rgb_array_render(env_id: str) -> None:
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    frames = [env.render()]
    env.step(env.action_space.sample())
    frames.append(env.render())
    for frame in frames:
        assert isinstance(frame, np.ndarray)
        assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
        assert frame.min() < 255  # something was drawn on the white background
    plain = gym.make(env_id)
    plain.reset(seed=0)
    assert plain.render() is None  # no render_mode: no frames


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_oracle_observation_appends_strategy(env_id: str) -> None:
    env = OracleObservation(gym.make(env_id))
    inner_dim = env.env.observation_space.shape[0]
    strat_dim = env.unwrapped.strategy_space.shape[0]
    assert env.observation_space.shape == (inner_dim + strat_dim,)
    obs, info = env.reset(seed=1)
    for _ in range(3):
        strategy = info["strategy"]
        assert obs in env.observation_space
        np.testing.assert_array_equal(obs[inner_dim:], strategy)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(env.action_space.sample())
            done = terminated or truncated
            assert obs in env.observation_space
            # Even the last step carries this interaction's strategy, not the next one.
            np.testing.assert_array_equal(obs[inner_dim:], strategy)
        obs, info = env.reset()


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: PointMassEnv(step_noise=-0.1), "step_noise=-0.1"),
        (lambda: PointMassEnv(history=0), "history=0"),
        (lambda: PointMassEnv(horizon=0), "horizon=0"),
        (lambda: PointMassEnv(render_mode="human"), "'human'"),
        (lambda: PointMassEnv(strategy_votes="yes"), "strategy_votes='yes'.*true or false"),
        (lambda: Driving2DEnv(history=0), "history=0"),
        (lambda: Driving2DEnv(render_mode="human"), "'human'"),
    ],
)
def test_bad_kwargs_raise_value_error_naming_the_value(make, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        make()


# -- Point Mass ----------------------------------------------------------------------------------


def test_point_mass_start_scaling_clipping_and_reward() -> None:
    env = gym.make("lili/PointMass-v0")
    obs, info = env.reset(seed=0)
    np.testing.assert_array_equal(obs, [0.0, 0.0])
    target = info["strategy"].astype(np.float64)
    assert np.linalg.norm(target - CENTER) == pytest.approx(RADIUS, abs=1e-6)

    obs, reward, *_ = env.step(np.array([1.0, -0.5], dtype=np.float32))
    np.testing.assert_allclose(obs, [0.01, -0.005], atol=1e-7)
    assert reward == pytest.approx(-np.linalg.norm(np.array([0.01, -0.005]) - target), abs=1e-6)

    for _ in range(30):  # 30 * 0.01 would reach 0.3; the position is clipped at 0.15
        obs, reward, *_ = env.step(np.array([1.0, 1.0], dtype=np.float32))
    np.testing.assert_allclose(obs, [0.15, 0.15], atol=1e-7)
    assert reward == pytest.approx(-np.linalg.norm(np.array([0.15, 0.15]) - target), abs=1e-6)


def test_point_mass_horizon_is_50() -> None:
    env = gym.make("lili/PointMass-v0")
    env.reset(seed=0)
    flags = [env.step(env.action_space.sample())[2:4] for _ in range(50)]
    assert all(flags[t] == (False, False) for t in range(49))
    assert flags[49] == (False, True)
    assert env.unwrapped.horizon == 50


def test_point_mass_theta_moves_clockwise_inside_and_counter_clockwise_outside() -> None:
    env = gym.make("lili/PointMass-v0")
    _, info = env.reset(seed=2)
    for policy, direction in [(stay, -1), (to_corner, +1), (to_corner, +1), (stay, -1)]:
        before = angle(info["strategy"])
        run_interaction(env, policy)
        _, info = env.reset()
        assert wrapped_diff(before, angle(info["strategy"])) == pytest.approx(
            direction * STEP, abs=1e-5)


def test_point_mass_initial_theta_on_grid_and_seeded() -> None:
    grid = CENTER + RADIUS * np.stack(
        [np.cos(STEP * np.arange(32)), np.sin(STEP * np.arange(32))], axis=1)
    env = gym.make("lili/PointMass-v0")
    starts = []
    for seed in range(20):
        _, info = env.reset(seed=seed)
        target = info["strategy"].astype(np.float64)
        assert np.min(np.linalg.norm(grid - target, axis=1)) < 1e-6
        starts.append(tuple(np.round(target, 5)))
        _, again = env.reset(seed=seed)
        np.testing.assert_array_equal(again["strategy"], info["strategy"])
    assert len(set(starts)) >= 5


@pytest.mark.parametrize("noise", [0.0, 0.1, 0.5])
def test_point_mass_step_noise_sigma_is_a_fraction_of_the_step(noise: float) -> None:
    partner = CirclePartner(step_noise=noise)
    rng = np.random.default_rng(0)
    partner.reset(rng)
    steps = []
    for _ in range(20000):
        before = partner.theta
        partner.update(False, rng)  # outside: counter-clockwise, so the step adds to theta
        steps.append(wrapped_diff(before, partner.theta))
    steps = np.array(steps)
    assert steps.mean() == pytest.approx(STEP, abs=0.003)
    assert steps.std() == pytest.approx(noise * STEP, abs=0.003 + 0.03 * noise * STEP)


def test_point_mass_history_follows_majority_of_last_three() -> None:
    env = gym.make("lili/PointMass-v0", history=3)
    _, info = env.reset(seed=4)
    outcomes = [True, True, False, False, False, True]  # True = ended inside the circle
    # Majority of the last 3: in, in, in (2 of 3), out (2 of 3), out, out (2 of 3).
    expected = [-1, -1, -1, +1, +1, +1]
    for inside, direction in zip(outcomes, expected, strict=True):
        before = angle(info["strategy"])
        run_interaction(env, stay if inside else to_corner)
        _, info = env.reset()
        assert wrapped_diff(before, angle(info["strategy"])) == pytest.approx(
            direction * STEP, abs=1e-5)


def test_point_mass_strategy_votes_tell_the_partners_whole_state() -> None:
    env = gym.make("lili/PointMass-v0", history=3, strategy_votes=True)
    assert env.unwrapped.strategy_space.shape == (5,)
    _, info = env.reset(seed=4)
    np.testing.assert_array_equal(info["strategy"][2:], [0, 0, 0])  # no vote cast yet
    outcomes = [True, False, False, True]
    expected_votes = [[1, 0, 0], [-1, 1, 0], [-1, -1, 1], [1, -1, -1]]  # most recent first
    for inside, votes in zip(outcomes, expected_votes, strict=True):
        before = angle(info["strategy"][:2])
        run_interaction(env, stay if inside else to_corner)
        _, info = env.reset()
        np.testing.assert_array_equal(info["strategy"][2:], votes)
        # The target part moves as without the votes: the majority of the last three.
        majority = 1 if sum(votes) > 0 else -1
        assert wrapped_diff(before, angle(info["strategy"][:2])) == pytest.approx(
            -majority * STEP, abs=1e-5)
    # The Oracle sees all five numbers.
    assert OracleObservation(env).observation_space.shape == (2 + 5,)


# -- Driving 2D ----------------------------------------------------------------------------------


def lane_policy(side: int):
    """Steer fully to ``side`` (-1 left, +1 right) from the first step."""
    return lambda obs, t: np.array([float(side)], dtype=np.float32)


def test_driving_other_car_merges_into_lane_ego_used_last() -> None:
    env = gym.make("lili/Driving2D-v0")
    env.reset(seed=0)
    for side, sid in [(-1, 0), (+1, 1), (+1, 1), (-1, 0)]:
        run_interaction(env, lane_policy(side))
        _, info = env.reset()
        assert info["strategy_id"] == sid
        np.testing.assert_array_equal(info["strategy"], [side])
        obs, *_ = run_interaction(env, lane_policy(0))
        assert obs[-1][2] == pytest.approx(side)  # the other car's final x is that lane
        env.reset()


def test_driving_staying_in_the_middle_rear_ends_once() -> None:
    env = gym.make("lili/Driving2D-v0")
    env.reset(seed=0)
    for _ in range(3):
        _, rewards, infos = run_interaction(env, lane_policy(0))
        assert sorted(rewards) == [-1.0] + [0.0] * 9  # -1 once although in contact for 2 steps
        assert infos[-1]["success"] is False
        env.reset()


def test_driving_opposite_lane_succeeds_and_horizon_is_10() -> None:
    env = gym.make("lili/Driving2D-v0")
    _, info = env.reset(seed=1)
    for _ in range(6):
        side = -1 if info["strategy_id"] == 1 else 1
        _, rewards, infos = run_interaction(env, lane_policy(side))
        assert len(rewards) == 10 and env.unwrapped.horizon == 10
        assert all(r == 0.0 for r in rewards)
        assert infos[-1]["success"] is True
        assert all("success" not in i for i in infos[:-1])
        _, info = env.reset()


def test_driving_same_lane_as_merge_collides() -> None:
    env = gym.make("lili/Driving2D-v0")
    _, info = env.reset(seed=1)
    side = -1 if info["strategy_id"] == 0 else 1
    _, rewards, infos = run_interaction(env, lane_policy(side))
    assert sum(rewards) == -1.0
    assert infos[-1]["success"] is False


def test_driving_history_follows_majority_of_last_three() -> None:
    env = gym.make("lili/Driving2D-v0", history=3)
    env.reset(seed=0)
    sides = [-1, -1, +1, +1, -1]
    expected = [0, 0, 0, 1, 1]  # majority of the last 3 ego lanes (0 left, 1 right)
    for side, sid in zip(sides, expected, strict=True):
        run_interaction(env, lane_policy(side))
        _, info = env.reset()
        assert info["strategy_id"] == sid


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_last_interaction_observation_appends_how_the_last_interaction_went(env_id: str) -> None:
    env = LastInteractionObservation(gym.make(env_id))
    inner = env.env.observation_space.shape[0]
    strat = env.unwrapped.strategy_space.shape[0]
    act = env.action_space.shape[0]
    assert env.observation_space.shape == (2 * inner + strat + act,)
    seen = []
    for seed in (1, None, None, 2):
        obs, info = env.reset(seed=seed) if seed is not None else env.reset()
        appended = obs[inner:]
        if seed is not None:  # a new sequence: nothing came before it
            np.testing.assert_array_equal(appended, 0.0)
        else:
            last = seen[-1]
            np.testing.assert_allclose(appended, np.concatenate(
                [last["strategy"], last["obs"], last["act"]]), rtol=1e-6)
        strategy, done = info["strategy"], False
        while not done:
            a = env.action_space.sample()
            obs, _, terminated, truncated, info = env.step(a)
            done = terminated or truncated
            assert obs in env.observation_space
            np.testing.assert_array_equal(obs[inner:], appended)  # fixed within the interaction
        seen.append({"strategy": strategy, "obs": obs[:inner], "act": a})


class _NoStrategyInfo(gym.Wrapper):
    """An env that declares a strategy space but leaves info['strategy'] out of reset()."""

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        return obs, {k: v for k, v in info.items() if k != "strategy"}


@pytest.mark.parametrize(("wrapper", "who"), [
    (OracleObservation, "the Oracle"),
    (LastInteractionObservation, "the last-interaction Oracle"),
])
def test_oracle_wrappers_need_the_strategy_in_reset_info(wrapper, who: str) -> None:
    env = wrapper(_NoStrategyInfo(gym.make("lili/PointMass-v0")))
    with pytest.raises(ValueError, match=f"^{who} needs info\\['strategy'\\] from reset\\(\\); "
                                         "env PointMassEnv gave keys"):
        env.reset(seed=0)


def test_last_interaction_observation_tells_the_outcome_when_asked() -> None:
    # Air hockey's outcome (the side of the paddle where the puck ended) is in no observation.
    plain = LastInteractionObservation(gym.make("lili/AirHockey-v0"))
    env = LastInteractionObservation(gym.make("lili/AirHockey-v0"), outcome=True)
    assert env.observation_space.shape[0] == plain.observation_space.shape[0] + 1
    obs, _ = env.reset(seed=3)
    assert obs[-1] == 0.0  # nothing came before a seeded reset
    outcomes = []
    for _ in range(6):
        done, info = False, {}
        while not done:
            obs, _, terminated, truncated, info = env.step(env.action_space.sample())
            done = terminated or truncated
        assert info["outcome"] in (-1, 1)  # the env reports what the striker reacts to
        outcomes.append(info["outcome"])
        obs, _ = env.reset()
        assert obs[-1] == outcomes[-1]
    with pytest.raises(ValueError, match="^outcome='yes' is invalid; allowed: True or False"):
        LastInteractionObservation(gym.make("lili/PointMass-v0"), outcome="yes")


def test_last_interaction_outcome_must_be_a_number() -> None:
    # Lunar Lander declares a vector outcome: refused when the agent is built.
    with pytest.raises(ValueError, match="needs an outcome that is one number; env LunarLanderEnv "
                                         "declares _outcome\\(\\) -> np.ndarray"):
        LastInteractionObservation(gym.make("lili/LunarLander-v0"), outcome=True)

    class Undeclared(PointMassEnv):
        def _outcome(self):  # declares nothing, returns a pair: refused at the first outcome
            return (1, 2)

    env = LastInteractionObservation(Undeclared(), outcome=True)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="needs info\\['outcome'\\] on the last step as one finite "
                                         "number; env Undeclared gave \\(1, 2\\)"):
        for _ in range(200):
            env.step(np.zeros(env.action_space.shape, np.float32))
