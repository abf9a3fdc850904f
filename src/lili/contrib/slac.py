"""Variants of SLAC, built as diagnoses (:mod:`lili.agents.slac` for SLAC itself):

- ``slac-obs-critic``: SLAC whose critic reads the observation (the network frame at step t:
  normalised observation and phase) beside its sample of the latent model's belief. Everything
  else (the latent model, its loss and optimiser, the actor's history, acting) is SLAC's.
- ``slac-frame-actor``: SLAC whose actor reads the current frame only, as SAC's, while the
  latent model trains on and the critic's filter runs over SLAC's K + 1 frames. Everything
  else is SLAC's.

Why it exists: on Lunar Lander SLAC plays many interactions to the horizon without landing
where SAC, whose critic reads the observation, seldom does (``docs/journal/2026-11-to-12.md``,
"Lunar Lander SLAC at 4000 interactions"). SLAC's critic sees the lander only through a sample
of a belief trained to reconstruct it; if that sample blurs what decides a touchdown (height,
legs' contact), the critic cannot tell landing from hovering. This variant gives the critic
what SAC's has, so the difference between the two is the latent's. That left the lander
hovering; so did ``extra.slac.sequence_length: 1`` (an actor of one frame), which also cuts the
model's sequences to two frames ("Lunar Lander SLAC with one frame"). ``slac-frame-actor``
shortens the actor's history alone. Each variant's options are SLAC's
(:class:`~lili.agents.slac.SLACOptions`), read from ``extra[<its name>]``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from lili.agents.registry import register
from lili.agents.slac import SLAC, SLACCore, SLACOptions

__all__ = ["ObsCriticSLACCore", "ObsCriticSLAC", "FrameActorSLACCore", "FrameActorSLAC"]


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


class FrameActorSLACCore(SLACCore):
    """SLAC's core whose actor reads the current frame only (the model keeps K)."""

    options_key = "slac-frame-actor"
    actor_frames = 1


class FrameActorSLAC(SLAC):
    """SLAC whose actor reads the current frame only (``slac-frame-actor``)."""

    algo = "slac-frame-actor"
    core_cls = FrameActorSLACCore


register("slac-frame-actor", FrameActorSLAC, options=SLACOptions)
