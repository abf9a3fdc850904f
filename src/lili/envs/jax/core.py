"""The environment contract of :mod:`lili.envs.core`, as pure JAX functions (gymnax style).

A :class:`JaxRepeatedEnv` is a small frozen (hashable) object that holds only *static* settings
(array sizes); everything that may differ between runs in one program (the partner's sigma, its
history N, the horizon) lives in a ``params`` pytree of arrays, and everything that changes
while playing lives in an :class:`EnvState` pytree. So ``reset`` and ``step`` jit, ``vmap``
over keys and over stacked params (:func:`stack`), and ``lax.scan`` over the steps of an
interaction.

- ``reset(key, params) -> (obs, state)``: interaction 0 with a fresh partner, its first
  strategy drawn from ``key`` (the Gymnasium env's ``reset(seed=s)``).
- ``step(key, state, action, params) -> (obs, state, reward, done, info)``: one step. On the
  last step of an interaction (``done``) the partner updates *inside the step*, as in the
  Gymnasium env: the returned ``state`` already holds the next strategy, drawn from ``key``.
- ``next_interaction(key, state, params) -> (obs, state)``: start interaction ``i + 1`` under
  the partner's current strategy (the Gymnasium env's ``reset()`` without a seed). An
  interaction abandoned before its end does not update the partner, as there.
- ``info(state, params)``: what a policy may be told before it acts (``strategy``,
  ``strategy_id``, ``interaction``, ``t``), the keys of the Gymnasium env's ``info``.

``step``'s ``info`` has a fixed structure (jit needs one): ``strategy`` (the strategy this step
was played under, float32), ``strategy_id`` (-1 where the env has none), ``interaction``,
``t`` (steps taken in this interaction), ``outcome`` (what the partner reacts to; meaningful
where ``done``), ``terminated``, ``truncated``, ``active`` and, where the env defines success,
``success`` (meaningful where ``done``). A step after the end of an interaction (the Gymnasium
env raises there; under ``vmap`` over different horizons a fixed-length scan makes them)
changes nothing: reward 0, ``done`` True, ``active``, ``terminated`` and ``truncated`` False.

The Oracle's observation (:class:`lili.envs.OracleObservation`) is ``obs`` with the strategy
of the interaction appended: for a step's next observation that is the step's
``info["strategy"]``, not ``info(state)`` of the returned state, which after the last step
already holds the next strategy (:class:`lili.envs.jax.wrappers.StrategyObservation`).

The partner's randomness is isolated in *draws*: ``reset`` is ``reset_with(reset_draws(key,
params), params)`` and ``step`` is ``step_with(update_draws(key, params), state, action,
params)``. Everything after the draws is deterministic, so a test can hand the JAX env the very
numbers a NumPy generator drew for the Gymnasium env (``tests/test_jax_envs.py``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

__all__ = ["EnvState", "JaxRepeatedEnv", "stack", "tree_where"]

Info = dict[str, jax.Array]


@struct.dataclass
class EnvState:
    """Where a repeated interaction stands: the ego's part (``ego``, reset every interaction),
    the partner's (``partner``: its strategy and memory), the step ``t`` in the interaction,
    the ``interaction`` index and whether the interaction has ended (``done``)."""

    ego: Any
    partner: Any
    t: jax.Array
    interaction: jax.Array
    done: jax.Array


def tree_where(cond: jax.Array, new: Any, old: Any) -> Any:
    """``new`` where ``cond`` else ``old``, leaf by leaf (a scalar ``cond``)."""
    return jax.tree.map(lambda a, b: jnp.where(cond, a, b), new, old)


def stack(trees: list[Any] | tuple[Any, ...]) -> Any:
    """Stack pytrees of the same structure (e.g. K params) along a new leading axis, for vmap."""
    if not trees:
        raise ValueError("stack() needs at least one pytree; got none")
    return jax.tree.map(lambda *leaves: jnp.stack(leaves), *trees)


class JaxRepeatedEnv:
    """Base of the JAX-native repeated-interaction envs (see the module docstring).

    Subclasses are frozen dataclasses and implement the hooks below; the bookkeeping (``t``,
    the interaction index, the horizon, the partner's update at the end, masking after the
    end, ``info``) lives here, once, as in :class:`lili.envs.core.RepeatedInteractionEnv`.
    Every params pytree has an integer ``horizon``.
    """

    action_shape: tuple[int, ...]
    observation_shape: tuple[int, ...]
    strategy_shape: tuple[int, ...]

    def params(self, **env_kwargs: Any) -> Any:
        """The params pytree from the Gymnasium env's keyword arguments (checked as it does)."""
        raise NotImplementedError

    # -- partner hooks -----------------------------------------------------------------------
    def reset_draws(self, key: jax.Array, params: Any) -> Any:
        """The partner's random numbers for a fresh sequence (its first strategy)."""
        raise NotImplementedError

    def update_draws(self, key: jax.Array, params: Any) -> Any:
        """The partner's random numbers for one update (drawn every step, used on the last)."""
        raise NotImplementedError

    def partner_reset(self, draws: Any, params: Any) -> Any:
        """The partner's state at the start of a sequence, given ``reset_draws``."""
        raise NotImplementedError

    def partner_update(self, partner: Any, outcome: jax.Array, draws: Any, params: Any) -> Any:
        """The partner's state for the next interaction after one that ended in ``outcome``."""
        raise NotImplementedError

    def strategy(self, partner: Any, params: Any) -> jax.Array:
        """The current strategy as a float32 vector (the Gymnasium env's ``info['strategy']``)."""
        raise NotImplementedError

    def strategy_id(self, partner: Any) -> jax.Array:
        """A discrete label of the current strategy, or -1 where the env has none."""
        return jnp.asarray(-1, jnp.int32)

    # -- ego hooks ---------------------------------------------------------------------------
    def begin(self, partner: Any, params: Any) -> Any:
        """The ego's state at the start of an interaction."""
        raise NotImplementedError

    def observe(self, ego: Any) -> jax.Array:
        """The observation of the ego's state (float32)."""
        raise NotImplementedError

    def ego_step(self, ego: Any, partner: Any, action: jax.Array,
                 params: Any) -> tuple[Any, jax.Array, jax.Array]:
        """Advance one step: ``(ego, reward, terminated)``."""
        raise NotImplementedError

    def outcome(self, ego: Any, partner: Any, params: Any) -> jax.Array:
        """What the partner reacts to when the interaction ends in ``ego``."""
        raise NotImplementedError

    def success(self, ego: Any, partner: Any, params: Any) -> jax.Array | None:
        """Whether the interaction that ends in ``ego`` succeeded, or None where the env
        defines no success (then ``info`` has no ``success`` key)."""
        return None

    # -- the API -----------------------------------------------------------------------------
    def reset(self, key: jax.Array, params: Any) -> tuple[jax.Array, EnvState]:
        """Interaction 0 with a fresh partner whose first strategy is drawn from ``key``."""
        return self.reset_with(self.reset_draws(key, params), params)

    def reset_with(self, draws: Any, params: Any) -> tuple[jax.Array, EnvState]:
        """:meth:`reset` given the partner's draws."""
        partner = self.partner_reset(draws, params)
        ego = self.begin(partner, params)
        state = EnvState(ego=ego, partner=partner, t=jnp.asarray(0, jnp.int32),
                         interaction=jnp.asarray(0, jnp.int32), done=jnp.asarray(False))
        return self.observe(ego), state

    def next_interaction(self, key: jax.Array, state: EnvState,
                         params: Any) -> tuple[jax.Array, EnvState]:
        """Start interaction ``i + 1`` under the partner's current strategy.

        ``key`` is for envs whose interactions start at random; these envs start at a fixed
        point and ignore it.
        """
        del key
        ego = self.begin(state.partner, params)
        state = state.replace(ego=ego, t=jnp.zeros_like(state.t),
                              interaction=state.interaction + 1,
                              done=jnp.zeros_like(state.done))
        return self.observe(ego), state

    def info(self, state: EnvState, params: Any) -> Info:
        """What a policy may be told before it acts (the Gymnasium env's ``info`` keys)."""
        return {"strategy": self.strategy(state.partner, params).astype(jnp.float32),
                "strategy_id": self.strategy_id(state.partner), "interaction": state.interaction,
                "t": state.t}

    def step(self, key: jax.Array, state: EnvState, action: jax.Array,
             params: Any) -> tuple[jax.Array, EnvState, jax.Array, jax.Array, Info]:
        """One step; on the last step of an interaction the partner updates (draws from ``key``)."""
        return self.step_with(self.update_draws(key, params), state, action, params)

    def step_with(self, draws: Any, state: EnvState, action: jax.Array,
                  params: Any) -> tuple[jax.Array, EnvState, jax.Array, jax.Array, Info]:
        """:meth:`step` given the partner's draws."""
        action = jnp.asarray(action, jnp.float32)
        if action.shape != self.action_shape:
            raise ValueError(f"action has shape {action.shape}; expected {self.action_shape}")
        info = self.info(state, params)
        ego, reward, terminated = self.ego_step(state.ego, state.partner, action, params)
        t = state.t + 1
        terminated = jnp.asarray(terminated)
        truncated = ~terminated & (t >= params.horizon)
        done = terminated | truncated
        outcome = self.outcome(ego, state.partner, params)
        partner = tree_where(done, self.partner_update(state.partner, outcome, draws, params),
                             state.partner)
        live = ~state.done
        new = tree_where(live, EnvState(ego=ego, partner=partner, t=t,
                                        interaction=state.interaction, done=done), state)
        info.update(t=new.t, outcome=outcome, terminated=terminated & live,
                    truncated=truncated & live, active=live)
        success = self.success(ego, state.partner, params)
        if success is not None:
            info["success"] = success
        reward = jnp.where(live, reward, 0.0).astype(jnp.float32)
        return self.observe(new.ego), new, reward, new.done, info
