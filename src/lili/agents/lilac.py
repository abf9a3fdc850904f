"""LILAC: SAC conditioned on a latent that follows its own (exogenous) dynamics across interactions.

Lifelong Latent Actor-Critic (Xie, Harrison, Finn 2020, "Deep RL amidst Lifelong
Non-Stationarity"), the LILI paper's closest baseline. Its latent dynamics z^{i+1} ~ f(. | z^i)
are "only influenced by the environment and unaffected by the ego agent's behavior": LILAC can
track a partner's strategy but has no model of how to influence it. Its parts, sharing the SAC
core of :mod:`lili.agents.core`:

- Posterior q(z^i | tau^i) over the SAME interaction's transitions: a diagonal Gaussian from
  :class:`lili.nets.Encoder` (per-transition MLP, masked mean: permutation-invariant, any length).
- Learned prior p(z^i | z^{i-N..i-1}): a GRU over the previous interactions' posterior means
  (:class:`LatentPrior`), with a learned unconditional prior when there is no previous
  interaction.
- Decoder p(s' - s, r | s, a, z^i): :class:`lili.nets.Decoder`, unit variance in normalised units
  (as LILI's).
- Representation loss: the negative ELBO per step of interaction k of a sampled window
  k-N..k: -log p(tau^k | z^k), z^k ~ q(. | tau^k) (reparameterised), on k's batch transitions,
  plus beta KL(q(z^k | tau^k) || p(z^k | z^{k-N..k-1})) / length_k; the window's earlier
  interactions add their KL to their shorter-context priors, as gradient for the prior only
  (see :meth:`LILAC.elbo_terms`). Decoding one interaction, not all N + 1, and differentiating
  only k's posterior keep the update cost down. The KL to the learned prior is the only thing
  that trains the prior.
- Acting: z^i = mean of p(z^i | posterior means of the last N finished interactions); tau^i does
  not exist yet. The first interaction uses the unconditional prior's mean.

Choices the papers leave open, and why (options live in ``AgentConfig.extra["lilac"]``, see
:class:`LILACOptions`):

- ``critic_latent="prior"`` (default): actor and critic see the latent the agent acts with, the
  prior's prediction for interaction k, detached. This is the RL term of LILAC's bound (z^i from
  the prior given the past posteriors) and removes the train/act mismatch of training on the
  hindsight posterior q(z^k | tau^k), which sees the very interaction it is used in. Detaching
  also keeps the latent dynamics exogenous: a critic gradient through the prior would teach the
  posteriors of past interactions to carry whatever predicts the next interaction's reward,
  the ego's own behaviour included - the influence channel LILAC does not have - and would move
  the prior by something other than the KL. ``"posterior"`` is the reading of a public
  re-implementation (PEARL-style): the critic and actor train on the posterior mean of tau^k
  and the critic's gradient reaches the posterior (scaled by ``critic_to_encoder``); offered
  for comparison.
- The prior reads the posterior means detached (the KL trains the prior and the q side, not the
  context), for the same reason: otherwise the KL would teach q(z^{k-1} | tau^{k-1}) to encode
  what predicts z^k, ego behaviour included. Means rather than samples make acting
  deterministic given the history.
- ``prior_window`` = N = 2 previous interactions (LILAC's LSTM reads the whole history; a finite
  window is what the fused sampler provides). One previous latent is the LILI paper's
  first-order chain z^{i+1} ~ f(. | z^i); on Point Mass it can only learn one fixed rotation of
  the target, while two give the direction of the most recent step, so an exogenous prior can
  follow a reversal (caused by the ego, which it cannot see) one interaction late. Each
  further interaction costs about 3.5 ms per update
  (Point Mass, default sizes: 17 ms per update at N = 2, 24 ms at N = 4, LILI 11 ms). The
  sampler's window is k-N..k, so the prior for k reads k-N..k-1, and each earlier position j
  gives the prior a KL with the context it has (0..N-1 previous interactions): what acting in
  the first N interactions of a sequence needs. LILAC does not read ``AgentConfig.history``
  (LILI's encoder window; setting it is an error); its window is this option, and
  ``warmup_interactions`` must exceed it.
- Boundary: bootstrap across the interaction boundary (the stream goes on), from the first
  observation of k+1 with the latent LILAC will act with there: the prior's prediction from the
  (target) posteriors of k-N+1..k. In :mod:`lili.agents.core`'s terms that is the ``influence``
  mode (the next interaction's latent), but for LILAC it is no influence path: the posterior
  explains tau^k's dynamics and rewards, which the partner's strategy, not the ego, determines,
  and the prior only sees posteriors. Latents inside the critic target come from the
  Polyak-averaged copy of posterior and prior (``target_encoder``).
- ``kl_weight`` = beta = 1 (the ELBO; the notes' assumption). The prior and the posterior share
  the encoder's learning rate (``lr_encoder``); the GRU has ``enc_hidden[-1]`` units.
"""

