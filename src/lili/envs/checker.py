# Over 400 lines: the contract's checks in the order check_env runs them, each with its message.
"""Check that an env honours the repeated-interaction contract (``lili check-env``).

:func:`check_env` is for users' own envs: an env that passes it trains with every algorithm in
the library with no other change. It raises :class:`EnvContractError` with one message that
names what broke and what the contract (``/DESIGN.md``, "Environment contract") requires.

An env named by a spec (``"package.module:ClassName"``, a registered Gymnasium id or an alias)
is resolved by :func:`lili.envs.spec.load_env_class`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env as gym_check_env

from lili.buffer import check_buffer_fits
from lili.config import AgentConfig, check_seed
from lili.envs.core import RepeatedInteractionEnv, env_horizon
from lili.envs.spec import EnvFactory, load_env_class
from lili.envs.wrappers import OracleObservation
from lili.errors import shown

__all__ = ["EnvContractError", "check_env", "DEFAULT_INTERACTIONS", "MAX_INTERACTIONS"]

_DETERMINISM_HINT = (
    "reset(seed=s) restarts the whole sequence (interaction 0, fresh partner) deterministically "
    "from s: draw all randomness, the partner's included, from self.np_random (seeded by "
    "super().reset(seed=seed)), never from the global np.random or an unseeded generator"
)


class EnvContractError(ValueError):
    """An env breaks the repeated-interaction contract; the message says what and what is needed."""


@dataclass
class _Interaction:
    """What one interaction produced: observations (reset first), rewards and strategies."""

    obs: list[np.ndarray] = field(default_factory=list)
    rewards: list[float] = field(default_factory=list)
    strategies: list[np.ndarray] = field(default_factory=list)
    strategy_ids: list[int] = field(default_factory=list)


DEFAULT_INTERACTIONS = 100
"""Interactions per run of the check: enough to meet a fault that appears only after a few dozen
interactions (a state that drifts to NaN, a strategy cycle of many steps) and to fit the leak
check on thousands of steps, while Point Mass (H = 50) is still checked in about a second."""

MAX_INTERACTIONS = 10_000
"""The check keeps every observation of two runs in memory, like a replay buffer of that size."""


def check_env(
    env_or_factory: gym.Env | EnvFactory | str, n_interactions: int = DEFAULT_INTERACTIONS,
    seed: int = 0, buffer_capacity: int | None = None,
) -> None:
    """Raise :class:`EnvContractError` unless the env honours the repeated-interaction contract.

    ``env_or_factory`` is an env instance, a callable returning a fresh env (a class, a
    ``functools.partial`` of ``gymnasium.make``, a lambda) or a spec for :func:`load_env_class`.
    With a factory, Gymnasium's checker and the contract checks each get a fresh env, and the
    envs are closed afterwards; an instance is used as is and left open.

    Checks, in order (the first failure is raised):

    1. Not wrapped in :class:`OracleObservation` (it appends the strategy to the observation) and
       no ``TimeLimit`` shorter than ``horizon`` (it would cut interactions short, so the partner
       would never update).
    2. ``env.unwrapped`` is a ``gymnasium.Env`` with a ``strategy_space`` (a 1-D float ``Box``)
       and an integer ``horizon >= 1``. Subclassing :class:`RepeatedInteractionEnv` is not
       required: other envs are checked for the same attributes (duck typing).
    3. The observation space is a flat float ``Box`` and the action space a ``Box`` with finite
       bounds (the agents emit continuous, squashed actions).
       The replay buffer that training allocates (``buffer_capacity`` interactions, default
       ``AgentConfig().buffer_capacity``, each padded to ``horizon``) and the check's own record
       of its runs fit in memory (:func:`lili.buffer.check_buffer_fits`), so an absurd horizon
       fails here, before anything is allocated.
    4. ``gymnasium.utils.env_checker.check_env(env.unwrapped, skip_render_check=True)`` passes.
    5. ``reset(seed=seed)`` and then ``n_interactions`` interactions (``reset()`` without a seed
       between them) under fixed pseudo-random actions (interaction i's from
       ``np.random.default_rng([seed, i])``):
       every reset and step returns ``info["strategy"]`` (float32, shape and bounds of
       ``strategy_space``), ``info["strategy_id"]`` (int) and ``info["interaction"]`` (0 after
       the seeded reset, +1 per reset without a seed); observations are finite and lie in the
       observation space; rewards are finite numbers; every interaction ends (terminated or
       truncated) within ``horizon`` steps; ``info["success"]``, where present, is a bool.
    6. The strategy (and its id) is the same on the reset and on every step of an interaction.
    7. A second ``reset(seed=seed)`` with the same actions replays the first run: the same
       observations, rewards and strategies (``np.allclose``) and interaction lengths.
    8. The strategy does not leak into the observation: no observation dimension that varies
       is an affine function of the strategy over all resets and steps of the run (a
       least-squares fit of it on the strategy vector and the one-hot of ``strategy_id``, where
       the id takes at most 16 values, leaves less than 1e-6 of its variance unexplained).
       That catches copies, scaled and shifted copies and one-hot codes of the strategy; a
       nonlinear function of it (its square, a sine) is not detected. If no strategy dimension
       varied during the run the check cannot tell and a ``UserWarning`` says so.

    ``n_interactions`` must be an integer in [2, :data:`MAX_INTERACTIONS`] (one change of
    strategy needs two interactions) and ``seed`` one in [0, 2**32 - 1].
    """
    if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
            or not 2 <= n_interactions <= MAX_INTERACTIONS:
        raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an integer in "
                         f"[2, {MAX_INTERACTIONS}]")
    check_seed(seed)
    if buffer_capacity is None:
        buffer_capacity = AgentConfig().buffer_capacity
    if isinstance(env_or_factory, str):
        env_or_factory = load_env_class(env_or_factory)

    owned: list[gym.Env] = []
    try:
        env = _obtain(env_or_factory, owned)
        name = type(env.unwrapped).__name__ if isinstance(env, gym.Env) else type(env).__name__
        _check_wrappers(env, name)
        inner = env.unwrapped
        horizon = _check_attributes(env, name)
        _check_time_limit(env, horizon, name)
        _check_spaces(env, name)
        _check_memory(env, horizon, max(buffer_capacity, 2 * n_interactions), name)

        # Gymnasium's checker reseeds and steps the env in ways of its own; with a factory it
        # gets a fresh env so that a failure there cannot be blamed on our runs or vice versa.
        is_factory = not isinstance(env_or_factory, gym.Env)
        gym_env = _obtain(env_or_factory, owned) if is_factory else env
        _run_gym_checker(gym_env.unwrapped, name)

        first = _rollout(env, inner, seed, n_interactions, horizon, name)
        replay = _rollout(env, inner, seed, n_interactions, horizon, name)
        _check_replay(first, replay, seed, name)
        _check_no_leak(first, name)
    finally:
        for made in owned:
            try:
                made.close()
            except Exception:  # closing is best effort; the check's verdict stands
                pass


# -- the individual checks -----------------------------------------------------------------------


def _fail(name: str, what: str, required: str) -> EnvContractError:
    return EnvContractError(f"{name}: {what}. The contract requires: {required}.")


def _obtain(env_or_factory: gym.Env | EnvFactory, owned: list[gym.Env]) -> gym.Env:
    """The env itself, or a fresh one from the factory (remembered in ``owned`` to close)."""
    if isinstance(env_or_factory, gym.Env):
        return env_or_factory
    if not callable(env_or_factory):
        raise EnvContractError(
            f"{env_or_factory!r} is neither a gymnasium.Env nor a callable that returns one"
        )
    try:
        env = env_or_factory()
    except Exception as exc:
        raise EnvContractError(
            f"the env factory {env_or_factory!r} raised {type(exc).__name__}: {exc}"
        ) from exc
    if not isinstance(env, gym.Env):
        raise EnvContractError(
            f"the env factory {env_or_factory!r} returned a {type(env).__name__}; the contract "
            f"requires a gymnasium.Env (one episode = one interaction)"
        )
    owned.append(env)
    return env


def _wrapper_chain(env: gym.Env) -> list[gym.Env]:
    chain = [env]
    while isinstance(chain[-1], gym.Wrapper):
        chain.append(chain[-1].env)
    return chain


def _check_wrappers(env: gym.Env, name: str) -> None:
    if not isinstance(env, gym.Env):
        raise _fail(name, f"the env is a {type(env).__name__}, not a gymnasium.Env",
                    "a gymnasium.Env where one episode is one interaction")
    if any(isinstance(layer, OracleObservation) for layer in _wrapper_chain(env)):
        raise _fail(
            name, "the env is wrapped in OracleObservation, which appends the strategy to the "
            "observation", "observations without the strategy; pass the env without "
            "OracleObservation (the Oracle baseline adds it itself)")


def _check_attributes(env: gym.Env, name: str) -> int:
    """Check ``strategy_space`` on the unwrapped env and the interaction length; return it."""
    inner = env.unwrapped
    subclass = isinstance(inner, RepeatedInteractionEnv)
    how = "" if subclass else " (it does not subclass RepeatedInteractionEnv, so it must define " \
        "the same attributes itself)"
    try:
        strategy_space = inner.strategy_space  # type: ignore[attr-defined]
    except Exception as exc:  # a subclass without a partner raises here, not AttributeError only
        raise _fail(name, f"env.unwrapped.strategy_space is missing{how} "
                    f"({type(exc).__name__}: {exc})",
                    "a strategy_space attribute, a gymnasium.spaces.Box of the strategy vector "
                    "reported in info['strategy'] (without one, SAC and LILI still train on the "
                    "env, but the Oracle and these checks need it)") from exc
    if not isinstance(strategy_space, spaces.Box) or len(strategy_space.shape) != 1 \
            or not np.issubdtype(strategy_space.dtype, np.floating):
        raise _fail(name, f"strategy_space is {strategy_space!r}{how}",
                    "strategy_space to be a 1-D float gymnasium.spaces.Box (the strategy is a "
                    "fixed size float32 vector)")
    try:
        return env_horizon(env)
    except ValueError as exc:
        raise _fail(name, f"{exc}{how}", "an interaction length: an integer horizon >= 1 (the "
                    "most steps an interaction can take), max_episode_steps or a TimeLimit") \
            from None


def _check_time_limit(env: gym.Env, horizon: int, name: str) -> None:
    for layer in _wrapper_chain(env):
        limit = getattr(layer, "_max_episode_steps", None)
        if isinstance(layer, gym.wrappers.TimeLimit) and limit is not None and limit < horizon:
            raise _fail(
                name, f"a TimeLimit wrapper cuts episodes at {limit} steps, before the env's "
                f"horizon={horizon}", "that the env ends its own interactions (so the partner "
                "updates inside the env); register it without max_episode_steps or with "
                "max_episode_steps >= horizon")


def _check_spaces(env: gym.Env, name: str) -> None:
    obs_space, act_space = env.observation_space, env.action_space
    if not isinstance(obs_space, spaces.Box) or len(obs_space.shape) != 1 \
            or not np.issubdtype(obs_space.dtype, np.floating):
        raise _fail(name, f"the observation space is {obs_space!r}",
                    "a flat (1-D) float gymnasium.spaces.Box observation space (the agents' "
                    "networks take a vector)")
    if not isinstance(act_space, spaces.Box) or not np.issubdtype(act_space.dtype, np.floating):
        raise _fail(name, f"the action space is {act_space!r}",
                    "a float gymnasium.spaces.Box action space (the agents emit continuous "
                    "actions)")
    if not (np.all(np.isfinite(act_space.low)) and np.all(np.isfinite(act_space.high))):
        raise _fail(name, f"the action space {act_space!r} has infinite bounds",
                    "finite action bounds (the agents squash actions into them)")


def _check_memory(env: gym.Env, horizon: int, capacity: int, name: str) -> None:
    obs_dim = int(np.prod(env.observation_space.shape))
    act_dim = int(np.prod(env.action_space.shape))
    try:
        check_buffer_fits(capacity, horizon, obs_dim, act_dim)
    except ValueError as exc:
        raise _fail(name, f"horizon={horizon} is too long to train on: {exc}",
                    "a horizon (and observation size) whose replay buffer fits in memory") \
            from None


def _run_gym_checker(inner: gym.Env, name: str) -> None:
    try:
        gym_check_env(inner, skip_render_check=True)
    except Exception as exc:
        detail = str(exc).strip() or "(no message)"
        required = "a valid gymnasium.Env (gymnasium.utils.env_checker.check_env passes)"
        if "determinis" in detail.lower():
            required = f"{required}; {_DETERMINISM_HINT}"
        raise _fail(name, f"gymnasium's env checker failed: {type(exc).__name__}: {detail}",
                    required) from exc


def _check_info(info: Any, inner: gym.Env, index: int, where: str, name: str) -> np.ndarray:
    """Check the contract's info keys on one reset or step; return the strategy."""
    if not isinstance(info, dict):
        raise _fail(name, f"{where}: info is a {type(info).__name__}", "info to be a dict")
    missing = [key for key in ("strategy", "strategy_id", "interaction") if key not in info]
    if missing:
        raise _fail(name, f"{where}: info lacks {', '.join(repr(k) for k in missing)}",
                    "info['strategy'], info['strategy_id'] and info['interaction'] on every "
                    "reset and step")
    strategy = info["strategy"]
    space: spaces.Box = inner.strategy_space  # type: ignore[attr-defined]
    if not isinstance(strategy, np.ndarray) or strategy.dtype != np.float32 \
            or strategy.shape != space.shape:
        described = (f"{type(strategy).__name__} of dtype {strategy.dtype} and shape "
                     f"{strategy.shape}" if isinstance(strategy, np.ndarray) else repr(strategy))
        raise _fail(name, f"{where}: info['strategy'] is a {described}",
                    f"info['strategy'] to be a float32 np.ndarray of shape {space.shape} "
                    f"(strategy_space.shape)")
    if not (np.all(np.isfinite(strategy)) and np.all(strategy >= space.low)
            and np.all(strategy <= space.high)):
        raise _fail(name, f"{where}: info['strategy'] = {strategy} is outside strategy_space "
                    f"[{space.low}, {space.high}]", "the strategy to lie in strategy_space")
    sid = info["strategy_id"]
    if isinstance(sid, bool) or not isinstance(sid, (int, np.integer)):
        raise _fail(name, f"{where}: info['strategy_id'] is {sid!r}",
                    "info['strategy_id'] to be an int (a discrete label, -1 where none exists)")
    got = info["interaction"]
    if isinstance(got, bool) or not isinstance(got, (int, np.integer)) or got != index:
        raise _fail(name, f"{where}: info['interaction'] is {got!r}, expected {index}",
                    "info['interaction'] = 0 after reset(seed=...) and one more for every "
                    "reset() without a seed")
    return strategy.copy()


