"""Network pieces only :mod:`lili.contrib` uses: the straight-through one-hot, the nearest code
of a codebook, an encoder that carries its codebook, one with an MLP after its pooling and one
that reads its interactions as one flat input (:mod:`lili.contrib.latents`), and a Q network
with LayerNorm in its hidden layers (:mod:`lili.contrib.critics`' twin critic)."""

from __future__ import annotations

from collections.abc import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from lili.nets import MLP, Encoder

__all__ = ["straight_through_one_hot", "nearest_code", "QuantisedEncoder", "SetEncoder",
           "FlatEncoder", "LayerNormMLP"]


def straight_through_one_hot(logits: jax.Array) -> jax.Array:
    """The one-hot of ``logits``' largest entry, with the softmax's gradient (Bengio et al.
    2013's straight-through estimator): the forward value is exactly one-hot, so everything
    downstream sees one of ``logits.shape[-1]`` names, while the encoder still learns."""
    soft = jax.nn.softmax(logits, axis=-1)
    hard = jax.nn.one_hot(jnp.argmax(logits, axis=-1), logits.shape[-1], dtype=soft.dtype)
    return soft + jax.lax.stop_gradient(hard - soft)


def nearest_code(e: jax.Array, codebook: jax.Array) -> jax.Array:
    """The codebook row [K, L] nearest to each of ``e`` [..., L] (squared distance), without
    gradient to ``e``: vector quantisation (van den Oord et al. 2017)."""
    d = ((e[..., None, :] - codebook) ** 2).sum(-1)
    return codebook[jnp.argmin(d, axis=-1)]


class QuantisedEncoder(nn.Module):
    """:class:`~lili.nets.Encoder` plus a codebook of ``codes`` vectors (the parameter
    ``codebook`` [codes, latent_dim], read by the caller), so that a Polyak copy of the encoder
    carries its codebook along. Returns the encoder's output before quantisation."""

    hidden: Sequence[int]
    latent_dim: int
    codes: int

    @nn.compact
    def __call__(self, x: jax.Array, weight: jax.Array) -> jax.Array:
        self.param("codebook", nn.initializers.normal(0.5), (self.codes, self.latent_dim))
        return Encoder(self.hidden, self.latent_dim)(x, weight)


class SetEncoder(Encoder):
    """E as Deep Sets' rho(mean phi): :class:`lili.nets.Encoder`'s per-transition MLP and
    pooling, then an MLP of the same widths on the pooled features before the linear map to z.
    The core's E maps the pooled features linearly, so z is a linear function of a mean over
    transitions, and what depends on two transitions at once (Flee's next slot: the slot, read
    from the rewards, and where the ego stopped, read from the last step) can only be in z as a
    sum; here z can hold it as such."""

    def head(self, pooled: jax.Array) -> jax.Array:
        for width in self.hidden:
            pooled = nn.relu(nn.Dense(width)(pooled))
        return pooled


class FlatEncoder(nn.Module):
    """E as one MLP over the N interactions' transitions laid side by side: every step of every
    interaction, each in its place ([..., N, S, features] flattened to N * S * features, padding
    zeroed by ``weight``), so each of the N x S places has weights of its own. LILI's E
    (:class:`lili.nets.Encoder`) embeds every transition with one shared network and pools each
    interaction, so what it must learn grows little with N; here it grows N-fold (the paper's
    history experiment says only that its encoder "takes the last N trajectories as input")."""

    hidden: Sequence[int]
    latent_dim: int

    @nn.compact
    def __call__(self, x: jax.Array, weight: jax.Array) -> jax.Array:
        flat = (x * weight[..., None].astype(x.dtype)).reshape(*x.shape[:-3], -1)
        return MLP(self.hidden, self.latent_dim)(flat)


class LayerNormMLP(nn.Module):
    """:class:`~lili.nets.MLP` with a LayerNorm (learned scale and bias) between each hidden
    layer's Dense and its ReLU, as in the critics of Ball et al. 2023 (RLPD, where it curbs the
    critic's over-extrapolation) and Nauman et al. 2024 (BRO): each hidden feature vector is
    rescaled to zero mean and unit variance before its learned scale and bias, so Q no longer
    grows with the scale of its input or of the layers before."""

    hidden: Sequence[int]
    out: int

    @nn.compact
    def __call__(self, x: jax.Array) -> jax.Array:
        for h in self.hidden:
            x = nn.relu(nn.LayerNorm()(nn.Dense(h)(x)))
        return nn.Dense(self.out)(x)

