"""LILI: SAC conditioned on a latent strategy z^i = E(tau^{i-1}) learnt by predicting tau^i.

Exactly the semantics of DESIGN.md "LILI semantics":

- Encoder E (2x128, latent 8): the transitions (s, a, r, s') of the last N interactions -> z,
  deterministic and permutation-invariant within an interaction (per-transition MLP, masked
  mean). Each transition also carries its phase t/H and a last-step flag, so that E can single
  out how the interaction ended (that is what the partner reacts to) without losing
  permutation invariance.
- Decoder D (2x128): (s_t, a_t, z^i) -> Gaussian (unit variance in normalised units) over
  (s_{t+1} - s_t, r_t); J_rep is its log-likelihood on tau^i's transitions under
  z^i = E(tau^{i-1}).
- Actor pi(a | s, z) and twin critic Q(s, a, z): the encoder learns from J_rep and from the
  critic loss; the actor sees z detached.
- Acting: z^1 = 0; after interaction i ends, z^{i+1} = E(tau^i) is held for all of i+1.
- Critic target at the last step of interaction i: LILI (influence) bootstraps from the first
  observation of i+1 with z^{i+1} = E(tau^i); LILI (no influence) uses y = r.

Latents inside the critic target come from a Polyak-averaged copy of the encoder (see
``AgentConfig.target_encoder``). With ``AgentConfig.latent_kind="categorical"`` z is the
one-hot of E's largest output (a departure from the paper's continuous z, off by default);
with ``AgentConfig.latent_bottleneck`` > 0 the decoder reads a noisy z and J_rep pays for z's
size (an information bottleneck, also off by default). With
``AgentConfig.critic_latent="prediction"`` the critic reads what z predicts (the decoder at
fixed probe inputs) instead of z (off by default).
"""

from __future__ import annotations

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np

from lili.agents.base import Normaliser, Params
from lili.agents.sac import SAC, SACCore, register, sg
from lili.buffer import Batch, Window
from lili.config import AgentConfig
from lili.dists import unit_gaussian_nll
from lili.nets import Decoder, Encoder, QuantisedEncoder, nearest_code, straight_through_one_hot

__all__ = ["LILI", "LILICore", "decoder_loss", "category_imbalance", "bottleneck_kl",
           "quantisation_loss", "window_part", "PROBES"]

PROBES = 16
"""Probe inputs at which ``critic_latent="prediction"`` reads the decoder."""


def decoder_loss(decoder: Decoder, params: Params, norm: Normaliser, batch: Batch,
                 z: jax.Array) -> jax.Array:
    """J_rep's reconstruction term: the unit-variance Gaussian NLL of tau^k's normalised
    (s' - s, r) under D(s, a, z^k), with ``z`` [B, L] held for each interaction's transitions.
    Shared by LILI and LILAC."""
    s = norm.obs(batch["obs"])
    target = jnp.concatenate([norm.delta(batch["obs"], batch["next_obs"]),
                              norm.rew(batch["rew"])[..., None]], -1)
    zb = jnp.broadcast_to(z[:, None, :], (*s.shape[:-1], z.shape[-1]))
    return unit_gaussian_nll(decoder.apply(params, s, batch["act"], zb), target)


def category_imbalance(p: jax.Array) -> jax.Array:
    """log K - H(p) >= 0 for the batch's mean category probabilities ``p`` [K]: zero when the
    batch uses all K categories equally. A one-hot latent whose encoder starts with one
    largest output for nearly every input never trains the decoder on the other categories
    and stays collapsed (measured on Drift: 499 of 500 interactions in one category); this
    term spreads the batch over the categories so the decoder can tell them apart."""
    k = p.shape[-1]
    return jnp.log(k) + (p * jnp.log(jnp.maximum(p, 1e-12))).sum(-1)


