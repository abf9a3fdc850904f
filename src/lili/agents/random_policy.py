"""The uniform random policy: the floor every learning curve is read against.

The paper reports it for air hockey (a random blocker stops 18% of shots). It is an agent like
the others (same run folder, metrics, checkpoints, ``lili eval``) so that reports need no
special case; it simply never learns.
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp

from lili.agents.base import ActingState, AgentState, Normaliser, Params
from lili.agents.core import SACCore
from lili.agents.registry import register
from lili.agents.sac import SAC
from lili.buffer import InteractionBuffer

__all__ = ["RandomPolicy", "RandomCore"]


class RandomCore(SACCore):
    """Uniform actions from the caller's key; the learning block is a no-op."""

    def _act(self, actor: Params, norm: Normaliser, obs: jax.Array, acting: ActingState,
             key: jax.Array, deterministic: bool) -> tuple[jax.Array, ActingState]:
        a = jax.random.uniform(key, (self.act_dim,), jnp.float32, -1.0, 1.0)
        return a, acting.replace(t=acting.t + 1)

    def learn_block(self, state: AgentState, buffer: InteractionBuffer,
                    key: jax.Array) -> tuple[AgentState, dict[str, float]]:
        return state, {}


class RandomPolicy(SAC):
    """Uniform random actions in the action space; no updates.

    ``deterministic`` is ignored: a random policy has no mode. The action comes from the key the
    caller passes (the training loop derives it from ``(seed, interaction, step)``), so runs are
    reproducible.
    """

    algo: ClassVar[str] = "random"
    core_cls = RandomCore


register("random", RandomPolicy)
