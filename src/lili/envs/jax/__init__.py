"""JAX-native repeated-interaction envs: the cheap domains as pure functions (gymnax style).

Point Mass (:class:`PointMass`, with its noisy and history partners), Driving (2D)
(:class:`Driving2D`) and the influence suite's :class:`InfluenceDrift`,
:class:`InfluenceSwitch` and :class:`InfluenceFlee`. The Gymnasium envs
(:mod:`lili.envs.point_mass`, :mod:`lili.envs.driving2d`, :mod:`lili.envs.influence`) are the
reference; these follow their rules step for step (``tests/test_jax_envs.py`` checks it), with the
partner's settings as a params pytree, so that a whole interaction is one ``lax.scan`` and many
runs, at different seeds and partner settings, one ``vmap``::

    from lili.envs.jax import PointMass, UniformPolicy, rollout_many, stack

    env = PointMass()
    params = stack([env.params(step_noise=s) for s in (0.0, 0.2, 0.4, 0.6)])
    keys = jax.random.split(jax.random.PRNGKey(0), 4)
    obs, state, tr = rollout_many(env, UniformPolicy((2,)), keys, params, 50, 10)
    tr.reward.shape   # (4, 10, 50): runs, interactions, steps

API (:mod:`.core`): ``env.params(**kwargs)`` takes the Gymnasium env's keyword arguments;
``env.reset(key, params) -> (obs, state)``; ``env.step(key, state, action, params) -> (obs,
state, reward, done, info)``, the partner updating inside the last step of an interaction;
``env.next_interaction(key, state, params) -> (obs, state)``; ``env.info(state, params)``.
:func:`make` builds an env and its params from a Gymnasium id or alias and its kwargs.
:mod:`.wrappers` has what the Oracles observe of any of them (:class:`StrategyObservation`,
:class:`LastInteractionObservation`).
"""

from __future__ import annotations

import inspect
from typing import Any

from lili.envs.core import resolve_env_id
from lili.envs.jax.core import EnvState, JaxRepeatedEnv, stack
from lili.envs.jax.drift import InfluenceDrift
from lili.envs.jax.driving2d import Driving2D
from lili.envs.jax.flee import InfluenceFlee
from lili.envs.jax.point_mass import PointMass
from lili.envs.jax.rollout import Transition, UniformPolicy, interaction, rollout, rollout_many
from lili.envs.jax.switch import InfluenceSwitch
from lili.envs.jax.wrappers import LastInteractionObservation, StrategyObservation

__all__ = ["JAX_ENVS", "Driving2D", "EnvState", "JaxRepeatedEnv", "InfluenceDrift",
           "InfluenceFlee", "InfluenceSwitch", "LastInteractionObservation", "PointMass",
           "StrategyObservation", "Transition", "UniformPolicy", "interaction", "make", "rollout",
           "rollout_many", "stack"]

# Gymnasium id -> the JAX env that follows it.
JAX_ENVS: dict[str, type[JaxRepeatedEnv]] = {
    "lili/PointMass-v0": PointMass,
    "lili/Driving2D-v0": Driving2D,
    "lili/InfluenceDrift-v0": InfluenceDrift,
    "lili/InfluenceSwitch-v0": InfluenceSwitch,
    "lili/InfluenceFlee-v0": InfluenceFlee,
}


def make(name: str, **env_kwargs: Any) -> tuple[JaxRepeatedEnv, Any]:
    """``(env, params)`` for a Gymnasium id or alias (``point-mass``) and its env kwargs.

    Raises ``ValueError`` naming the env when it has no JAX version, and the kwargs it takes
    when one is unknown.
    """
    env_id = resolve_env_id(name)
    if env_id not in JAX_ENVS:
        raise ValueError(f"env {name!r} has no JAX version; allowed: {', '.join(JAX_ENVS)}")
    env = JAX_ENVS[env_id]()
    allowed = list(inspect.signature(env.params).parameters)
    unknown = sorted(set(env_kwargs) - set(allowed))
    if unknown:
        raise ValueError(f"env kwargs {unknown} are not taken by the JAX {env_id}; allowed: "
                         f"{', '.join(allowed)}")
    return env, env.params(**env_kwargs)
