"""Variants of LILI's latent; the first five measured no gain on Drift
(``docs/journal/2026-11-to-12.md``, "Drift: a categorical latent", "a bottlenecked latent, and
one target per next strategy", "the noise stops SAC through the critic"), each a subclass of
:class:`LILICore` and :class:`LILI` under its own algo name, with its options in
``AgentConfig.extra[<algo>]``:

- ``lili-categorical``: z is the one-hot of E's largest output (straight-through gradient), so
  that z names one of ``latent_dim`` strategies; option ``balance`` (1.0).
- ``lili-quantised``: z is the nearest of ``codes`` (16) learned code vectors to E's output
  (straight-through), with VQ-VAE's codebook and commitment losses.
- ``lili-bottleneck``: the decoder reads z + eps and J_rep pays ``weight`` (0.1) * |z|^2 / 2,
  an information bottleneck on z.
- ``lili-posterior``: E is regressed onto a second encoder P(tau^i), whose code D decodes.
- ``lili-prediction-critic``: the critic reads what z predicts (D at fixed probe inputs)
  instead of z.
- ``lili-set-encoder``: E maps its pooled transition features to z by an MLP (Deep Sets'
  rho), not linearly (tried on Flee, issue 36).
- ``lili-flat-encoder``: E is one MLP over every step of the last N interactions in place (the
  history table's "LILI (N = 11) ≈ SAC", issue 34).

Each gives, with its options at the values ``AgentConfig`` once had, the numbers of the
``latent_kind`` / ``latent_bottleneck`` / ``latent_target`` / ``critic_latent`` fields it
replaces (``lili.config.RETIRED_FIELDS``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from lili.agents.base import Normaliser, Params
from lili.agents.core import sg
from lili.agents.latent import decoder_loss, window_part
from lili.buffer import Batch, Window
from lili.contrib.nets import (
    FlatEncoder,
    QuantisedEncoder,
    SetEncoder,
    nearest_code,
    straight_through_one_hot,
)
from lili.contrib.variant import VariantCore, variant
from lili.nets import Decoder, Encoder

__all__ = ["CategoricalOptions", "QuantisedOptions", "BottleneckOptions", "CategoricalLILI",
           "QuantisedLILI", "BottleneckLILI", "PosteriorLILI", "PredictionCriticLILI",
           "SetEncoderLILI", "FlatEncoderLILI",
           "category_imbalance", "quantisation_loss", "bottleneck_kl", "PROBES", "probe_inputs",
           "decoder_predictions"]

PROBES = 16
"""Probe inputs at which ``lili-prediction-critic`` reads the decoder."""


def _check(algo: str, name: str, value: Any, ok: bool, allowed: str) -> None:
    if not ok:
        raise ValueError(f"config extra.{algo}.{name}={value!r} is invalid; allowed: {allowed}")


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


@dataclass(frozen=True)
class CategoricalOptions:
    """``extra["lili-categorical"]``. ``balance``: the weight in J_rep of log K - H of the
    batch's mean category probabilities (0 = off), which keeps the encoder from sending every
    interaction to one category (:func:`category_imbalance`)."""

    balance: float = 1.0

    def __post_init__(self) -> None:
        _check("lili-categorical", "balance", self.balance,
               _is_number(self.balance) and self.balance >= 0, "a finite number >= 0")


@dataclass(frozen=True)
class QuantisedOptions:
    """``extra["lili-quantised"]``. ``codes``: the size of the codebook."""

    codes: int = 16

    def __post_init__(self) -> None:
        _check("lili-quantised", "codes", self.codes, isinstance(self.codes, int)
               and not isinstance(self.codes, bool) and self.codes >= 2, "an integer >= 2")


@dataclass(frozen=True)
class BottleneckOptions:
    """``extra["lili-bottleneck"]``. ``weight``: beta, the price of z's size in J_rep."""

    weight: float = 0.1

    def __post_init__(self) -> None:
        _check("lili-bottleneck", "weight", self.weight,
               _is_number(self.weight) and self.weight > 0, "a finite number > 0")


def category_imbalance(p: jax.Array) -> jax.Array:
    """log K - H(p) >= 0 for the batch's mean category probabilities ``p`` [K]: zero when the
    batch uses all K categories equally. A one-hot latent whose encoder starts with one
    largest output for nearly every input never trains the decoder on the other categories
    and stays collapsed (measured on Drift: 499 of 500 interactions in one category); this
    term spreads the batch over the categories so the decoder can tell them apart."""
    k = p.shape[-1]
    return jnp.log(k) + (p * jnp.log(jnp.maximum(p, 1e-12))).sum(-1)


