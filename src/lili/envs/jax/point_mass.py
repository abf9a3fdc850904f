"""Point Mass in pure JAX: the rules of :mod:`lili.envs.point_mass` (the reference), with the
partner's settings as params so that runs with different partners share one program.

    env = PointMass()                                   # static: max_history = 16
    params = env.params(step_noise=0.4, history=5)      # the Gymnasium env's keyword arguments
    obs, state = env.reset(key, params)
    obs, state, reward, done, info = env.step(key, state, action, params)

``params`` (:class:`PointMassParams`): ``step_noise`` (sigma as a fraction of the 0.2 rad
step), ``history`` (N, the majority over the last N outcomes, at most ``max_history``),
``inside_sign`` (-1 for ``inside_turn="clockwise"``, the default, +1 for
``"counterclockwise"``) and ``horizon``. The partner's state (:class:`CircleState`) is the angle
``theta`` and its last ``max_history`` outcomes, most recent first. Its draws: the index of the
first angle on the 0.2 grid (an integer in [0, 32), :class:`ResetDraws`) and one standard
normal per update (:class:`UpdateDraws`, scaled by ``step_noise * 0.2``; NumPy's
``rng.normal(0, s)`` is ``s`` times its standard normal, so the two can be aligned).

Computed in float32 (the reference works in float64 and returns float32 observations).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from lili.envs.jax.core import JaxRepeatedEnv
from lili.envs.jax.partners import Votes, check_history, no_votes, push_vote
from lili.envs.partners import check_partner_options
from lili.envs.point_mass import BOUND, CENTER, INSIDE_TURNS, RADIUS, SPEED, STEP

__all__ = ["PointMass", "PointMassParams", "CircleState", "ResetDraws", "UpdateDraws",
           "N_ANGLES"]

# The first angle is STEP * k, k drawn from [0, N_ANGLES) (the reference's grid).
N_ANGLES = int(2 * np.pi / STEP) + 1


@struct.dataclass
class PointMassParams:
    """The partner's settings and the horizon (arrays, so that they can be stacked)."""

    step_noise: jax.Array
    history: jax.Array
    inside_sign: jax.Array
    horizon: jax.Array


@struct.dataclass
class CircleState:
    """The target's angle and the last outcomes (True: ended inside)."""

    theta: jax.Array
    votes: Votes


@struct.dataclass
class ResetDraws:
    index: jax.Array  # the first angle is STEP * index


@struct.dataclass
class UpdateDraws:
    z: jax.Array  # standard normal; the step is STEP * (1 + step_noise * z)


@dataclass(frozen=True)
class PointMass(JaxRepeatedEnv):
    """``lili/PointMass-v0`` in JAX. ``max_history``: the largest ``history`` its params may
    take (the size of the partner's memory)."""

    max_history: int = 16
    action_shape: tuple[int, ...] = (2,)
    observation_shape: tuple[int, ...] = (2,)
    strategy_shape: tuple[int, ...] = (2,)

    def params(self, step_noise: float = 0.0, history: int = 1, horizon: int = 50,
               inside_turn: str = "clockwise") -> PointMassParams:
        """Params from the Gymnasium env's keyword arguments, checked as it checks them."""
        check_partner_options(step_noise, history)
        check_history(history, self.max_history, "PointMass")
        if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) \
                or horizon < 1:
            raise ValueError(f"horizon={horizon!r} is invalid; allowed: an integer >= 1")
        if inside_turn not in INSIDE_TURNS:
            raise ValueError(f"inside_turn={inside_turn!r} is invalid; allowed: "
                             f"{', '.join(INSIDE_TURNS)}")
        return PointMassParams(
            step_noise=jnp.asarray(step_noise, jnp.float32),
            history=jnp.asarray(history, jnp.int32),
            inside_sign=jnp.asarray(-1.0 if inside_turn == "clockwise" else 1.0, jnp.float32),
            horizon=jnp.asarray(horizon, jnp.int32))

    # -- partner -----------------------------------------------------------------------------
    def reset_draws(self, key: jax.Array, params: PointMassParams) -> ResetDraws:
        return ResetDraws(jax.random.randint(key, (), 0, N_ANGLES))

    def update_draws(self, key: jax.Array, params: PointMassParams) -> UpdateDraws:
        return UpdateDraws(jax.random.normal(key, ()))

    def partner_reset(self, draws: ResetDraws, params: PointMassParams) -> CircleState:
        return CircleState(theta=STEP * jnp.asarray(draws.index, jnp.float32),
                           votes=no_votes(self.max_history))

    def partner_update(self, partner: CircleState, outcome: jax.Array, draws: UpdateDraws,
                       params: PointMassParams) -> CircleState:
        votes, inside = push_vote(partner.votes, outcome, params.history)
        step = STEP + params.step_noise * STEP * draws.z
        sign = jnp.where(inside, params.inside_sign, -params.inside_sign)
        theta = jnp.mod(partner.theta + sign * step, 2 * jnp.pi)
        return CircleState(theta=theta, votes=votes)

    def target(self, partner: CircleState) -> jax.Array:
        return jnp.asarray(CENTER, jnp.float32) + RADIUS * jnp.stack(
            [jnp.cos(partner.theta), jnp.sin(partner.theta)])

    def strategy(self, partner: CircleState, params: PointMassParams) -> jax.Array:
        return self.target(partner)

    # -- ego ---------------------------------------------------------------------------------
    def begin(self, partner: CircleState, params: PointMassParams) -> jax.Array:
        return jnp.zeros(2, jnp.float32)

    def observe(self, ego: jax.Array) -> jax.Array:
        return ego

    def ego_step(self, ego: jax.Array, partner: CircleState, action: jax.Array,
                 params: PointMassParams) -> tuple[jax.Array, jax.Array, jax.Array]:
        pos = jnp.clip(ego + SPEED * jnp.clip(action, -1.0, 1.0), -BOUND, BOUND)
        reward = -jnp.linalg.norm(pos - self.target(partner))
        return pos, reward, jnp.asarray(False)

    def outcome(self, ego: jax.Array, partner: CircleState, params: PointMassParams) -> jax.Array:
        """True when the ego ended inside the circle."""
        return jnp.linalg.norm(ego - jnp.asarray(CENTER, jnp.float32)) < RADIUS
