"""A variant of LILI's critic, not yet measured: ``lili-critic-ln``, LILI whose twin critic has a
LayerNorm in every hidden layer (:class:`lili.nets.TwinCritic` of two
:class:`lili.contrib.nets.LayerNormMLP`); everything else (encoder, decoder, actor, losses,
targets, acting) is LILI's.

The candidate fix of issue 36 (item 4) for the critic divergence that the records show in the
current core's one collapsing Point Mass seed (``docs/journal/2026-11-to-12.md``, "Point Mass
LILI's late collapses": its critic loss rose x1.4 and its Q by 0.4 while its return still held,
then x5.9 and +1.1 as the return fell). It sits here, not in the core, until a measurement
says it costs nothing on the paper's domains (``benchmarks/gpu_session.sh`` trains it on Point
Mass, seeds 0-13). No options (``extra["lili-critic-ln"]`` may only be empty).

``lili-flat-encoder-critic-ln`` puts the same critic beside ``lili-flat-encoder``'s encoder
(:mod:`lili.contrib.latents`), whose critic diverges on some seeds of the history partner from
N = 7 on (``docs/journal/2026-11-to-12.md``, "The flat encoder at N = 7"), to tell whether a
normalised critic stops that. Measured at N = 7 (three seeds): no Q climbs, but one seed's
critic loss still grows and its return falls ("The flat encoder with a layer-normed critic at
N = 7"); no gain over LILI.
"""

from __future__ import annotations

from lili.contrib.latents import FlatEncoderCore
from lili.contrib.nets import LayerNormMLP
from lili.contrib.variant import VariantCore, variant
from lili.nets import TwinCritic

__all__ = ["CriticLayerNormCore", "CriticLayerNormLILI", "FlatEncoderCriticLayerNormCore",
           "FlatEncoderCriticLayerNormLILI"]


class CriticLayerNormCore(VariantCore):
    """LILI's core whose twin critic's Q networks are :class:`~lili.contrib.nets.LayerNormMLP`
    (and so its target critic's, a Polyak copy of the same network)."""

    algo = "lili-critic-ln"

    def _build(self) -> None:
        super()._build()
        self.critic = TwinCritic(self.config.hidden, LayerNormMLP)


CriticLayerNormLILI = variant(CriticLayerNormCore, "LILI with LayerNorm in its critic's hidden "
                                                   "layers (``lili-critic-ln``).")


class FlatEncoderCriticLayerNormCore(CriticLayerNormCore, FlatEncoderCore):
    """``lili-flat-encoder``'s core (its encoder, and whole interactions in updates) whose
    twin critic is ``lili-critic-ln``'s: each parent's ``_build`` replaces its one network."""

    algo = "lili-flat-encoder-critic-ln"


FlatEncoderCriticLayerNormLILI = variant(
    FlatEncoderCriticLayerNormCore, "LILI with the flat encoder and a critic with LayerNorm in "
                                    "its hidden layers (``lili-flat-encoder-critic-ln``).")