def _rollout(env: gym.Env, inner: gym.Env, seed: int, n_interactions: int, horizon: int,
             name: str) -> list[_Interaction]:
    """``reset(seed)`` and then ``n_interactions`` interactions, checking as it goes."""
    space = env.action_space
    low = np.broadcast_to(space.low, space.shape)
    high = np.broadcast_to(space.high, space.shape)
    run: list[_Interaction] = []
    for i in range(n_interactions):
        # One generator per interaction: the replay gets the same actions even where an
        # interaction of the first run ended at another step (which the replay check reports).
        rng = np.random.default_rng([seed, i])
        where = f"interaction {i}, reset"
        try:
            obs, info = env.reset(seed=seed) if i == 0 else env.reset()
        except Exception as exc:
            raise _fail(name, f"{where}: reset raised {type(exc).__name__}: {exc}",
                        "reset() to start the next interaction") from exc
        strategy = _check_info(info, inner, i, where, name)
        sid = info["strategy_id"]
        _check_obs(env, obs, where, name)
        record = _Interaction([np.asarray(obs).copy()], [], [strategy], [int(sid)])
        ended = False
        for t in range(horizon):
            where = f"interaction {i}, step {t + 1}"
            try:
                action = rng.uniform(low, high).astype(space.dtype)
                obs, reward, terminated, truncated, info = env.step(action)
            except Exception as exc:
                raise _fail(name, f"{where}: step raised {type(exc).__name__}: {exc}",
                            f"step() to accept actions from the action space for up to "
                            f"horizon={horizon} steps") from exc
            step_strategy = _check_info(info, inner, i, where, name)
            if not np.array_equal(step_strategy, strategy) or info["strategy_id"] != sid:
                raise _fail(
                    name, f"{where}: the strategy changed within the interaction (reset: "
                    f"{strategy}, id {sid}; now: {step_strategy}, id {info['strategy_id']})",
                    "a strategy fixed during an interaction; the partner updates only when an "
                    "interaction ends, and the new strategy shows on the next reset")
            _check_obs(env, obs, where, name)
            if isinstance(reward, (bool, np.bool_)) or not isinstance(
                    reward, (int, float, np.integer, np.floating)) or not np.isfinite(reward):
                raise _fail(name, f"{where}: reward is {reward!r}", "finite number rewards")
            if "success" in info and not isinstance(info["success"], (bool, np.bool_)):
                raise _fail(name, f"{where}: info['success'] is {info['success']!r}",
                            "info['success'], where defined, to be a bool")
            record.obs.append(np.asarray(obs).copy())
            record.rewards.append(float(reward))
            record.strategies.append(step_strategy)
            record.strategy_ids.append(int(info["strategy_id"]))
            if terminated or truncated:
                ended = True
                break
        if not ended:
            raise _fail(name, f"interaction {i} did not end within horizon={horizon} steps "
                        f"(neither terminated nor truncated)",
                        "every interaction to end, terminated or truncated, within "
                        "env.unwrapped.horizon steps")
        run.append(record)
    return run


