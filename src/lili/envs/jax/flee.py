"""``lili/InfluenceFlee-v0`` in JAX (:mod:`lili.envs.influence.flee` is the reference and
gives the rules): a partner on nine slots that moves one slot away from where the ego stopped,
and stays home (g = 0) while the ego stops there.

    env = InfluenceFlee()
    params = env.params(horizon=4)   # the Gymnasium env's keyword arguments

The partner's state is its slot k in -4..4 (``strategy_id`` k + 4); ``strategy`` is ``[0.25
k]``. Its only draw is the first slot, an index uniform in [0, 8) over the slots away from home
(:class:`ResetDraws`: index i is slot i - 4 below home, i - 3 above); its updates draw nothing
(``UpdateDraws`` is the empty tuple).

x is float32 here and float64 in the reference, so an end within float32 rounding of a
half-slot boundary (x = +-0.125, +-0.375, ...) may be read as the neighbouring slot; the
boundaries themselves are exact in both, and the window where the two can differ is about
1e-8 wide.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.influence.flee import SLOT, SLOTS, SPEED
from lili.envs.jax.line import HorizonOnlyLineEnv, HorizonParams, LineState

__all__ = ["InfluenceFlee", "FleeParams", "ResetDraws", "fled"]

FleeParams = HorizonParams  # Flee's only option is its horizon


@struct.dataclass
class ResetDraws:
    """The first slot's index in [0, 8) (module docstring)."""

    index: jax.Array


def fled(k: jax.Array, k_end: jax.Array) -> jax.Array:
    """:func:`lili.envs.influence.flee.fled` on arrays: the next slot from ``k`` after the ego
    stopped at slot ``k_end``."""
    side = jnp.where(k > 0, 1, -1)
    away = jnp.where(side * k_end > side * k, k - side,
                     jnp.where(jnp.abs(k) == SLOTS, -side, k + side))
    home = jnp.where(k_end == 0, 0, jnp.where(k_end > 0, -1, 1))
    return jnp.where(k == 0, home, away).astype(jnp.int32)


@dataclass(frozen=True)
class InfluenceFlee(HorizonOnlyLineEnv):
    """``lili/InfluenceFlee-v0`` in JAX (see the module docstring)."""

    speed: float = SPEED
    strategy_shape: tuple[int, ...] = (1,)

    def reset_draws(self, key: jax.Array, params: FleeParams) -> ResetDraws:
        return ResetDraws(jax.random.randint(key, (), 0, 2 * SLOTS))

    def partner_reset(self, draws: ResetDraws, params: FleeParams) -> jax.Array:
        k = jnp.asarray(draws.index, jnp.int32) - SLOTS
        return jnp.where(k >= 0, k + 1, k)

    def partner_update(self, partner: jax.Array, outcome: jax.Array, draws: tuple[()],
                       params: FleeParams) -> jax.Array:
        return fled(partner, outcome)

    def goal(self, partner: jax.Array) -> jax.Array:
        return SLOT * partner.astype(jnp.float32)

    def strategy(self, partner: jax.Array, params: FleeParams) -> jax.Array:
        return self.goal(partner)[None]

    def strategy_id(self, partner: jax.Array) -> jax.Array:
        return partner + SLOTS

    def outcome(self, ego: LineState, partner: jax.Array, params: FleeParams) -> jax.Array:
        """The slot nearest where the ego stopped (halves round up), in -4..4."""
        return jnp.clip(jnp.floor(ego.x / SLOT + 0.5), -SLOTS, SLOTS).astype(jnp.int32)