from __future__ import annotations

from dataclasses import dataclass

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

from lili.agents.base import ActingState, AgentState, Normaliser, Params
from lili.agents.core import SACCore, sg
from lili.agents.latent import decoder_loss
from lili.agents.registry import register
from lili.agents.sac import SAC
from lili.buffer import Batch, InteractionBuffer, Window
from lili.config import AgentConfig, dataclass_options
from lili.dists import gaussian_kl, soft_clip_log_std
from lili.nets import Decoder, Encoder

__all__ = ["LILAC", "LILACCore", "LatentPrior", "LILACOptions"]

CRITIC_LATENTS = ("prior", "posterior")


@dataclass(frozen=True)
class LILACOptions:
    """LILAC's options, set as ``AgentConfig(extra={"lilac": {...}})`` (the module docstring
    says why each default): ``prior_window`` (N = 2 previous interactions), ``kl_weight``
    (beta = 1) and ``critic_latent`` (``prior`` or ``posterior``)."""

    prior_window: int = 2
    kl_weight: float = 1.0
    critic_latent: str = "prior"

    def __post_init__(self) -> None:
        n = self.prior_window
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"config extra.lilac.prior_window={n!r} is invalid; allowed: an "
                             "integer >= 1")
        beta = self.kl_weight
        if isinstance(beta, bool) or not isinstance(beta, (int, float)) or beta < 0:
            raise ValueError(f"config extra.lilac.kl_weight={beta!r} is invalid; allowed: a "
                             "number >= 0")
        if self.critic_latent not in CRITIC_LATENTS:
            raise ValueError(f"config extra.lilac.critic_latent={self.critic_latent!r} is "
                             f"invalid; allowed: {', '.join(CRITIC_LATENTS)}")
        object.__setattr__(self, "prior_window", int(n))
        object.__setattr__(self, "kl_weight", float(beta))

    def check(self, config: AgentConfig) -> None:
        """ValueError unless ``config``'s warm-up and buffer hold the prior's window."""
        n = self.prior_window
        if config.warmup_interactions <= n:
            raise ValueError(
                f"config warmup_interactions={config.warmup_interactions} is invalid for LILAC "
                f"with prior_window={n}; allowed: an integer >= {n + 1} (the first update needs "
                "prior_window earlier interactions)")
        if config.buffer_capacity <= n:
            raise ValueError(
                f"config buffer_capacity={config.buffer_capacity} is invalid for LILAC with "
                f"prior_window={n}; allowed: an integer >= {n + 1}")


class LatentPrior(nn.Module):
    """p(z^j | z^{<j}): a GRU over a sequence of latents, a Gaussian head on each of its states.

    Input ``z``: [..., W, L] latents in order, ``present``: [..., W] (False = missing interaction:
    the GRU state passes it unchanged). Returns (mean, log_std), each [..., W + 1, L]: entry j is
    the prior for position j given positions 0..j-1 (entry 0 is the unconditional prior, entry W
    the prediction after the whole sequence).
    """

    hidden: int
    latent_dim: int

    @nn.compact
    def __call__(self, z: jax.Array, present: jax.Array) -> tuple[jax.Array, jax.Array]:
        cell = nn.GRUCell(features=self.hidden)
        head = nn.Dense(2 * self.latent_dim)
        h = jnp.zeros((*z.shape[:-2], self.hidden), z.dtype)
        states = [h]
        # The window is a handful of interactions, so an unrolled loop is cheaper than a scan.
        for j in range(z.shape[-2]):
            h_new, _ = cell(h, z[..., j, :])
            h = jnp.where(present[..., j, None], h_new, h)
            states.append(h)
        mean, log_std = jnp.split(head(jnp.stack(states, -2)), 2, axis=-1)
        return mean, soft_clip_log_std(log_std)