def window_part(window: Window, part: slice) -> Window:
    """The interactions ``part`` of a batch's windows ([B, N + 1, ...] -> [B, len, ...]): the
    window holds k-N..k, so ``slice(None, -1)`` is E's input for z^k, ``slice(1, None)`` for
    z^{k+1}, and ``slice(-1, None)`` interaction k itself."""
    return {k: v[:, part] for k, v in window.items()}


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
    varies with but the decoder cannot use (``AgentConfig.latent_bottleneck``)."""
    return 0.5 * (z ** 2).sum(-1).mean()


class LILICore(SACCore):
    """LILI's maths (module docstring); ``boundary`` "influence" (LILI) or "cut" (no influence)."""

    uses_latent = True
    default_boundary = "influence"

    def _latent_param_names(self) -> tuple[str, ...]:
        if self.config.latent_target == "posterior":
            return ("encoder", "decoder", "posterior")
        return ("encoder", "decoder")

    def _build(self) -> None:
        super()._build()
        cfg = self.config
        self.encoder = Encoder(cfg.enc_hidden, cfg.latent_dim)
        if cfg.latent_kind == "quantised":
            self.encoder = QuantisedEncoder(cfg.enc_hidden, cfg.latent_dim, cfg.latent_codes)
        self.decoder = Decoder(cfg.enc_hidden, self.obs_dim + 1)
        self.posterior = Encoder(cfg.enc_hidden, cfg.latent_dim)
        self.feat_dim = 3 * self.obs_dim + self.act_dim + 3
        self.critic_reads_code = cfg.critic_latent == "prediction"
        # Fixed, so that a latent's code means the same at every update and in every run.
        rng = np.random.default_rng(0)
        self.probe_obs = rng.normal(size=(PROBES, self.obs_dim)).astype(np.float32)
        self.probe_act = rng.uniform(-1, 1, size=(PROBES, self.act_dim)).astype(np.float32)

    def _input_dims(self) -> tuple[int, int]:
        if not self.critic_reads_code:
            return super()._input_dims()
        code = PROBES * (self.obs_dim + 1)
        return self.x_dim - self.latent_dim + code, self.x_dim

    def _critic_latent(self, model: Params, z: jax.Array) -> jax.Array:
        return self.predictions(model, z)

    def predictions(self, model: Params, z: jax.Array) -> jax.Array:
        """What latents ``z`` [B, L] predict: D's (normalised) state change and reward at the
        fixed probe inputs, [B, PROBES * (|S| + 1)], detached. The critic's code of z with
        ``critic_latent="prediction"``."""
        b = z.shape[0]
        s = jnp.broadcast_to(self.probe_obs, (b, *self.probe_obs.shape))
        a = jnp.broadcast_to(self.probe_act, (b, *self.probe_act.shape))
        zb = jnp.broadcast_to(z[:, None, :], (b, PROBES, z.shape[-1]))
        return sg(self.decoder.apply(model["decoder"], s, a, zb).reshape(b, -1))

    def _init_latent(self, key: jax.Array) -> dict[str, Params]:
        ke, kd = jax.random.split(key)
        n, h = self.history, self.horizon
        enc = self.encoder.init(ke, jnp.zeros((1, n, h, self.feat_dim)), jnp.ones((1, n, h)))
        dec = self.decoder.init(kd, jnp.zeros((1, self.obs_dim)), jnp.zeros((1, self.act_dim)),
                                jnp.zeros((1, self.latent_dim)))
        if self.config.latent_target == "decoder":
            return {"encoder": enc, "decoder": dec}
        # A new key for P, so that E's and D's initial weights are those of the default.
        post = self.posterior.init(jax.random.fold_in(key, 1), jnp.zeros((1, 1, h, self.feat_dim)),
                                   jnp.ones((1, 1, h)))
        return {"encoder": enc, "decoder": dec, "posterior": post}

    def _features(self, norm: Normaliser, win: Window) -> jax.Array:
        """Per-transition encoder input from window fields shaped [..., steps, ...]."""
        obs, nxt = win["obs"], win["next_obs"]
        phase = win["t"].astype(jnp.float32) / self.horizon
        last = win["last"].astype(jnp.float32)
        return jnp.concatenate(
            [norm.obs(obs), win["act"], norm.rew(win["rew"])[..., None], norm.delta(obs, nxt),
             norm.obs(nxt), phase[..., None], last[..., None]], -1)

    def _encoder_out(self, enc: Params, norm: Normaliser, win: Window) -> jax.Array:
        """E's linear output: z itself, or with a categorical latent its logits."""
        return self.encoder.apply(enc, self._features(norm, win), win["weight"])

    def _encode(self, enc: Params, norm: Normaliser, win: Window) -> jax.Array:
        out = self._encoder_out(enc, norm, win)
        if self.config.latent_kind == "categorical":
            return straight_through_one_hot(out)
        if self.config.latent_kind == "quantised":
            return out + sg(nearest_code(out, enc["params"]["codebook"]) - out)
        return out

    def _latents(self, model: Params, target: Params, norm: Normaliser, batch: Batch):
        win = batch["window"]
        prev, nxt = window_part(win, slice(None, -1)), window_part(win, slice(1, None))
        z = self._encode(model["encoder"], norm, prev)
        enc_t = target["encoder"] if self.config.target_encoder else sg(model["encoder"])
        return z, self._encode(enc_t, norm, prev), self._encode(enc_t, norm, nxt)

    def _rep_noise(self) -> bool:
        # Only the bottleneck draws noise, so every run without it keeps its key stream.
        return self.config.latent_bottleneck > 0

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        beta = self.config.latent_bottleneck
        code, loss = z, jnp.zeros(())
        if self.config.latent_target == "posterior":
            own = window_part(batch["window"], slice(-1, None))  # tau^k, the batch's own
            code = self.posterior.apply(model["posterior"], self._features(norm, own),
                                        own["weight"])
            loss = ((z - sg(code)) ** 2).sum(-1).mean()
        read = code + jax.random.normal(batch["rep_key"], code.shape) if beta > 0 else code
        loss = loss + decoder_loss(self.decoder, model["decoder"], norm, batch, read)
        if beta > 0:
            loss = loss + beta * bottleneck_kl(code)
        if self.config.latent_kind == "categorical" and self.config.latent_balance > 0:
            prev = window_part(batch["window"], slice(None, -1))
            p = jax.nn.softmax(self._encoder_out(model["encoder"], norm, prev), -1).mean(0)
            loss = loss + self.config.latent_balance * category_imbalance(p)
        if self.config.latent_kind == "quantised":
            e = self._encoder_out(model["encoder"], norm, window_part(batch["window"],
                                                                      slice(None, -1)))
            loss = loss + quantisation_loss(e, model["encoder"]["params"]["codebook"])
        return loss

    def _act_latent(self, model: Params, norm: Normaliser, window: Window) -> jax.Array:
        batched = {k: v[None] for k, v in window.items()}
        return self._encode(model["encoder"], norm, batched)[0]


class LILI(SAC):
    """Learning and Influencing Latent Intent (Xie et al., CoRL 2020).

    ``LILI(env)`` optimises reward across interactions (it learns to influence the partner);
    ``LILI(env, influence=False)`` is the paper's greedy "LILI (no influence)".
    """

    algo = "lili"
    core_cls = LILICore

    def __init__(self, env: gym.Env | str, config: AgentConfig | dict | None = None,
                 seed: int = 0, influence: bool = True) -> None:
        if not isinstance(influence, bool):
            raise ValueError(f"influence={influence!r} is invalid; allowed: True or False")
        self.influence = influence
        self.algo = "lili" if influence else "lili-no-influence"
        super().__init__(env, config, seed)

    def _make_core(self) -> SACCore:
        return LILICore(self.obs_dim, self.act_dim, self.horizon, self.config,
                        boundary="influence" if self.influence else "cut")


register("lili", LILI)
register("lili-no-influence", LILI, influence=False)
