"""Networks: MLPs, the tanh-Gaussian actor, the twin critic, LILI's encoder and decoder (Flax)."""

from __future__ import annotations

from collections.abc import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from lili.dists import soft_clip_log_std

__all__ = ["MLP", "Actor", "TwinCritic", "Encoder", "Decoder"]


class MLP(nn.Module):
    """ReLU MLP with a linear output layer."""

    hidden: Sequence[int]
    out: int

    @nn.compact
    def __call__(self, x: jax.Array) -> jax.Array:
        for h in self.hidden:
            x = nn.relu(nn.Dense(h)(x))
        return nn.Dense(self.out)(x)


class Actor(nn.Module):
    """Gaussian policy head: returns (mean, log_std) of the pre-tanh action."""

    hidden: Sequence[int]
    act_dim: int

    @nn.compact
    def __call__(self, x: jax.Array) -> tuple[jax.Array, jax.Array]:
        out = MLP(self.hidden, 2 * self.act_dim)(x)
        mean, log_std = jnp.split(out, 2, axis=-1)
        return mean, soft_clip_log_std(log_std)


class TwinCritic(nn.Module):
    """Two independent Q networks evaluated together; returns shape [2, batch]. Each is
    ``q_net(hidden, 1)``: an :class:`MLP` here, another network of that signature in a variant
    (:class:`lili.contrib.nets.LayerNormMLP`)."""

    hidden: Sequence[int]
    q_net: type[nn.Module] = MLP

    @nn.compact
    def __call__(self, x: jax.Array, a: jax.Array) -> jax.Array:
        q = nn.vmap(
            self.q_net,
            variable_axes={"params": 0},
            split_rngs={"params": True},
            in_axes=None,
            out_axes=0,
            axis_size=2,
        )(self.hidden, 1)
        return q(jnp.concatenate([x, a], -1))[..., 0]


class Encoder(nn.Module):
    """E: the transitions of the last N interactions -> z (deterministic).

    Each interaction is embedded by a per-transition MLP and a weighted mean over its
    transitions (permutation-invariant, so early termination and any H work; the weights are the
    validity mask, see ``InteractionBuffer.window`` for when they are not all 0/1); the N
    embeddings are concatenated in order and mapped linearly to z.

    Input ``x``: [..., N, S, features]; ``weight``: [..., N, S] (0 for padding).
    """

    hidden: Sequence[int]
    latent_dim: int

    @nn.compact
    def __call__(self, x: jax.Array, weight: jax.Array) -> jax.Array:
        h = x
        for width in self.hidden:
            h = nn.relu(nn.Dense(width)(h))
        # The head's layers are made before z's, so that z's Dense keeps the last index: the
        # core's parameter names do not depend on whether a variant's head adds layers.
        pooled = self.head(pool(h, weight))
        return nn.Dense(self.latent_dim)(pooled)

    def head(self, pooled: jax.Array) -> jax.Array:
        """What the pooled features pass before the linear map to z: nothing here; a variant's
        hook (called inside ``__call__``, so it may create layers)."""
        return pooled


def pool(h: jax.Array, weight: jax.Array) -> jax.Array:
    """Each interaction's weighted mean of per-transition features ``h`` [..., N, S, F] over its
    steps, the N interactions' means concatenated in order: [..., N * F]."""
    w = weight[..., None].astype(h.dtype)
    pooled = (h * w).sum(-2) / jnp.maximum(w.sum(-2), 1e-6)
    return pooled.reshape(*pooled.shape[:-2], -1)


class Decoder(nn.Module):
    """D: (s, a, z) -> mean of the (normalised) next-state change and reward."""

    hidden: Sequence[int]
    out: int

    @nn.compact
    def __call__(self, s: jax.Array, a: jax.Array, z: jax.Array) -> jax.Array:
        return MLP(self.hidden, self.out)(jnp.concatenate([s, a, z], -1))