def _check_obs(env: gym.Env, obs: Any, where: str, name: str) -> None:
    arr = np.asarray(obs)
    if np.issubdtype(arr.dtype, np.number) and not np.all(np.isfinite(arr)):
        flat = arr.ravel()
        kinds = [(what, np.flatnonzero(test(flat)).tolist()) for what, test in
                 (("NaN", np.isnan), ("infinity", np.isinf))]
        found = "; ".join(f"{what} in dimension(s) {dims[:5]}" for what, dims in kinds if dims)
        raise _fail(name, f"{where}: the observation is not finite ({found})",
                    "finite observations (no NaN or infinity)")
    if not env.observation_space.contains(obs):
        raise _fail(name, f"{where}: the observation {shown(obs)} is not in the observation space "
                    f"{env.observation_space!r}", "observations inside the observation space")


def _check_replay(first: list[_Interaction], replay: list[_Interaction], seed: int,
                  name: str) -> None:
    for i, (a, b) in enumerate(zip(first, replay, strict=True)):
        if len(a.rewards) != len(b.rewards):
            raise _fail(name, f"reset(seed={seed}) did not replay the sequence: interaction {i} "
                        f"took {len(a.rewards)} steps, then {len(b.rewards)} with the same "
                        f"actions", _DETERMINISM_HINT)
        for t in range(len(a.obs)):
            when = "reset" if t == 0 else f"step {t}"
            for what, x, y in (("strategy", a.strategies[t], b.strategies[t]),
                               ("observation", a.obs[t], b.obs[t])):
                if not np.allclose(x, y):
                    raise _fail(name, f"reset(seed={seed}) did not replay the sequence: "
                                f"interaction {i}, {when}: {what} {x} first, {y} on replay "
                                f"with the same actions (not deterministic)", _DETERMINISM_HINT)
        if not np.allclose(a.rewards, b.rewards):
            raise _fail(name, f"reset(seed={seed}) did not replay the sequence: interaction {i} "
                        f"rewards differ with the same actions (not deterministic)",
                        _DETERMINISM_HINT)