def quantisation_loss(e: jax.Array, codebook: jax.Array, commitment: float = 0.25) -> jax.Array:
    """VQ-VAE's codebook and commitment terms for encoder outputs ``e`` [B, L]: the nearest
    code moves to the outputs it names, and the outputs (weighted ``commitment``) to their code.
    The decoder's gradient reaches ``e`` through the straight-through z, not the codes."""
    q = nearest_code(sg(e), codebook)
    return ((sg(e) - q) ** 2).sum(-1).mean() + commitment * ((e - sg(q)) ** 2).sum(-1).mean()


def bottleneck_kl(z: jax.Array) -> jax.Array:
    """KL(N(z, I) || N(0, I)) = |z|^2 / 2, batch mean: the price of the information a
    unit-variance Gaussian latent centred on ``z`` [B, L] carries. Paid together with a decoder
    that reads z + eps, it leaves z only as large as the decoder needs, and shrinks what z
    varies with but the decoder cannot use."""
    return 0.5 * (z ** 2).sum(-1).mean()


def probe_inputs(obs_dim: int, act_dim: int) -> tuple[np.ndarray, np.ndarray]:
    """The :data:`PROBES` fixed probe inputs (normalised states from N(0, I), actions from
    U(-1, 1)), from one fixed generator, so that a latent's code means the same at every update
    and in every run."""
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(PROBES, obs_dim)).astype(np.float32)
    return obs, rng.uniform(-1, 1, size=(PROBES, act_dim)).astype(np.float32)


def decoder_predictions(decoder: Decoder, params: Params, z: jax.Array, probe_obs: np.ndarray,
                        probe_act: np.ndarray) -> jax.Array:
    """What latents ``z`` [B, L] predict: D's (normalised) state change and reward at the probe
    inputs, [B, PROBES * (|S| + 1)], detached (also read by ``benchmarks/latent_probe.py`` on
    any LILI)."""
    b = z.shape[0]
    s = jnp.broadcast_to(probe_obs, (b, *probe_obs.shape))
    a = jnp.broadcast_to(probe_act, (b, *probe_act.shape))
    zb = jnp.broadcast_to(z[:, None, :], (b, PROBES, z.shape[-1]))
    return sg(decoder.apply(params, s, a, zb).reshape(b, -1))


class CategoricalCore(VariantCore):
    """z is the one-hot of E's largest output, trained by the straight-through estimator
    (forward the one-hot, backward the softmax's gradient). Measured on Drift, where a policy
    learns to influence from the partner's predicted goal given as indicators but not from
    LILI's continuous latent: worse than the continuous latent."""

    algo = "lili-categorical"
    options_cls = CategoricalOptions

    def _encode(self, enc: Params, norm: Normaliser, win: Window) -> jax.Array:
        return straight_through_one_hot(self._encoder_out(enc, norm, win))

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        loss = super()._rep_loss(model, norm, batch, z)
        if self.options.balance > 0:
            p = jax.nn.softmax(self._encoder_out(model["encoder"], norm, self._prev(batch)),
                               -1).mean(0)
            loss = loss + self.options.balance * category_imbalance(p)
        return loss


class QuantisedCore(VariantCore):
    """z is the codebook vector nearest to E's output (straight-through gradient), and J_rep
    gains the vector-quantisation losses |sg(e) - z|^2 + 0.25 |e - sg(z)|^2. Unlike the
    categorical latent nothing spreads the batch over the codes."""

    algo = "lili-quantised"
    options_cls = QuantisedOptions

    def _build(self) -> None:
        super()._build()
        cfg = self.config
        self.encoder = QuantisedEncoder(cfg.enc_hidden, cfg.latent_dim, self.options.codes)

    def _encode(self, enc: Params, norm: Normaliser, win: Window) -> jax.Array:
        out = self._encoder_out(enc, norm, win)
        return out + sg(nearest_code(out, enc["params"]["codebook"]) - out)

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        e = self._encoder_out(model["encoder"], norm, self._prev(batch))
        return (super()._rep_loss(model, norm, batch, z)
                + quantisation_loss(e, model["encoder"]["params"]["codebook"]))


class BottleneckCore(VariantCore):
    """An information bottleneck on z: the decoder reads z + eps, eps ~ N(0, I), and J_rep gains
    beta * |z|^2 / 2, the KL of N(z, I) from N(0, I) (a variational bottleneck with unit
    posterior variance, as PEARL's KL on its task latent). Actor, critic and acting use z."""

    algo = "lili-bottleneck"
    options_cls = BottleneckOptions

    def _rep_noise(self) -> bool:
        return True

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        read = z + jax.random.normal(batch["rep_key"], z.shape)
        return (decoder_loss(self.decoder, model["decoder"], norm, batch, read)
                + self.options.weight * bottleneck_kl(z))


