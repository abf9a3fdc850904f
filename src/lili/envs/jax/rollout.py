"""Whole interactions as one ``lax.scan``, and many runs as one ``vmap``.

A policy here is any ``policy_fn(key, obs, info) -> action`` of JAX arrays, where ``info`` is
:meth:`~lili.envs.jax.core.JaxRepeatedEnv.info` of the state that produced ``obs`` (so a policy
*told* the strategy reads ``info["strategy"]``, as :mod:`lili.envs.influence.scripted`'s do).
It must be hashable to be a static argument of :func:`rollout_many` (a module-level function,
or a frozen dataclass such as :class:`UniformPolicy`).

- :func:`interaction`: one interaction, ``horizon`` steps, one ``lax.scan``.
- :func:`rollout`: ``reset``, then ``n_interactions`` interactions (a scan of scans), the
  partner updating between them inside the env.
- :func:`rollout_many`: :func:`rollout` jitted and vmapped over K keys and K stacked params
  (:func:`lili.envs.jax.core.stack`), e.g. K seeds of the noisy partner at K sigmas.

``horizon`` is static (the scan's length) and should be the largest ``params.horizon``: steps
after an interaction's end are inactive (``info["active"]`` False, reward 0), and an interaction
cut short by a smaller ``horizon`` is abandoned (its partner does not update).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.jax.core import EnvState, Info, JaxRepeatedEnv

__all__ = ["Transition", "UniformPolicy", "interaction", "rollout", "rollout_many"]

PolicyFn = Callable[[jax.Array, jax.Array, Info], jax.Array]


@struct.dataclass
class Transition:
    """One step: what was observed, done, earned and seen next, and the step's ``info``."""

    obs: jax.Array
    action: jax.Array
    reward: jax.Array
    next_obs: jax.Array
    done: jax.Array
    info: Info


@dataclass(frozen=True)
class UniformPolicy:
    """Actions uniform in [-1, 1]^shape (the envs' action box), ignoring obs and info."""

    shape: tuple[int, ...]

    def __call__(self, key: jax.Array, obs: jax.Array, info: Info) -> jax.Array:
        return jax.random.uniform(key, self.shape, jnp.float32, -1.0, 1.0)


def interaction(env: JaxRepeatedEnv, policy_fn: PolicyFn, key: jax.Array, obs: jax.Array,
                state: EnvState, params: Any,
                horizon: int) -> tuple[jax.Array, EnvState, Transition]:
    """Play ``horizon`` steps from ``(obs, state)``: ``(last obs, state, transitions)``, the
    transitions stacked along a leading axis of length ``horizon``."""

    def body(carry: tuple[jax.Array, EnvState], key: jax.Array):
        obs, state = carry
        k_act, k_env = jax.random.split(key)
        action = policy_fn(k_act, obs, env.info(state, params))
        next_obs, state, reward, done, info = env.step(k_env, state, action, params)
        return (next_obs, state), Transition(obs, action, reward, next_obs, done, info)

    (obs, state), transitions = jax.lax.scan(body, (obs, state), jax.random.split(key, horizon))
    return obs, state, transitions


def rollout(env: JaxRepeatedEnv, policy_fn: PolicyFn, key: jax.Array, params: Any,
            horizon: int, n_interactions: int = 1) -> tuple[jax.Array, EnvState, Transition]:
    """``reset`` and play ``n_interactions`` interactions: ``(obs, state, transitions)``, where
    ``(obs, state)`` starts the next, unplayed interaction and the transitions have leading
    axes ``(n_interactions, horizon)``."""
    k_reset, k_play = jax.random.split(key)
    obs, state = env.reset(k_reset, params)

    def body(carry: tuple[jax.Array, EnvState], key: jax.Array):
        obs, state = carry
        k_play, k_next = jax.random.split(key)
        _, state, transitions = interaction(env, policy_fn, k_play, obs, state, params, horizon)
        obs, state = env.next_interaction(k_next, state, params)
        return (obs, state), transitions

    (obs, state), transitions = jax.lax.scan(body, (obs, state),
                                             jax.random.split(k_play, n_interactions))
    return obs, state, transitions


@partial(jax.jit, static_argnames=("env", "policy_fn", "horizon", "n_interactions"))
def rollout_many(env: JaxRepeatedEnv, policy_fn: PolicyFn, keys: jax.Array, params: Any,
                 horizon: int, n_interactions: int = 1) -> tuple[jax.Array, EnvState, Transition]:
    """:func:`rollout` for K runs in one jitted program: ``keys`` has shape (K, ...) and every
    leaf of ``params`` a leading axis of K; every output gains a leading axis of K."""
    return jax.vmap(lambda k, p: rollout(env, policy_fn, k, p, horizon, n_interactions))(
        keys, params)
