"""Diagonal Gaussian pieces shared by every agent: log-density, KL, soft-clipped log-std and the
tanh-squashed sample of SAC's actor. One implementation each (agents import them from here)."""

from __future__ import annotations

import jax
import jax.numpy as jnp

__all__ = ["LOG_STD_MIN", "LOG_STD_MAX", "soft_clip_log_std", "gaussian_logp", "gaussian_kl",
           "tanh_gaussian", "unit_gaussian_nll"]

LOG_STD_MIN, LOG_STD_MAX = -5.0, 2.0


def soft_clip_log_std(log_std: jax.Array) -> jax.Array:
    """Squash a raw log-std into [LOG_STD_MIN, LOG_STD_MAX] smoothly.

    A hard clip kills the gradient at the bounds; tanh keeps it alive (as SAC implementations do).
    """
    return LOG_STD_MIN + 0.5 * (LOG_STD_MAX - LOG_STD_MIN) * (jnp.tanh(log_std) + 1)


def gaussian_logp(x: jax.Array, mean: jax.Array, log_std: jax.Array) -> jax.Array:
    """Element-wise log N(x; mean, exp(log_std)^2) (not summed)."""
    return -0.5 * (((x - mean) / jnp.exp(log_std)) ** 2 + 2 * log_std + jnp.log(2 * jnp.pi))


def gaussian_kl(mean_q: jax.Array, log_std_q: jax.Array, mean_p: jax.Array,
                log_std_p: jax.Array) -> jax.Array:
    """KL(N(mean_q, std_q) || N(mean_p, std_p)) of diagonal Gaussians, summed over the last axis."""
    var_q, var_p = jnp.exp(2 * log_std_q), jnp.exp(2 * log_std_p)
    kl = log_std_p - log_std_q + (var_q + (mean_q - mean_p) ** 2) / (2 * var_p) - 0.5
    return kl.sum(-1)


def unit_gaussian_nll(pred: jax.Array, target: jax.Array) -> jax.Array:
    """Negative log-likelihood (up to a constant) of ``target`` under N(pred, I): summed over the
    last axis, mean over the rest. The decoder loss of LILI and LILAC (in normalised units)."""
    return 0.5 * ((pred - target) ** 2).sum(-1).mean()


def tanh_gaussian(
    mean: jax.Array, log_std: jax.Array, key: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """Sample a = tanh(u), u ~ N(mean, std); return (a, log pi(a)) with the tanh correction."""
    u = mean + jnp.exp(log_std) * jax.random.normal(key, mean.shape)
    logp = gaussian_logp(u, mean, log_std)
    # log(1 - tanh(u)^2) written stably.
    logp = logp - 2 * (jnp.log(2.0) - u - jax.nn.softplus(-2 * u))
    return jnp.tanh(u), logp.sum(-1)