class LILACCore(SACCore):
    """LILAC's maths (see the module docstring)."""

    uses_latent = True
    default_boundary = "influence"

    def __init__(self, obs_dim: int, act_dim: int, horizon: int, config: AgentConfig,
                 boundary: str | None = None) -> None:
        self.options: LILACOptions = dataclass_options(config, "lilac", LILACOptions)
        self.options.check(config)
        super().__init__(obs_dim, act_dim, horizon, config, boundary)

    # -- construction --------------------------------------------------------------------------
    def _latent_param_names(self) -> tuple[str, ...]:
        # Posterior and prior live together under "encoder": they share its optimiser and its
        # Polyak-averaged target copy.
        return ("encoder", "decoder")

    def _build(self) -> None:
        # SAC sets history from config.history (LILI's encoder window); LILAC's window is the
        # prior's, and everything downstream (sampler, acting, evaluate) reads self.history.
        self.history = self.options.prior_window
        super()._build()
        cfg = self.config
        self.posterior = Encoder(cfg.enc_hidden, 2 * cfg.latent_dim)
        self.prior = LatentPrior(cfg.enc_hidden[-1], cfg.latent_dim)
        self.decoder = Decoder(cfg.enc_hidden, self.obs_dim + 1)
        self.feat_dim = 2 * self.obs_dim + self.act_dim + 2

    def _init_latent(self, key: jax.Array) -> dict[str, Params]:
        kq, kp, kd = jax.random.split(key, 3)
        L = self.latent_dim
        post = self.posterior.init(kq, jnp.zeros((1, 1, 1, self.feat_dim)), jnp.ones((1, 1, 1)))
        prior = self.prior.init(kp, jnp.zeros((1, 1, L)), jnp.ones((1, 1), bool))
        dec = self.decoder.init(kd, jnp.zeros((1, self.obs_dim)), jnp.zeros((1, self.act_dim)),
                                jnp.zeros((1, L)))
        return {"encoder": {"posterior": post, "prior": prior}, "decoder": dec}

    # -- the latent model ------------------------------------------------------------------------
    def _features(self, norm: Normaliser, win: Window) -> jax.Array:
        """Per-transition posterior input (s, a, r, s' - s, t/H), normalised."""
        obs = win["obs"]
        phase = win["t"].astype(jnp.float32) / self.horizon
        return jnp.concatenate([norm.obs(obs), win["act"], norm.rew(win["rew"])[..., None],
                                norm.delta(obs, win["next_obs"]), phase[..., None]], -1)

    def posterior_params(self, enc: Params, norm: Normaliser,
                         win: Window) -> tuple[jax.Array, jax.Array]:
        """q(z^j | tau^j) for each interaction of a window ([..., W, S, ...] fields): (mean,
        log_std), each [..., W, L]."""
        x = self._features(norm, win)[..., None, :, :]
        out = self.posterior.apply(enc["posterior"], x, win["weight"][..., None, :])
        mean, log_std = jnp.split(out, 2, axis=-1)
        return mean, soft_clip_log_std(log_std)

    def prior_params(self, enc: Params, post_mean: jax.Array,
                     present: jax.Array) -> tuple[jax.Array, jax.Array]:
        """p(z^j | z^{<j}) from posterior means [..., W, L] (read detached): [..., W + 1, L]."""
        return self.prior.apply(enc["prior"], sg(post_mean), present)

    def _model(self, enc: Params, norm: Normaliser, win: Window):
        """Posteriors and priors over a sampled window k-N..k.

        The context k-N..k-1 and interaction k are encoded in separate calls: the context's
        posteriors only ever enter detached, so only k's call is differentiated (backpropagating
        through the whole window cost 4.4 ms more per update on Point Mass at N = 4). Returns the
        posterior (mean, log_std) [B, N + 1, L], the prior (mean, log_std) [B, N + 2, L] and
        which interactions are present [B, N + 1].
        """
        n = self.history
        ctx_mean, ctx_log_std = self.posterior_params(enc, norm, {k: v[:, :n]
                                                                  for k, v in win.items()})
        cur_mean, cur_log_std = self.posterior_params(enc, norm, {k: v[:, n:]
                                                                  for k, v in win.items()})
        q_mean = jnp.concatenate([sg(ctx_mean), cur_mean], 1)
        q_log_std = jnp.concatenate([sg(ctx_log_std), cur_log_std], 1)
        present = win["weight"].sum(-1) > 0
        p_mean, p_log_std = self.prior_params(enc, q_mean, present)
        return q_mean, q_log_std, p_mean, p_log_std, present

    def elbo_terms(self, model: Params, norm: Normaliser, batch: Batch,
                   key: jax.Array) -> dict[str, jax.Array]:
        """The representation loss on a sampled batch (window k-N..k) and its parts.

        ``loss`` = the negative ELBO per step of interaction k: reconstruction NLL of its batch
        transitions under z^k ~ q(. | tau^k), plus kl_weight * KL(q(z^k | tau^k) ||
        p(z^k | z^{k-N..k-1})) / length_k. ``recon``, ``kl`` (nats per interaction) and
        ``kl_context`` (the window's earlier interactions' KL to their shorter-context priors,
        mean) are its parts.

        The earlier interactions' KLs train the prior only (their posteriors are detached), so
        that it also predicts from 0..N-1 previous interactions, as at the start of a sequence.
        They enter the loss as x - sg(x): their gradient, none of their value, so ``loss``
        stays interaction k's ELBO. The posterior is regularised towards the prior LILAC acts
        with; over the uniformly drawn k every interaction takes that place.
        """
        win, n = batch["window"], self.history
        q_mean, q_log_std, p_mean, p_log_std, _ = self._model(model["encoder"], norm, win)
        z = q_mean[:, n] + jnp.exp(q_log_std[:, n]) * jax.random.normal(key, q_mean[:, n].shape)
        recon = decoder_loss(self.decoder, model["decoder"], norm, batch, z)
        # The prior's last entry predicts k+1, which has no posterior in this window.
        kl = gaussian_kl(q_mean, q_log_std, p_mean[:, :-1], p_log_std[:, :-1])
        # The last sampled step is the interaction's last, so max t + 1 is its length.
        per_step = kl / ((win["t"] * win["valid"]).max(-1) + 1.0)
        context = per_step[:, :n].sum(-1)
        beta = self.options.kl_weight
        loss = recon + beta * (per_step[:, n] + context - sg(context)).mean()
        return {"loss": loss, "recon": recon, "kl": kl[:, n].mean(),
                "kl_context": kl[:, :n].mean()}

    # -- SAC hooks --------------------------------------------------------------------------------
    def _rep_noise(self) -> bool:
        return True  # the ELBO samples z ~ q

    def _latents(self, model: Params, target: Params, norm: Normaliser, batch: Batch):
        n = self.history
        enc_t = target["encoder"] if self.config.target_encoder else sg(model["encoder"])
        q_mean, _, p_mean, _, present = self._model(model["encoder"], norm, batch["window"])
        tq_mean, _, tp_mean, _, _ = self._model(enc_t, norm, batch["window"])
        # The acting latent of k+1 reads k-N+1..k: drop the window's oldest interaction.
        tp_next, _ = self.prior_params(enc_t, tq_mean, present.at[..., 0].set(False))
        if self.options.critic_latent == "posterior":
            return q_mean[:, n], tq_mean[:, n], tp_next[:, n + 1]
        return sg(p_mean[:, n]), tp_mean[:, n], tp_next[:, n + 1]

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        return self.elbo_terms(model, norm, batch, batch["rep_key"])["loss"]

    def _act_latent(self, model: Params, norm: Normaliser, window: Window) -> jax.Array:
        enc = model["encoder"]
        batched = {k: v[None] for k, v in window.items()}
        q_mean, _ = self.posterior_params(enc, norm, batched)
        p_mean, _ = self.prior_params(enc, q_mean, batched["weight"].sum(-1) > 0)
        return p_mean[0, -1]

    def initial_acting(self, state: AgentState) -> ActingState:
        """The acting state at the first interaction: the unconditional prior's mean."""
        empty = InteractionBuffer(max(2, self.history), self.horizon, self.obs_dim,
                                  self.act_dim).window(-1, self.history, self.window_steps)
        return ActingState(self.jit_latent(state.model, state.norm, empty),
                           jnp.zeros((), jnp.int32))


class LILAC(SAC):
    """Lifelong Latent Actor-Critic, the LILI paper's baseline (see the module docstring).

    ``LILAC(env, AgentConfig(extra={"lilac": {"prior_window": 2, "kl_weight": 1.0,
    "critic_latent": "prior"}}))`` spells out the defaults.
    """

    algo = "lilac"
    core_cls = LILACCore


register("lilac", LILAC, options=LILACOptions)
