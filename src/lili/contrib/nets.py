"""Network pieces only :mod:`lili.contrib` uses: the straight-through one-hot, the nearest code
of a codebook, an encoder that carries its codebook and one with an MLP after its pooling
(:mod:`lili.contrib.latents`), and a Q network with LayerNorm in its hidden layers
(:mod:`lili.contrib.critics`' twin critic)."""

from __future__ import annotations

from collections.abc import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from lili.nets import Encoder

__all__ = ["straight_through_one_hot", "nearest_code", "QuantisedEncoder", "SetEncoder",
           "LayerNormMLP"]


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

