"""``lili.envs.checker``: passes the library's envs and names what a broken env breaks."""

from __future__ import annotations

import functools
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import lili.envs  # noqa: F401 - registers the envs
from lili.envs import OracleObservation, RepeatedInteractionEnv
from lili.envs.checker import DEFAULT_INTERACTIONS, EnvContractError, check_env
from lili.envs.point_mass import PointMassEnv
from lili.envs.spec import check_env_kwargs, env_kwarg_names, load_env_class, make_env


class FlipPartner:
    """Strategy z in {-1, +1}: random at the start, flips after every interaction."""

    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self) -> None:
        self.z = 1.0

    def reset(self, rng: np.random.Generator) -> None:
        self.z = float(rng.choice([-1.0, 1.0]))

    def strategy(self) -> np.ndarray:
        return np.array([self.z], dtype=np.float32)

    def strategy_id(self) -> int | None:
        return int(self.z > 0)

    def update(self, outcome: Any, rng: np.random.Generator) -> None:
        self.z = -self.z


class ToyEnv(RepeatedInteractionEnv):
    """A correct toy env: move x on a line towards the hidden z; 5 steps per interaction."""

    def __init__(self) -> None:
        super().__init__()
        self.horizon = 5
        self.partner = FlipPartner()
        self.observation_space = spaces.Box(-2.0, 2.0, shape=(1,), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.x = 0.0

    def _obs(self) -> np.ndarray:
        return np.array([self.x], dtype=np.float32)

    def _begin(self) -> np.ndarray:
        self.x = float(self.np_random.uniform(-0.1, 0.1))
        return self._obs()

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        self.x = float(np.clip(self.x + 0.3 * action[0], -2.0, 2.0))
        return self._obs(), -abs(self.x - self.partner.z), False

    def _outcome(self) -> Any:
        return self.x > 0


class LeakyEnv(ToyEnv):
    """Puts the strategy into the observation."""

    def __init__(self) -> None:
        super().__init__()
        self.observation_space = spaces.Box(-2.0, 2.0, shape=(2,), dtype=np.float32)

    def _obs(self) -> np.ndarray:
        return np.array([self.x, self.partner.z], dtype=np.float32)


class ScaledLeakEnv(LeakyEnv):
    """Puts a scaled and shifted copy of the strategy into the observation."""

    def _obs(self) -> np.ndarray:
        return np.array([self.x, 1.5 * self.partner.z - 0.5], dtype=np.float32)


class BinPartner(FlipPartner):
    """A continuous strategy in [-1, 1]; its id is the third of the interval it falls in."""

    def update(self, outcome: Any, rng: np.random.Generator) -> None:
        self.z = float(rng.uniform(-1.0, 1.0))

    def strategy_id(self) -> int | None:
        return min(2, int((self.z + 1.0) * 1.5))


class LabelLeakEnv(LeakyEnv):
    """Shows whether the strategy id is the middle one: not affine in z, affine in the one-hot."""

    def __init__(self) -> None:
        super().__init__()
        self.partner = BinPartner()

    def _obs(self) -> np.ndarray:
        return np.array([self.x, float(self.partner.strategy_id() == 1)], dtype=np.float32)


class LateNaNEnv(ToyEnv):
    """Breaks only from interaction ``at`` on: the observation turns NaN or the reward inf."""

    def __init__(self, at: int = 60, what: str = "obs") -> None:
        super().__init__()
        self.at, self.what = at, what
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(1,), dtype=np.float32)

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        obs, reward, done = super()._step(action)
        if self.interaction >= self.at:
            if self.what == "obs":
                obs = np.full_like(obs, np.nan)
            else:
                reward = float("inf")
        return obs, reward, done


class HugeHorizonEnv(ToyEnv):
    def __init__(self) -> None:
        super().__init__()
        self.horizon = 10**9


class DriftingEnv(ToyEnv):
    """Changes the strategy in the middle of an interaction."""

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        if self.t == 2:
            self.partner.z = -self.partner.z
        return super()._step(action)


class GlobalRandomPartner(FlipPartner):
    """Draws the next strategy from the global ``np.random`` instead of the env's generator."""

    def update(self, outcome: Any, rng: np.random.Generator) -> None:
        self.z = float(np.random.uniform(-1.0, 1.0))


class GlobalRandomEnv(ToyEnv):
    """Not deterministic under ``reset(seed)``: its partner ignores the seeded generator."""

    def __init__(self) -> None:
        super().__init__()
        self.partner = GlobalRandomPartner()


