"""Variants of SLAC, built as diagnoses (:mod:`lili.agents.slac` for SLAC itself):

- ``slac-obs-critic``: SLAC whose critic reads the observation (the network frame at step t:
  normalised observation and phase) beside its sample of the latent model's belief. Everything
  else (the latent model, its loss and optimiser, the actor's history, acting) is SLAC's.
- ``slac-frame-actor``: SLAC whose actor reads the current frame only, as SAC's, while the
  latent model trains on and the critic's filter runs over SLAC's K + 1 frames. Everything
  else is SLAC's.
- ``slac-mean-critic``: SLAC whose critic reads the filter run on means (every z1 and z2 its
  distribution's mean given the means before it) instead of a sample of the belief. The model's
  own training still samples; everything else is SLAC's.
- ``slac-frame-critic``: SLAC whose critic reads the current frame only (normalised observation
  and phase), as SAC's, and no latent; the actor keeps SLAC's K frames, and the model still
  trains though nothing reads it. Everything else is SLAC's.

Why they exist: on Lunar Lander SLAC plays many interactions to the horizon without landing
where SAC, whose critic reads the observation, seldom does (``docs/journal/2026-11-to-12.md``,
"Lunar Lander SLAC at 4000 interactions"). SLAC's critic sees the lander only through a sample
of a belief trained to reconstruct it; if that sample blurs what decides a touchdown (height,
legs' contact), the critic cannot tell landing from hovering. This variant gives the critic
what SAC's has, so the difference between the two is the latent's. That left the lander
hovering; so did ``extra.slac.sequence_length: 1`` (an actor of one frame), which also cuts the
model's sequences to two frames ("Lunar Lander SLAC with one frame"). ``slac-frame-actor``
shortens the actor's history alone, and still hovered ("Lunar Lander SLAC whose actor reads one
frame, its model eight"): what every hovering variant kept was a critic that reads a sampled
latent. ``slac-mean-critic`` takes the sampling away and still hovers; ``slac-frame-critic``
takes the latent away and lands as SAC does ("Lunar Lander SLAC whose critic reads the latent's
mean or one frame"). Each variant's options are SLAC's
(:class:`~lili.agents.slac.SLACOptions`), read from ``extra[<its name>]``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from lili.agents.slac import SLAC, SLACCore, SLACOptions
from lili.contrib.variant import facade

__all__ = ["ObsCriticSLACCore", "ObsCriticSLAC", "FrameActorSLACCore", "FrameActorSLAC",
           "MeanCriticSLACCore", "MeanCriticSLAC", "FrameCriticSLACCore", "FrameCriticSLAC"]


def _variant(core: type[SLACCore], doc: str) -> type[SLAC]:
    """The facade of ``core``, registered under its ``options_key`` (the variant's algo, under
    which a config's ``extra`` holds its options, SLAC's)."""
    return facade(SLAC, core, core.options_key, SLACOptions,
                  core.__name__.removesuffix("Core"), doc)


class ObsCriticSLACCore(SLACCore):
    """SLAC's core whose critic input is [z, phase, x_t] instead of [z, phase]."""

    options_key = "slac-obs-critic"

    def _input_dims(self) -> tuple[int, int]:
        critic, actor = super()._input_dims()
        return critic + self.x_dim, actor

    def _critic_in(self, z: jax.Array, t: jax.Array, x: jax.Array) -> jax.Array:
        return jnp.concatenate([self._critic_x(z, t), x], -1)


ObsCriticSLAC = _variant(ObsCriticSLACCore, "SLAC whose critic reads the observation beside "
                                           "the latent (``slac-obs-critic``).")


class FrameActorSLACCore(SLACCore):
    """SLAC's core whose actor reads the current frame only (the model keeps K)."""

    options_key = "slac-frame-actor"
    actor_frames = 1


FrameActorSLAC = _variant(FrameActorSLACCore, "SLAC whose actor reads the current frame only "
                                             "(``slac-frame-actor``).")


class MeanCriticSLACCore(SLACCore):
    """SLAC's core whose critic reads the filter's means, not a sample of its belief."""

    options_key = "slac-mean-critic"
    critic_samples = False


MeanCriticSLAC = _variant(MeanCriticSLACCore, "SLAC whose critic reads the filter run on means "
                                             "(``slac-mean-critic``).")


class FrameCriticSLACCore(SLACCore):
    """SLAC's core whose critic input is the frame x_t (observation and phase), no latent."""

    options_key = "slac-frame-critic"

    def _input_dims(self) -> tuple[int, int]:
        return self.x_dim, super()._input_dims()[1]

    def _critic_in(self, z: jax.Array, t: jax.Array, x: jax.Array) -> jax.Array:
        return x


FrameCriticSLAC = _variant(FrameCriticSLACCore, "SLAC whose critic reads the current frame only "
                                               "(``slac-frame-critic``).")
