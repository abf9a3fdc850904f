"""Driving (2D) in JAX (:mod:`lili.envs.driving2d` is the reference and gives the rules): pass
a car that merges into the lane the ego passed in last time (the majority of the last N).

    env = Driving2D()                      # static: max_history = 16
    params = env.params(history=3)         # the Gymnasium env's keyword arguments

The ego's state (:class:`Cars`) holds both cars, whether they have collided, the step and the
lane the other car merges into in this interaction. The partner's state (:class:`LaneState`)
is that lane (-1 left, +1 right; ``strategy`` ``[lane]``, ``strategy_id`` 0 / 1) and its last
outcomes (True: the ego ended right). Its only draw is the first lane (:class:`ResetDraws`,
``right`` a fair coin, the reference's ``rng.choice([-1, 1])``); updates draw nothing.
``info["success"]``: passed without a collision.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
from flax import struct

from lili.envs.driving2d import (
    CAR_LENGTH,
    CAR_WIDTH,
    EGO_SPEED,
    LATERAL,
    MERGE_AFTER,
    OTHER_SPEED,
    OTHER_START,
    ROAD,
)
from lili.envs.jax.core import JaxRepeatedEnv
from lili.envs.jax.partners import Votes, check_history, no_votes, push_vote
from lili.envs.partners import check_partner_options

__all__ = ["Driving2D", "DrivingParams", "Cars", "LaneState", "ResetDraws", "HORIZON"]

HORIZON = 10  # the reference's fixed interaction length


@struct.dataclass
class DrivingParams:
    history: jax.Array
    horizon: jax.Array


@struct.dataclass
class Cars:
    ego: jax.Array  # (x, y)
    other: jax.Array  # (x, y)
    collided: jax.Array
    k: jax.Array  # steps taken in this interaction
    lane: jax.Array  # where the other car merges in this interaction


@struct.dataclass
class LaneState:
    lane: jax.Array
    votes: Votes


@struct.dataclass
class ResetDraws:
    right: jax.Array


@dataclass(frozen=True)
class Driving2D(JaxRepeatedEnv):
    """``lili/Driving2D-v0`` in JAX (see the module docstring)."""

    max_history: int = 16
    action_shape: tuple[int, ...] = (1,)
    observation_shape: tuple[int, ...] = (4,)
    strategy_shape: tuple[int, ...] = (1,)

    def params(self, history: int = 1) -> DrivingParams:
        """Params from the Gymnasium env's keyword arguments, checked as it checks them."""
        check_partner_options(0.0, history)
        check_history(history, self.max_history, "Driving2D")
        return DrivingParams(history=jnp.asarray(history, jnp.int32),
                             horizon=jnp.asarray(HORIZON, jnp.int32))

    # -- partner -----------------------------------------------------------------------------
    def reset_draws(self, key: jax.Array, params: DrivingParams) -> ResetDraws:
        return ResetDraws(jax.random.bernoulli(key))

    def update_draws(self, key: jax.Array, params: DrivingParams) -> tuple[()]:
        return ()

    def partner_reset(self, draws: ResetDraws, params: DrivingParams) -> LaneState:
        return LaneState(lane=jnp.where(draws.right, 1, -1).astype(jnp.int32),
                         votes=no_votes(self.max_history))

    def partner_update(self, partner: LaneState, outcome: jax.Array, draws: tuple[()],
                       params: DrivingParams) -> LaneState:
        votes, right = push_vote(partner.votes, outcome > 0, params.history)
        return LaneState(lane=jnp.where(right, 1, -1).astype(jnp.int32), votes=votes)

    def strategy(self, partner: LaneState, params: DrivingParams) -> jax.Array:
        return partner.lane.astype(jnp.float32)[None]

    def strategy_id(self, partner: LaneState) -> jax.Array:
        return (partner.lane > 0).astype(jnp.int32)

    # -- ego ---------------------------------------------------------------------------------
    def begin(self, partner: LaneState, params: DrivingParams) -> Cars:
        return Cars(ego=jnp.zeros(2, jnp.float32),
                    other=jnp.array([0.0, OTHER_START], jnp.float32),
                    collided=jnp.asarray(False), k=jnp.asarray(0, jnp.int32),
                    lane=partner.lane.astype(jnp.float32))

    def observe(self, ego: Cars) -> jax.Array:
        return jnp.concatenate([ego.ego, ego.other])

    def ego_step(self, ego: Cars, partner: LaneState, action: jax.Array,
                 params: DrivingParams) -> tuple[Cars, jax.Array, jax.Array]:
        a = jnp.clip(action[0], -1.0, 1.0)
        k = ego.k + 1
        t = k.astype(jnp.float32)
        me = jnp.stack([jnp.clip(ego.ego[0] + LATERAL * a, -ROAD, ROAD), EGO_SPEED * t])
        merge = jnp.clip((t - MERGE_AFTER) * 0.5, 0.0, 1.0)
        other = jnp.stack([ego.lane * merge, OTHER_START + OTHER_SPEED * t])
        hit = (jnp.abs(me[0] - other[0]) < CAR_WIDTH) & (jnp.abs(me[1] - other[1]) < CAR_LENGTH)
        reward = jnp.where(hit & ~ego.collided, -1.0, 0.0)
        return Cars(ego=me, other=other, collided=ego.collided | hit, k=k, lane=ego.lane), \
            reward, jnp.asarray(False)

    def outcome(self, ego: Cars, partner: LaneState, params: DrivingParams) -> jax.Array:
        """The ego's lane at the end: -1 (left) or +1 (right)."""
        return jnp.where(ego.ego[0] < 0, -1, 1).astype(jnp.int32)

    def success(self, ego: Cars, partner: LaneState, params: DrivingParams) -> jax.Array:
        return ~ego.collided