class GlobalRandomStartEnv(ToyEnv):
    """Not deterministic under ``reset(seed)``: the start state comes from the global np.random."""

    def _begin(self) -> np.ndarray:
        self.x = float(np.random.uniform(-0.1, 0.1))
        return self._obs()


class DuckEnv(gym.Env):
    """Honours the contract without subclassing RepeatedInteractionEnv; ends after ``end_at``."""

    metadata = {"render_modes": []}
    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
    observation_space = spaces.Box(-100.0, 100.0, shape=(1,), dtype=np.float32)
    action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self, end_at: int = 5, horizon: Any = 5) -> None:
        self.horizon = horizon
        self.end_at = end_at
        self.index, self.t, self.z, self.x = -1, 0, 1.0, 0.0

    def _info(self) -> dict[str, Any]:
        return {"strategy": np.array([self.z], dtype=np.float32), "strategy_id": int(self.z > 0),
                "interaction": self.index}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is not None or self.index < 0:
            self.index, self.z = 0, 1.0
        else:
            self.index += 1
        self.t, self.x = 0, 0.0
        return np.array([self.x], dtype=np.float32), self._info()

    def step(self, action: Any):
        self.t += 1
        self.x = float(np.clip(self.x + action[0], -100.0, 100.0))
        truncated = self.t >= self.end_at
        info = self._info()
        if truncated:
            self.z = -self.z
        return np.array([self.x], dtype=np.float32), -abs(self.x - self.z), False, truncated, info


class NoStrategySpaceEnv(DuckEnv):
    strategy_space = None  # type: ignore[assignment]


class DiscreteActionEnv(ToyEnv):
    def __init__(self) -> None:
        super().__init__()
        self.action_space = spaces.Discrete(3)  # type: ignore[assignment]


class Float64StrategyEnv(ToyEnv):
    def _info(self) -> dict[str, Any]:
        info = super()._info()
        info["strategy"] = info["strategy"].astype(np.float64)
        return info


# -- passing envs --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "env_or_factory",
    [
        functools.partial(PointMassEnv, step_noise=0.2, history=3),
        ToyEnv,
        DuckEnv,
    ],
)
def test_check_env_passes(env_or_factory: Any) -> None:
    assert check_env(env_or_factory) is None


@pytest.mark.parametrize("env_or_factory", ["lili/PointMass-v0", "driving-2d", PointMassEnv])
def test_check_env_takes_an_id_an_alias_or_a_class(env_or_factory: Any) -> None:
    # Short: each library env's own test file checks it at the default length with warnings
    # as errors (test_envs, test_driving_steer, test_air_hockey, ...); here only the forms.
    assert check_env(env_or_factory, n_interactions=10) is None


def test_check_env_accepts_an_instance_and_leaves_it_usable() -> None:
    env = gym.make("lili/Driving2D-v0")
    check_env(env, n_interactions=4, seed=7)
    _, info = env.reset(seed=0)
    assert info["interaction"] == 0


