"""``lili/InfluenceDrift-v0`` in JAX (:mod:`lili.envs.influence.drift` is the reference and
gives the rules): a goal on an 8-point grid that drifts one point toward the side where the ego
ended, or with probability ``returns`` goes back to one of the two points next to the start.

    env = InfluenceDrift()
    params = env.params(returns=0.05, horizon=4)   # the Gymnasium env's keyword arguments

The partner's state is the goal's index (``strategy_id``); ``strategy`` is ``[goal]``. Its
draws: the first index, uniform in [0, 8) (:class:`ResetDraws`), and per update a uniform
``u`` in [0, 1) (it returns when ``u < returns``) and the side it returns to, 0 or 1
(:class:`UpdateDraws`), in the order the reference draws them from its NumPy generator.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.influence.drift import GOALS, NEAR_START, RETURNS, SPEED
from lili.envs.influence.line import check_horizon, check_probability
from lili.envs.jax.line import JaxLineEnv, LineState

__all__ = ["InfluenceDrift", "DriftParams", "ResetDraws", "UpdateDraws"]


@struct.dataclass
class DriftParams:
    returns: jax.Array
    horizon: jax.Array


@struct.dataclass
class ResetDraws:
    index: jax.Array


@struct.dataclass
class UpdateDraws:
    u: jax.Array
    side: jax.Array


@dataclass(frozen=True)
class InfluenceDrift(JaxLineEnv):
    """``lili/InfluenceDrift-v0`` in JAX (see the module docstring)."""

    speed: float = SPEED
    strategy_shape: tuple[int, ...] = (1,)

    def params(self, horizon: int = 4, returns: float = RETURNS) -> DriftParams:
        """Params from the Gymnasium env's keyword arguments, checked as it checks them."""
        return DriftParams(returns=jnp.asarray(check_probability(returns, "returns"),
                                               jnp.float32),
                           horizon=jnp.asarray(check_horizon(horizon, 3), jnp.int32))

    def reset_draws(self, key: jax.Array, params: DriftParams) -> ResetDraws:
        return ResetDraws(jax.random.randint(key, (), 0, len(GOALS)))

    def update_draws(self, key: jax.Array, params: DriftParams) -> UpdateDraws:
        ku, ks = jax.random.split(key)
        return UpdateDraws(u=jax.random.uniform(ku, ()), side=jax.random.randint(ks, (), 0, 2))

    def partner_reset(self, draws: ResetDraws, params: DriftParams) -> jax.Array:
        return jnp.asarray(draws.index, jnp.int32)

    def partner_update(self, partner: jax.Array, outcome: jax.Array, draws: UpdateDraws,
                       params: DriftParams) -> jax.Array:
        drifted = jnp.clip(partner + outcome, 0, len(GOALS) - 1)
        back = jnp.asarray(NEAR_START, jnp.int32)[draws.side]
        return jnp.where(draws.u < params.returns, back, drifted).astype(jnp.int32)

    def goal(self, partner: jax.Array) -> jax.Array:
        return jnp.asarray(GOALS, jnp.float32)[partner]

    def strategy(self, partner: jax.Array, params: DriftParams) -> jax.Array:
        return self.goal(partner)[None]

    def strategy_id(self, partner: jax.Array) -> jax.Array:
        return partner

    def outcome(self, ego: LineState, partner: jax.Array, params: DriftParams) -> jax.Array:
        """The side of 0 where the ego ended: -1 left, +1 right (0 counts as right)."""
        return jnp.where(ego.x < 0, -1, 1).astype(jnp.int32)