class PosteriorCore(VariantCore):
    """A second encoder P reads tau^i itself, D predicts tau^i from P(tau^i), and E is
    regressed onto P(tau^i) (squared error, P detached), so z^i is the expected code of the
    interaction to come: every interaction that predicts the same next interaction has one
    target wherever it came from."""

    algo = "lili-posterior"
    _OPTIMISER_OF = {"posterior": "encoder"}

    def _latent_param_names(self) -> tuple[str, ...]:
        return ("encoder", "decoder", "posterior")

    def _build(self) -> None:
        super()._build()
        self.posterior = Encoder(self.config.enc_hidden, self.config.latent_dim)

    def _init_latent(self, key: jax.Array) -> dict[str, Params]:
        # A new key for P, so that E's and D's initial weights are those of LILI.
        h = self.horizon
        post = self.posterior.init(jax.random.fold_in(key, 1), jnp.zeros((1, 1, h, self.feat_dim)),
                                   jnp.ones((1, 1, h)))
        return {**super()._init_latent(key), "posterior": post}

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        own = window_part(batch["window"], slice(-1, None))  # tau^k, the batch's own
        code = self.posterior.apply(model["posterior"], self._features(norm, own), own["weight"])
        loss = ((z - sg(code)) ** 2).sum(-1).mean()
        return loss + decoder_loss(self.decoder, model["decoder"], norm, batch, code)


class PredictionCriticCore(VariantCore):
    """The critic reads what z predicts, the decoder's means D(s_p, a_p, z) at :data:`PROBES`
    fixed probe inputs (normalised states from N(0, I), actions from U(-1, 1), a fixed
    generator), detached, so the critic loss no longer shapes E (the algo does not read
    ``critic_to_encoder``: setting it is an error). The actor and acting still read z."""

    algo = "lili-prediction-critic"

    def _build(self) -> None:
        super()._build()
        self.probe_obs, self.probe_act = probe_inputs(self.obs_dim, self.act_dim)

    def _input_dims(self) -> tuple[int, int]:
        return self.x_dim - self.latent_dim + PROBES * (self.obs_dim + 1), self.x_dim

    def critic_code(self, model: Params, z: jax.Array) -> jax.Array:
        """The decoder's predictions from ``z`` (:func:`decoder_predictions`)."""
        return decoder_predictions(self.decoder, model["decoder"], z, self.probe_obs,
                                   self.probe_act)


class SetEncoderCore(VariantCore):
    """E maps the pooled transition features to z by an MLP (:class:`SetEncoder`), not
    linearly, so that z can hold what depends on several transitions of the interaction at
    once (issue 36: Flee's next slot depends on the slot and on where the ego stopped)."""

    algo = "lili-set-encoder"

    def _build(self) -> None:
        super()._build()
        self.encoder = SetEncoder(self.config.enc_hidden, self.config.latent_dim)


class FlatEncoderCore(VariantCore):
    """E is one MLP over every step of the last N interactions, each in its place
    (:class:`FlatEncoder`), so its input, and what it must learn, grows N-fold with the history;
    it reads all steps in updates too (``encoder_transitions`` is not read: a sample of steps
    has no fixed places)."""

    algo = "lili-flat-encoder"

    def _build(self) -> None:
        super()._build()
        self.encoder = FlatEncoder(self.config.enc_hidden, self.config.latent_dim)

    @property
    def window_steps(self) -> int | None:
        return None


CategoricalLILI = variant(CategoricalCore, "LILI with a one-hot latent (``lili-categorical``).")
QuantisedLILI = variant(QuantisedCore, "LILI with a vector-quantised latent (``lili-quantised``).")
BottleneckLILI = variant(BottleneckCore, "LILI with a bottlenecked latent (``lili-bottleneck``).")
PosteriorLILI = variant(PosteriorCore, "LILI with E regressed onto a posterior encoder "
                                       "(``lili-posterior``).")
PredictionCriticLILI = variant(PredictionCriticCore, "LILI whose critic reads z's predictions "
                                                     "(``lili-prediction-critic``).")
SetEncoderLILI = variant(SetEncoderCore, "LILI whose encoder has an MLP after the pooling "
                                         "(``lili-set-encoder``).")
FlatEncoderLILI = variant(FlatEncoderCore, "LILI whose encoder is one MLP over every step of its "
                                           "N interactions in place (``lili-flat-encoder``).")
