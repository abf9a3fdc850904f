"""The influence suite's shared body in JAX (:mod:`lili.envs.influence.line` is the reference):
an ego on a line that starts each interaction at x = 0, moves ``x <- clip(x + speed * a, -1,
1)`` and pays ``-|x - goal|`` after the move. Its state (:class:`LineState`) is ``x`` and the
last action (what Switch's partner reads); it observes ``[x]``. Subclasses give ``speed`` and
the partner's ``goal``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.jax.core import JaxRepeatedEnv

__all__ = ["JaxLineEnv", "LineState"]


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