# -- failing envs --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("env_or_factory", "fragments"),
    [
        (LeakyEnv, ["observation dimension 1 is an affine function", "obs[1] = 1 * strategy[0]",
                    "leaks"]),
        (ScaledLeakEnv, ["observation dimension 1", "-0.5 + 1.5 * strategy[0]", "leaks"]),
        (LabelLeakEnv, ["observation dimension 1", "a one-hot of strategy_id", "leaks"]),
        (functools.partial(LateNaNEnv, at=60), ["interaction 60", "not finite"]),
        (functools.partial(LateNaNEnv, at=60, what="reward"), ["interaction 60", "reward is inf"]),
        (HugeHorizonEnv, ["horizon=1000000000 is too long to train on", "GiB"]),
        (DriftingEnv, ["step 3", "strategy changed within the interaction"]),
        (GlobalRandomEnv, ["reset(seed=0) did not replay", "strategy", "np.random"]),
        (GlobalRandomStartEnv, ["gymnasium's env checker failed", "not equivalent", "np.random"]),
        (functools.partial(DuckEnv, end_at=20),
         ["interaction 0 did not end within horizon=5", "terminated or truncated"]),
        (functools.partial(DuckEnv, horizon=0), ["horizon=0", "does not subclass"]),
        (NoStrategySpaceEnv, ["strategy_space is None", "1-D float"]),
        (DiscreteActionEnv, ["action space is Discrete(3)", "continuous"]),
        (Float64StrategyEnv, ["dtype float64", "float32"]),
        (lambda: OracleObservation(gym.make("lili/PointMass-v0")), ["OracleObservation"]),
        (lambda: gym.make("lili/PointMass-v0", max_episode_steps=20), ["TimeLimit", "20"]),
        (lambda: "not an env", ["returned a str"]),
    ],
)
def test_check_env_names_the_broken_rule(env_or_factory: Any, fragments: list[str]) -> None:
    with pytest.raises(EnvContractError) as excinfo:
        check_env(env_or_factory)
    message = str(excinfo.value)
    for fragment in fragments:
        assert fragment in message, message
    assert "The contract requires" in message or "gymnasium.Env" in message


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"n_interactions": 1}, r"n_interactions=1 is invalid; allowed: an integer in \[2, 10000\]"),
    ({"n_interactions": 10**9}, "n_interactions=1000000000"),
    ({"n_interactions": 6.0}, "n_interactions=6.0"),
    ({"seed": -1}, r"seed=-1 is invalid; allowed: an integer in \[0, 4294967295\]"),
    ({"seed": 2**70}, "seed=1180591620717411303424"),
])
def test_check_env_rejects_bad_arguments(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        check_env(ToyEnv, **kwargs)


def test_the_default_run_is_long_enough_for_late_faults() -> None:
    assert DEFAULT_INTERACTIONS >= 60
    check_env(functools.partial(LateNaNEnv, at=DEFAULT_INTERACTIONS))  # never reached: passes


def test_env_kwarg_names_and_check() -> None:
    assert env_kwarg_names(load_env_class("point-mass"))[:3] == ["step_noise", "history",
                                                                  "horizon"]
    assert env_kwarg_names(load_env_class("driving-2d")) == ["history", "render_mode"]
    assert env_kwarg_names(ToyEnv) == []
    assert env_kwarg_names(lambda **kw: ToyEnv()) is None  # **kwargs: only the env can tell
    check_env_kwargs(load_env_class("driving-2d"), {"history": 3}, "driving-2d")
    with pytest.raises(ValueError) as excinfo:
        check_env_kwargs(load_env_class("driving-2d"), {"colour": 1, "lanes": 4}, "driving-2d")
    assert str(excinfo.value) == ("unknown env kwarg(s) 'colour', 'lanes' for driving-2d; "
                                  "allowed: history")
    with pytest.raises(ValueError, match="allowed: none"):
        check_env_kwargs(ToyEnv, {"x": 1}, "ToyEnv")


def test_never_varying_strategy_warns_that_leaks_were_not_checked() -> None:
    class StuckEnv(ToyEnv):
        def __init__(self) -> None:
            super().__init__()
            self.partner.update = lambda outcome, rng: None  # type: ignore[method-assign]

    with pytest.warns(UserWarning, match="never changed"):
        check_env(StuckEnv)


# -- env specs (lili.envs.spec) ------------------------------------------------------------------


def test_make_env_checks_the_options_by_name_then_builds() -> None:
    env = make_env("point-mass", {"history": 2}, render_mode="rgb_array")
    assert env.unwrapped.partner.votes.n == 2 and env.unwrapped.render_mode == "rgb_array"
    with pytest.raises(ValueError, match="unknown env kwarg.s. 'lanes' for driving-2d"):
        make_env("driving-2d", {"lanes": 4})
    with pytest.raises(ValueError, match="^env point-mass: .*step_noise"):
        make_env("point-mass", {"step_noise": -1.0})


def test_load_env_class_resolves_module_class_and_ids() -> None:
    assert load_env_class("lili.envs.point_mass:PointMassEnv") is PointMassEnv
    for spec in ("lili/PointMass-v0", "point-mass", "lili.envs:lili/PointMass-v0"):
        env = load_env_class(spec)(history=2)
        assert isinstance(env.unwrapped, PointMassEnv)
        assert env.unwrapped.partner.votes.n == 2


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ("no_such_pkg.envs:Foo", "cannot import module 'no_such_pkg.envs'"),
        ("lili.envs.point_mass:NoSuchEnv", "has no attribute 'NoSuchEnv'"),
        ("lili.envs.point_mass:STEP", "not a class or function"),
        ("no-such-env-v0", "unknown env 'no-such-env-v0'"),
        (":PointMassEnv", "malformed"),
    ],
)
def test_load_env_class_names_the_bad_value(spec: str, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        load_env_class(spec)
