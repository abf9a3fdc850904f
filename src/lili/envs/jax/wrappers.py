"""What the Oracles observe, for the JAX-native envs: the twins of
:class:`lili.envs.OracleObservation` and :class:`lili.envs.wrappers.LastInteractionObservation`.

Each wraps a :class:`~lili.envs.jax.core.JaxRepeatedEnv` and has its API (``reset``, ``step``,
``next_interaction``, ``info``, and ``reset_with`` / ``step_with`` for aligned draws), with the
observation extended, so the training program (:mod:`lili.jax_train`) plays an Oracle as any
other agent, the extension computed inside its scan:

- :class:`StrategyObservation` (the Oracle): ``obs`` and the strategy of the interaction. For a
  step's next observation that is the step's ``info["strategy"]`` (the strategy the step was
  played under), not that of the returned state, which after an interaction's last step already
  holds the next strategy: the next strategy shows in the first observation of the next
  interaction, as in the Gymnasium wrapper. Its state is the wrapped env's.
- :class:`LastInteractionObservation` (the last-interaction Oracle): ``obs`` and, fixed for the
  whole interaction, the last interaction's strategy, last observation and last action (and with
  ``outcome`` its ``info["outcome"]``), zeros in interaction 0 of a sequence. Its state
  (:class:`LastState`) adds what it remembers to the wrapped env's.

Both refuse an env that reports no strategy (a ``strategy_shape`` other than one axis of at
least one number), with the Gymnasium wrappers' message.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.jax.core import EnvState, Info, JaxRepeatedEnv

__all__ = ["LastInteractionObservation", "LastState", "StrategyObservation"]


def _strategy_size(env: JaxRepeatedEnv, who: str) -> int:
    """The size of ``env``'s strategy vector, or a ValueError saying that ``who`` needs one."""
    shape = getattr(env, "strategy_shape", None)
    if not isinstance(shape, tuple) or len(shape) != 1 or shape[0] < 1:
        raise ValueError(f"{who} needs the partner's true strategy, and JAX env "
                         f"{type(env).__name__} reports none (strategy_shape {shape!r}); "
                         "allowed: a JAX env with a strategy vector (strategy_shape (n,))")
    return int(shape[0])


def _flat_size(shape: tuple[int, ...], what: str, who: str) -> int:
    """The size of a one-axis ``shape``, or a ValueError saying that ``who`` needs one."""
    if len(shape) != 1:
        raise ValueError(f"{who} needs a flat {what}; got shape {shape}; allowed: a JAX env "
                         f"whose {what} has one axis, (n,)")
    return int(shape[0])


@dataclass(frozen=True)
class _Wrapper:
    """What both wrappers pass through: the wrapped env's params, shapes and draws."""

    env: JaxRepeatedEnv

    @property
    def action_shape(self) -> tuple[int, ...]:
        return self.env.action_shape

    @property
    def strategy_shape(self) -> tuple[int, ...]:
        return self.env.strategy_shape

    def params(self, **env_kwargs: Any) -> Any:
        """The wrapped env's params."""
        return self.env.params(**env_kwargs)

    def reset_draws(self, key: jax.Array, params: Any) -> Any:
        """The wrapped env's draws for a fresh sequence."""
        return self.env.reset_draws(key, params)

    def update_draws(self, key: jax.Array, params: Any) -> Any:
        """The wrapped env's draws for one partner update."""
        return self.env.update_draws(key, params)

    def reset(self, key: jax.Array, params: Any) -> tuple[jax.Array, Any]:
        """The wrapped env's :meth:`~JaxRepeatedEnv.reset`, observed by the Oracle."""
        return self.reset_with(self.reset_draws(key, params), params)

    def step(self, key: jax.Array, state: Any, action: jax.Array,
             params: Any) -> tuple[jax.Array, Any, jax.Array, jax.Array, Info]:
        """The wrapped env's :meth:`~JaxRepeatedEnv.step`, observed by the Oracle."""
        return self.step_with(self.update_draws(key, params), state, action, params)

    def reset_with(self, draws: Any, params: Any) -> tuple[jax.Array, Any]:
        """:meth:`reset` given the partner's draws."""
        raise NotImplementedError

    def step_with(self, draws: Any, state: Any, action: jax.Array,
                  params: Any) -> tuple[jax.Array, Any, jax.Array, jax.Array, Info]:
        """:meth:`step` given the partner's draws."""
        raise NotImplementedError


