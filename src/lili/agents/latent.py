"""What the latent agents (LILI, LILAC and their variants) share: the decoder's reconstruction
loss and the slicing of a batch's window of interactions."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from lili.agents.base import Normaliser, Params
from lili.buffer import Batch, Window
from lili.dists import unit_gaussian_nll
from lili.nets import Decoder

__all__ = ["decoder_loss", "window_part"]


def decoder_loss(decoder: Decoder, params: Params, norm: Normaliser, batch: Batch,
                 z: jax.Array) -> jax.Array:
    """J_rep's reconstruction term: the unit-variance Gaussian NLL of tau^k's normalised
    (s' - s, r) under D(s, a, z^k), with ``z`` [B, L] held for each interaction's transitions."""
    s = norm.obs(batch["obs"])
    target = jnp.concatenate([norm.delta(batch["obs"], batch["next_obs"]),
                              norm.rew(batch["rew"])[..., None]], -1)
    zb = jnp.broadcast_to(z[:, None, :], (*s.shape[:-1], z.shape[-1]))
    return unit_gaussian_nll(decoder.apply(params, s, batch["act"], zb), target)


def window_part(window: Window, part: slice) -> Window:
    """The interactions ``part`` of a batch's windows ([B, N + 1, ...] -> [B, len, ...]): the
    window holds k-N..k, so ``slice(None, -1)`` is E's input for z^k, ``slice(1, None)`` for
    z^{k+1}, and ``slice(-1, None)`` interaction k itself."""
    return {k: v[:, part] for k, v in window.items()}
