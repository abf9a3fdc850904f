"""A variant of SLAC's critic, measured as a diagnosis: ``slac-obs-critic``, SLAC whose critic
reads the observation (the network frame at step t: normalised observation and phase) beside
its sample of the latent model's belief. Everything else (the latent model, its loss and
optimiser, the actor's history, acting) is SLAC's (:mod:`lili.agents.slac`).

Why it exists: on Lunar Lander SLAC plays many interactions to the horizon without landing
where SAC, whose critic reads the observation, seldom does (``docs/journal/2026-11-to-12.md``,
"Lunar Lander SLAC at 4000 interactions"). SLAC's critic sees the lander only through a sample
of a belief trained to reconstruct it; if that sample blurs what decides a touchdown (height,
legs' contact), the critic cannot tell landing from hovering. This variant gives the critic
what SAC's has, so the difference between the two is the latent's. Its options are SLAC's
(:class:`~lili.agents.slac.SLACOptions`), read from ``extra["slac-obs-critic"]``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from lili.agents.registry import register
from lili.agents.slac import SLAC, SLACCore, SLACOptions

__all__ = ["ObsCriticSLACCore", "ObsCriticSLAC"]


class ObsCriticSLACCore(SLACCore):
    """SLAC's core whose critic input is [z, phase, x_t] instead of [z, phase]."""

    options_key = "slac-obs-critic"

    def _input_dims(self) -> tuple[int, int]:
        critic, actor = super()._input_dims()
        return critic + self.x_dim, actor

    def _critic_in(self, z: jax.Array, t: jax.Array, x: jax.Array) -> jax.Array:
        return jnp.concatenate([self._critic_x(z, t), x], -1)


class ObsCriticSLAC(SLAC):
    """SLAC whose critic reads the observation beside the latent (``slac-obs-critic``)."""

    algo = "slac-obs-critic"
    core_cls = ObsCriticSLACCore


register("slac-obs-critic", ObsCriticSLAC, options=SLACOptions)