@dataclass(frozen=True)
class StrategyObservation(_Wrapper):
    """The Oracle's view of ``env``: the observation and the interaction's strategy."""

    def __post_init__(self) -> None:
        _flat_size(self.env.observation_shape, "observation", "the Oracle")
        _strategy_size(self.env, "the Oracle")

    @property
    def observation_shape(self) -> tuple[int, ...]:
        return (self.env.observation_shape[0] + self.env.strategy_shape[0],)

    def _join(self, obs: jax.Array, strategy: jax.Array) -> jax.Array:
        return jnp.concatenate([obs, strategy.astype(jnp.float32)])

    def info(self, state: EnvState, params: Any) -> Info:
        return self.env.info(state, params)

    def reset_with(self, draws: Any, params: Any) -> tuple[jax.Array, EnvState]:
        obs, state = self.env.reset_with(draws, params)
        return self._join(obs, self.env.info(state, params)["strategy"]), state

    def step_with(self, draws: Any, state: EnvState, action: jax.Array,
                  params: Any) -> tuple[jax.Array, EnvState, jax.Array, jax.Array, Info]:
        obs, state, reward, done, info = self.env.step_with(draws, state, action, params)
        return self._join(obs, info["strategy"]), state, reward, done, info

    def next_interaction(self, key: jax.Array, state: EnvState,
                         params: Any) -> tuple[jax.Array, EnvState]:
        obs, state = self.env.next_interaction(key, state, params)
        return self._join(obs, self.env.info(state, params)["strategy"]), state


@struct.dataclass
class LastState:
    """The wrapped env's state (``env``) and what the last-interaction Oracle remembers:
    ``shown`` (appended to every observation of this interaction), and of this interaction so
    far its ``strategy``, latest observation ``obs``, latest action ``act`` and ``outcome``
    (one number, or none without the outcome)."""

    env: EnvState
    shown: jax.Array
    strategy: jax.Array
    obs: jax.Array
    act: jax.Array
    outcome: jax.Array


@dataclass(frozen=True)
class LastInteractionObservation(_Wrapper):
    """The last-interaction Oracle's view of ``env`` (module docstring); ``outcome``: also the
    last interaction's ``info["outcome"]`` (every JAX env's outcome is one number)."""

    outcome: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.outcome, bool):
            raise ValueError(f"outcome={self.outcome!r} is invalid; allowed: True or False")
        who = "the last-interaction Oracle"
        _flat_size(self.env.observation_shape, "observation", who)
        _flat_size(self.env.action_shape, "action", who)
        _strategy_size(self.env, who)

    @property
    def _shown_size(self) -> int:
        return (self.env.strategy_shape[0] + self.env.observation_shape[0]
                + self.env.action_shape[0] + int(self.outcome))

    @property
    def observation_shape(self) -> tuple[int, ...]:
        return (self.env.observation_shape[0] + self._shown_size,)

    def info(self, state: LastState, params: Any) -> Info:
        return self.env.info(state.env, params)

    def _start(self, obs: jax.Array, env_state: EnvState, shown: jax.Array, act: jax.Array,
               outcome: jax.Array, params: Any) -> tuple[jax.Array, LastState]:
        """An interaction's first observation and state, showing ``shown`` throughout. The
        latest action and outcome carry over until a step replaces them, as there."""
        strategy = self.env.info(env_state, params)["strategy"].astype(jnp.float32)
        state = LastState(env=env_state, shown=shown, strategy=strategy, obs=obs, act=act,
                          outcome=outcome)
        return jnp.concatenate([obs, shown]), state

    def reset_with(self, draws: Any, params: Any) -> tuple[jax.Array, LastState]:
        obs, env_state = self.env.reset_with(draws, params)
        return self._start(obs, env_state, jnp.zeros(self._shown_size, jnp.float32),
                           jnp.zeros(self.env.action_shape, jnp.float32),
                           jnp.zeros(int(self.outcome), jnp.float32), params)

    def step_with(self, draws: Any, state: LastState, action: jax.Array,
                  params: Any) -> tuple[jax.Array, LastState, jax.Array, jax.Array, Info]:
        obs, env_state, reward, done, info = self.env.step_with(draws, state.env, action,
                                                                params)
        live = info["active"]  # a step after the end changes nothing, here too
        ended = info["terminated"] | info["truncated"]
        outcome = jnp.reshape(info["outcome"], (-1,))[:int(self.outcome)].astype(jnp.float32)
        state = state.replace(
            env=env_state, obs=jnp.where(live, obs, state.obs),
            act=jnp.where(live, jnp.asarray(action, jnp.float32), state.act),
            outcome=jnp.where(ended, outcome, state.outcome))
        return jnp.concatenate([obs, state.shown]), state, reward, done, info

    def next_interaction(self, key: jax.Array, state: LastState,
                         params: Any) -> tuple[jax.Array, LastState]:
        obs, env_state = self.env.next_interaction(key, state.env, params)
        shown = jnp.concatenate([state.strategy, state.obs, state.act, state.outcome])
        return self._start(obs, env_state, shown, state.act, state.outcome, params)