def _check_no_leak(run: list[_Interaction], name: str) -> None:
    obs = np.stack([np.asarray(o, dtype=np.float64).ravel() for r in run for o in r.obs])
    strat = np.stack([s.astype(np.float64) for r in run for s in r.strategies])
    varied = [k for k in range(strat.shape[1]) if np.ptp(strat[:, k]) > 0]
    if not varied:
        warnings.warn(
            f"{name}: the strategy never changed during the check's {len(run)} interactions, "
            f"so whether it leaks into the observation could not be checked; try more "
            f"n_interactions or another seed", UserWarning, stacklevel=3)
        return
    ids = np.array([sid for r in run for sid in r.strategy_ids])
    values = np.unique(ids)
    # The strategy alone first, so that a plain copy is reported as one; then with the one-hot
    # of strategy_id, which catches an observation that encodes the label instead.
    designs = [np.stack([np.ones(len(obs)), *(strat[:, k] for k in varied)], axis=1)]
    if 1 < len(values) <= 16:
        onehot = [(ids == v).astype(np.float64) for v in values]
        designs.append(np.concatenate([designs[0], np.stack(onehot, axis=1)], axis=1))
    for j in range(obs.shape[1]):
        y = obs[:, j]
        spread = float(np.sum((y - y.mean()) ** 2))
        if spread <= 1e-12 * max(1.0, float(np.sum(y**2))):
            continue  # a constant feature cannot carry a strategy that changed
        for design in designs:
            coef, *_ = np.linalg.lstsq(design, y, rcond=None)
            unexplained = float(np.sum((y - design @ coef) ** 2)) / spread
            if unexplained < LEAK_TOLERANCE:
                raise _fail(
                    name, f"observation dimension {j} is an affine function of the strategy on "
                    f"every step of {len(run)} interactions (about obs[{j}] = "
                    f"{_affine_terms(coef, varied)}; {unexplained:.1e} of its variance "
                    f"unexplained) while the strategy changed (the strategy leaks into the "
                    f"observation)", "observations that never contain the strategy; report it "
                    "only in info['strategy'] (the Oracle baseline appends it with "
                    "OracleObservation)")


def _affine_terms(coef: np.ndarray, varied: list[int]) -> str:
    """The fit's terms that matter (the others are rounding noise, ~1e-16 of the largest)."""
    scale = 1e-9 * float(np.max(np.abs(coef)))
    terms = [f"{coef[0]:.3g}"] if abs(coef[0]) > scale else []
    terms += [f"{coef[1 + n]:.3g} * strategy[{k}]" for n, k in enumerate(varied)
              if abs(coef[1 + n]) > scale]
    if np.any(np.abs(coef[1 + len(varied):]) > scale):
        terms.append("a one-hot of strategy_id")
    return " + ".join(terms) or "0"

LEAK_TOLERANCE = 1e-6
"""Largest fraction of an observation feature's variance a strategy fit may leave unexplained
for the feature to count as a leak. Float32 copies leave about 1e-14; every feature of the
registered envs leaves at least 0.38 (Driving (2D)'s other car's x, which shows the lane only
after the merge), measured with check_env's defaults."""
