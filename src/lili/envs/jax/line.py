"""The influence suite's shared body in JAX (:mod:`lili.envs.influence.line` is the reference):
an ego on a line that starts each interaction at x = 0, moves ``x <- clip(x + speed * a, -1,
1)`` and pays ``-|x - goal|`` after the move. Its state (:class:`LineState`) is ``x`` and the
last action (what Switch's partner reads); it observes ``[x]``. Subclasses give ``speed`` and
the partner's ``goal``; :class:`HorizonOnlyLineEnv` is the base of those whose only option is
the horizon and whose partner draws nothing after its first strategy (Switch, Flee).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.influence.line import check_horizon
from lili.envs.jax.core import JaxRepeatedEnv

__all__ = ["HorizonOnlyLineEnv", "HorizonParams", "JaxLineEnv", "LineState"]


@struct.dataclass
class LineState:
    x: jax.Array
    last_action: jax.Array


class JaxLineEnv(JaxRepeatedEnv):
    """Base of the JAX influence envs (see the module docstring)."""

    speed: float
    action_shape: tuple[int, ...] = (1,)
    observation_shape: tuple[int, ...] = (1,)

    def goal(self, partner: Any) -> jax.Array:
        """Where the partner's current strategy wants the ego."""
        raise NotImplementedError

    def begin(self, partner: Any, params: Any) -> LineState:
        return LineState(x=jnp.asarray(0.0, jnp.float32),
                         last_action=jnp.asarray(0.0, jnp.float32))

    def observe(self, ego: LineState) -> jax.Array:
        return ego.x[None]

    def ego_step(self, ego: LineState, partner: Any, action: jax.Array,
                 params: Any) -> tuple[LineState, jax.Array, jax.Array]:
        a = jnp.clip(action[0], -1.0, 1.0)
        x = jnp.clip(ego.x + self.speed * a, -1.0, 1.0)
        return LineState(x=x, last_action=a), -jnp.abs(x - self.goal(partner)), \
            jnp.asarray(False)


@struct.dataclass
class HorizonParams:
    """The params of a :class:`HorizonOnlyLineEnv`: the steps of an interaction."""

    horizon: jax.Array


class HorizonOnlyLineEnv(JaxLineEnv):
    """A line env whose only option is the horizon (4 by default, at least 4, as in the
    Gymnasium env) and whose partner's updates draw nothing (``UpdateDraws`` is the empty
    tuple)."""

    def params(self, horizon: int = 4) -> HorizonParams:
        """Params from the Gymnasium env's keyword arguments, checked as it checks them."""
        return HorizonParams(horizon=jnp.asarray(check_horizon(horizon, 4), jnp.int32))

    def update_draws(self, key: jax.Array, params: HorizonParams) -> tuple[()]:
        return ()
