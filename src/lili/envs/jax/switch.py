"""``lili/InfluenceSwitch-v0`` in JAX (:mod:`lili.envs.influence.switch` is the reference and
gives the rules): three modes (goals -0.75, 0, +0.75) switched by a known table of the mode
and the direction of the ego's last action.

    env = InfluenceSwitch()
    params = env.params(horizon=4)   # the Gymnasium env's keyword arguments

The partner's state is the mode (``strategy_id``); ``strategy`` is its one-hot. Its only draw
is the first mode, uniform in [0, 3) (:class:`ResetDraws`); its updates draw nothing
(``UpdateDraws`` is the empty tuple).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from lili.envs.influence.switch import DEADBAND, GOALS, NEXT_MODE, SPEED
from lili.envs.jax.line import HorizonOnlyLineEnv, HorizonParams, LineState

__all__ = ["InfluenceSwitch", "SwitchParams", "ResetDraws", "NEXT_MODE_TABLE"]

# NEXT_MODE as a table: [mode, direction + 1] -> next mode.
NEXT_MODE_TABLE = np.array([[NEXT_MODE[(mode, d)] for d in (-1, 0, 1)] for mode in range(3)],
                           np.int32)
# The largest float32 <= DEADBAND: a float32 action is "still" in float32 exactly when it is in
# the reference's float64 comparison (float32(0.1) is a little above 0.1).
_DEADBAND32 = np.float32(DEADBAND)
if _DEADBAND32 > DEADBAND:
    _DEADBAND32 = np.nextafter(_DEADBAND32, np.float32(0))


SwitchParams = HorizonParams  # Switch's only option is its horizon


@struct.dataclass
class ResetDraws:
    mode: jax.Array


@dataclass(frozen=True)
class InfluenceSwitch(HorizonOnlyLineEnv):
    """``lili/InfluenceSwitch-v0`` in JAX (see the module docstring)."""

    speed: float = SPEED
    strategy_shape: tuple[int, ...] = (3,)

    def reset_draws(self, key: jax.Array, params: SwitchParams) -> ResetDraws:
        return ResetDraws(jax.random.randint(key, (), 0, len(GOALS)))

    def partner_reset(self, draws: ResetDraws, params: SwitchParams) -> jax.Array:
        return jnp.asarray(draws.mode, jnp.int32)

    def partner_update(self, partner: jax.Array, outcome: jax.Array, draws: tuple[()],
                       params: SwitchParams) -> jax.Array:
        return jnp.asarray(NEXT_MODE_TABLE)[partner, outcome + 1]

    def goal(self, partner: jax.Array) -> jax.Array:
        return jnp.asarray(GOALS, jnp.float32)[partner]

    def strategy(self, partner: jax.Array, params: SwitchParams) -> jax.Array:
        return jax.nn.one_hot(partner, len(GOALS), dtype=jnp.float32)

    def strategy_id(self, partner: jax.Array) -> jax.Array:
        return partner

    def outcome(self, ego: LineState, partner: jax.Array, params: SwitchParams) -> jax.Array:
        """The direction of the last action: -1 left, 0 still (``|a| <= DEADBAND``), +1 right."""
        a = ego.last_action
        return jnp.where(jnp.abs(a) <= _DEADBAND32, 0, jnp.where(a < 0, -1, 1)).astype(jnp.int32)
