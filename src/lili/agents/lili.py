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
``AgentConfig.target_encoder``). Variants that measured no gain subclass :class:`LILICore` in
:mod:`lili.contrib`.
"""

from __future__ import annotations

import gymnasium as gym
import jax
import jax.numpy as jnp

from lili.agents.base import Normaliser, Params
from lili.agents.core import SACCore, sg
from lili.agents.latent import decoder_loss, window_part
from lili.agents.registry import register
from lili.agents.sac import SAC
from lili.buffer import Batch, Window
from lili.config import AgentConfig
from lili.nets import Decoder, Encoder

__all__ = ["LILI", "LILICore", "decoder_loss", "window_part"]


class LILICore(SACCore):
    """LILI's maths (module docstring); ``boundary`` "influence" (LILI) or "cut" (no influence)."""

    uses_latent = True
    default_boundary = "influence"

    def _latent_param_names(self) -> tuple[str, ...]:
        return ("encoder", "decoder")

    def _build(self) -> None:
        super()._build()
        cfg = self.config
        self.encoder = Encoder(cfg.enc_hidden, cfg.latent_dim)
        self.decoder = Decoder(cfg.enc_hidden, self.obs_dim + 1)
        self.feat_dim = 3 * self.obs_dim + self.act_dim + 3

    def _init_latent(self, key: jax.Array) -> dict[str, Params]:
        ke, kd = jax.random.split(key)
        n, h = self.history, self.horizon
        enc = self.encoder.init(ke, jnp.zeros((1, n, h, self.feat_dim)), jnp.ones((1, n, h)))
        dec = self.decoder.init(kd, jnp.zeros((1, self.obs_dim)), jnp.zeros((1, self.act_dim)),
                                jnp.zeros((1, self.latent_dim)))
        return {"encoder": enc, "decoder": dec}

    def _features(self, norm: Normaliser, win: Window) -> jax.Array:
        """Per-transition encoder input from window fields shaped [..., steps, ...]."""
        obs, nxt = win["obs"], win["next_obs"]
        phase = win["t"].astype(jnp.float32) / self.horizon
        last = win["last"].astype(jnp.float32)
        return jnp.concatenate(
            [norm.obs(obs), win["act"], norm.rew(win["rew"])[..., None], norm.delta(obs, nxt),
             norm.obs(nxt), phase[..., None], last[..., None]], -1)

    def _encoder_out(self, enc: Params, norm: Normaliser, win: Window) -> jax.Array:
        """E's linear output (z itself; a variant may map it to z, see :meth:`_encode`)."""
        return self.encoder.apply(enc, self._features(norm, win), win["weight"])

    def _encode(self, enc: Params, norm: Normaliser, win: Window) -> jax.Array:
        return self._encoder_out(enc, norm, win)

    def _latents(self, model: Params, target: Params, norm: Normaliser, batch: Batch):
        win = batch["window"]
        prev, nxt = window_part(win, slice(None, -1)), window_part(win, slice(1, None))
        z = self._encode(model["encoder"], norm, prev)
        enc_t = target["encoder"] if self.config.target_encoder else sg(model["encoder"])
        return z, self._encode(enc_t, norm, prev), self._encode(enc_t, norm, nxt)

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        return decoder_loss(self.decoder, model["decoder"], norm, batch, z)

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
        if not influence:
            self.algo = "lili-no-influence"
        super().__init__(env, config, seed)

    def _make_core(self) -> SACCore:
        return self.core_cls(self.obs_dim, self.act_dim, self.horizon, self.config,
                             boundary="influence" if self.influence else "cut")


register("lili", LILI)
register("lili-no-influence", LILI, influence=False)
