"""The uniform random policy: the floor every learning curve is read against.

The paper reports it for air hockey (a random blocker stops 18% of shots). It is an agent like
the others (same run folder, metrics, checkpoints, ``lili eval``) so that reports need no
special case; it simply never learns.
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp

from lili.agents.sac import SAC, Params

__all__ = ["RandomPolicy"]


class RandomPolicy(SAC):
    """Uniform random actions in the action space; no updates (``train_block`` is a no-op).

    ``deterministic`` is ignored: a random policy has no mode. The action comes from the key the
    caller passes (the training loop derives it from ``(seed, interaction, step)``), so runs are
    reproducible.
    """

    algo: ClassVar[str] = "random"

    def _act(self, actor: Params, norm: dict, obs: jax.Array, t: jax.Array, z: jax.Array,
             key: jax.Array, deterministic: bool) -> jax.Array:
        return jax.random.uniform(key, (self.act_dim,), jnp.float32, -1.0, 1.0)

    def train_block(self, key: jax.Array) -> dict[str, float]:
        return {}
