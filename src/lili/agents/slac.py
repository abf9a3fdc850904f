# Over 400 lines: SLAC is one method (its latent model, sequence sampling and core), kept whole.
"""SLAC: Stochastic Latent Actor-Critic (Lee, Nagabandi, Abbeel, Levine; NeurIPS 2020).

The LILI paper's POMDP baseline: a sequential latent variable model learns a belief over the
hidden state *within* an interaction; the critic reads samples of that belief, the actor reads
the raw recent history. Each interaction is one episode, so SLAC never sees an earlier
interaction (which is why it cannot model the partner's strategy dynamics). Adapted to state
observations, as in ``shared/notes/slac.md``:

Latent model (every conditional a diagonal Gaussian from a 2-hidden-layer leaky-ReLU MLP, std =
softplus + 1e-5, as in the official code):

- z_t = (z1_t, z2_t); p(z1_0) = N(0, I); p(z2_0 | z1_0); p(z1_{t+1} | z2_t, a_t);
  p(z2_{t+1} | z1_{t+1}, z2_t, a_t).
- Posterior q(z1_0 | x_0), q(z1_{t+1} | x_{t+1}, z2_t, a_t); the z2 posteriors *are* the z2
  priors (shared networks), so only z1 carries a KL.
- x_t enters through a compressor (the official image encoder becomes an MLP: a hidden layer and
  a feature layer, both leaky-ReLU); the decoder p(x_t | z_t) is an MLP Gaussian with fixed std;
  the reward model p(r_t | z_t, a_t, z_{t+1}) is Gaussian with learned std.
- Loss: the negative ELBO, sum over a sequence of ``sequence_length`` + 1 frames of
  [-log p(x_t | z_t) - log p(r_t | ...) + KL(q(z1_t) || p(z1_t))] (analytic KL; t = 0 against
  N(0, I)), mean over the batch. Its own Adam optimiser; it is the ``rep_loss`` metric.

Reinforcement learning, on the SAC core of :mod:`lili.agents.core` (its actor, twin critic,
actor, temperature and critic-target formula), through the core's input hooks:

- Critic Q(z_t, a_t) on a posterior sample, detached (the RL losses never train the model), from
  a filter run over the sequence that ends at t + 1; the target uses the same sample path at
  t + 1. Sequences never cross an interaction boundary: a filter starts at max(0, t - K + 1)
  (K = ``sequence_length``) with the first-step distributions, exactly what the official code
  does at an episode's first step.
- Actor pi(a_t | x_{t-K+1..t}, a_{t-K+1..t-1}): the last K observations and the K - 1 actions
  between them, flattened, zero before the interaction's start (``actor_input``).
- At the last step of an interaction the target bootstraps (the stream of interactions goes on,
  as for SAC) from the next interaction's first step: the latent q(z1_0 | x^{i+1}_0),
  p(z2_0 | z1_0) and the actor history that holds only x^{i+1}_0. ``boundary="cut"`` (y = r) is
  the alternative; the latent-switching modes of LILI do not apply.

Sampling (:func:`sample_sequences`) is pure JAX and runs inside the fused ``lax.scan`` block,
like :func:`lili.buffer.sample`; the critic's latent samples are computed once per update there.

Defaults (options in ``AgentConfig.extra["slac"]``, see :class:`SLACOptions`) are the official
ones where this setting affords them: z1 32, K = 8, model Adam 1e-4, model batch 32 sequences,
decoder std sqrt(0.1), one model step per update. Shared with every agent of the library
(``AgentConfig``): actor / critic / temperature Adam 3e-4, RL batch 32 interactions x 8 steps =
256 (official: 256), target entropy -|A|, gamma 0.99, tau 5e-3, 2x256 actor and critic, and two
library-wide choices the official code does not make: an initial temperature of 0.1
(``init_alpha``; official 1.0) and the phase t/H (``phase_feature``) appended to every frame and
to the critic's latent, so that SLAC is compared with SAC and LILI on the same inputs.
Observations and rewards are standardised with the warm-up statistics (``normalize``), which is
what makes a fixed decoder std meaningful for state vectors. Changes of scale, with reasons:

- Model size: z2 64, feature 64, hidden 2 x 128 (official 256, 256, 2 x 256, sized for 64x64
  images). Measured CPU time per update on Point Mass (batch 256, one model step each,
  ``XLA_FLAGS=--xla_cpu_multi_thread_eigen=false``, 2-core machine): official sizes 78 ms, these
  26 ms (SAC 6.9, LILI 10.9). A Point Mass run is 100,000 updates: 2.2 h against 44 min. The
  cost is the critic's latents (a 9-frame filter for each of the 256 sequences, every update)
  and the model step, both growing with these widths; low-dimensional states need no more.
  The official sizes are ``{"z2_dim": 256, "feature_dim": 256, "model_hidden": [256, 256]}``.
  Not every task is indifferent to them: on Lunar Lander these sizes leave the lander hovering
  to the horizon more often than the official ones do, and ten times the pretraining does not
  make up for it (docs/journal, s40: "Lunar Lander SLAC at the official model sizes"; s42:
  three seeds of that control, and the official 100,000 steps at the official sizes).
- ``pretrain_steps`` = 1000 model-only steps after the warm-up (official: 100,000 after 10,000
  random steps, also sized for images). On the 20 warm-up interactions of Point Mass (Driving
  2D) the loss falls from 291 (405) to 15 (3.5) in 1000 steps, 97% (95%) of its fall over 3000
  steps; each step costs ~14 ms, and model steps go on with every update after that.
- ``model_every`` (official 1): one model step per ``model_every`` updates, a further knob when
  the model's cost matters (official sizes with 4: 57 ms per update).
- The reward likelihood at the last step of an interaction is kept (toshikwa masks it because
  its next frame is a reset; here the stored next observation is the true final one).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any, ClassVar

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax

from lili.agents.base import ActingState, AgentState, Normaliser, Params
from lili.agents.core import SACCore, core_jit, sg
from lili.agents.registry import register
from lili.agents.sac import SAC
from lili.buffer import InteractionBuffer, sample
from lili.config import AgentConfig, dataclass_options
from lili.dists import gaussian_kl, gaussian_logp, tanh_gaussian

__all__ = ["SLAC", "SLACCore", "LatentModel", "SLACOptions", "sample_sequences",
           "gather_sequences", "actor_input"]

@dataclass(frozen=True)
class SLACOptions:
    """SLAC's options, set as ``AgentConfig(extra={"slac": {...}})``; each checked on
    construction (ValueError naming ``extra.slac.<option>``, the value and what is allowed).

    - ``z1_dim``, ``z2_dim``: latent sizes (official 32 / 256; z2 here 64, see the module
      docstring).
    - ``feature_dim``: compressor output (official 8 * base_depth = 256; here 64).
    - ``model_hidden``: hidden widths of every model MLP (official 2 x 256; here 2 x 128).
    - ``sequence_length``: K, the actor's history and the filter length (official 8).
    - ``model_batch``: sequences per model step (official 32).
    - ``lr_model``: the model's Adam learning rate (official 1e-4).
    - ``decoder_std``: the fixed std of p(x | z) in standardised units (official sqrt(0.1)).
    - ``pretrain_steps``: model-only steps before the first RL update (official 100,000; see the
      module docstring).
    - ``model_every``: one model step every this many updates (official 1).
    """

    z1_dim: int = 32
    z2_dim: int = 64
    feature_dim: int = 64
    model_hidden: tuple[int, ...] = (128, 128)
    sequence_length: int = 8
    model_batch: int = 32
    lr_model: float = 1e-4
    decoder_std: float = math.sqrt(0.1)
    pretrain_steps: int = 1000
    model_every: int = 1

    def __post_init__(self) -> None:
        def bad(name: str, allowed: str) -> ValueError:
            return ValueError(f"config extra.slac.{name}={getattr(self, name)!r} is invalid; "
                              f"allowed: {allowed}")

        for name, low in (("z1_dim", 1), ("z2_dim", 1), ("feature_dim", 1),
                          ("sequence_length", 1), ("model_batch", 1), ("pretrain_steps", 0),
                          ("model_every", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise bad(name, f"an integer >= {low}")
            object.__setattr__(self, name, int(v))
        for name in ("lr_model", "decoder_std"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
                raise bad(name, "a number > 0")
            object.__setattr__(self, name, float(v))
        hidden = self.model_hidden
        if not isinstance(hidden, (list, tuple)) or not hidden or not all(
            isinstance(h, (int, np.integer)) and not isinstance(h, bool) and h > 0 for h in hidden
        ):
            raise bad("model_hidden", "a non-empty list of positive integers")
        object.__setattr__(self, "model_hidden", tuple(int(h) for h in hidden))

    def check(self, config: AgentConfig) -> None:
        """ValueError unless ``config.boundary`` is one SLAC takes (the latent-switching modes
        of LILI do not apply)."""
        if config.boundary not in (None, "bootstrap", "cut"):
            raise ValueError(f"config boundary={config.boundary!r} is invalid for SLAC; allowed: "
                             "bootstrap, cut or null (= bootstrap)")


MODEL_METRICS = ("rep_loss", "kl", "obs_nll", "rew_nll")
"""The model's metrics: ``rep_loss`` is the negative ELBO, the rest its parts."""

_LEAK = 0.2  # TensorFlow's leaky_relu default, which the official networks use.


# -- sequences -----------------------------------------------------------------------------------
def gather_sequences(arrays: dict[str, jax.Array], slot: jax.Array, t: jax.Array,
                     seq_len: int) -> dict[str, jax.Array]:
    """The sequences SLAC needs for the transitions at buffer ``slot`` and step ``t`` (pure JAX).

    Frame j of an interaction of length L is its j-th observation (frame L: the final
    ``next_obs``). With K = ``seq_len``, for every transition:

    - ``hist_*``: frames t-K+1 .. t+1 and actions t-K+1 .. t, the actor's history at t (first K
      frames, first K-1 actions) and at t+1 (the last ones); ``hist_valid`` is False before
      the interaction's start, where ``hist_act`` is zero (frames are zeroed after
      normalisation, see :func:`actor_input`).
    - ``win_*``: the K+1 frames from max(0, t-K+1) the latent filter runs over, with actions
      and rewards between them; ``win_valid`` marks frames <= L, ``win_step_valid`` steps < L
      (only short interactions have invalid ones). ``pos`` = t - start: z_t is the filter's
      sample at ``pos``, z_{t+1} at ``pos + 1``.

    Never crosses an interaction boundary. ``slot`` and ``t`` share a shape [...]; outputs are
    [..., frames, ...].
    """
    horizon = arrays["rew"].shape[1]
    rows = slot[..., None]
    length = arrays["length"][slot][..., None]

    def frames(idx):
        at = arrays["obs"][rows, jnp.clip(idx, 0, horizon - 1)]
        final = arrays["next_obs"][rows, jnp.clip(idx - 1, 0, horizon - 1)]
        return jnp.where((idx >= length)[..., None], final, at)

    def steps(name, idx):
        return arrays[name][rows, jnp.clip(idx, 0, horizon - 1)]

    k = seq_len
    h_idx = t[..., None] + jnp.arange(-k + 1, 2)
    h_valid = h_idx >= 0
    start = jnp.maximum(t - k + 1, 0)
    w_idx = start[..., None] + jnp.arange(k + 1)
    return {
        "hist_obs": frames(h_idx),
        "hist_t": h_idx,
        "hist_valid": h_valid,
        "hist_act": steps("act", h_idx[..., :-1]) * h_valid[..., :-1, None],
        "win_obs": frames(w_idx),
        "win_t": w_idx,
        "win_valid": w_idx <= length,
        "win_act": steps("act", w_idx[..., :-1]),
        "win_rew": steps("rew", w_idx[..., :-1]),
        "win_step_valid": w_idx[..., :-1] < length,
        "pos": t - start,
    }


def sample_sequences(arrays: dict[str, jax.Array], count: jax.Array, key: jax.Array,
                     n_interactions: int, per_interaction: int, seq_len: int
                     ) -> dict[str, jax.Array]:
    """A batch of transitions with their sequences (pure JAX, runs inside the update scan).

    The transitions are :func:`lili.buffer.sample`'s (same draw for the same key: interactions
    uniform, steps uniform within them), shaped [n_interactions, per_interaction]; the fields of
    :func:`gather_sequences` are added.
    """
    batch = sample(arrays, count, key, n_interactions, per_interaction)
    capacity = arrays["rew"].shape[0]
    slot = jnp.broadcast_to(jnp.mod(batch["index"], capacity)[:, None], batch["t"].shape)
    batch.update(gather_sequences(arrays, slot, batch["t"], seq_len))
    # As in lili.buffer.sample: keep XLA from re-gathering inside every consumer.
    return jax.lax.optimization_barrier(batch)


def _noise(key: jax.Array, shape: tuple[int, ...], sample: bool) -> jax.Array:
    """Standard normal noise for a reparameterised draw, or zeros (the draw is its mean)."""
    return jax.random.normal(key, shape) if sample else jnp.zeros(shape)


def actor_input(frames: jax.Array, actions: jax.Array) -> jax.Array:
    """The actor's input: K (normalised, zero-padded) frames [..., K, dx] and the K-1 actions
    between them [..., K-1, ad], flattened and concatenated. Used for training and acting alike.
    """
    flat = lambda a: a.reshape(*a.shape[:-2], -1)  # noqa: E731
    return jnp.concatenate([flat(frames), flat(actions)], -1)


# -- the latent variable model -------------------------------------------------------------------
class GaussianMLP(nn.Module):
    """A diagonal Gaussian from an MLP on the concatenated inputs: (mean, std)."""

    hidden: Sequence[int]
    out: int

    @nn.compact
    def __call__(self, *inputs: jax.Array) -> tuple[jax.Array, jax.Array]:
        h = jnp.concatenate(inputs, -1)
        for width in self.hidden:
            h = nn.leaky_relu(nn.Dense(width)(h), _LEAK)
        mean, raw = jnp.split(nn.Dense(2 * self.out)(h), 2, axis=-1)
        return mean, jax.nn.softplus(raw) + 1e-5


class LatentModel(nn.Module):
    """SLAC's sequential latent variable model for state observations (module docstring)."""

    x_dim: int
    z1_dim: int
    z2_dim: int
    feature_dim: int
    hidden: Sequence[int]

    def setup(self) -> None:
        h, z1, z2 = self.hidden, self.z1_dim, self.z2_dim
        self.compress_hidden = nn.Dense(h[0])
        self.compress_out = nn.Dense(self.feature_dim)
        self.q1_first = GaussianMLP(h, z1)
        self.p2_first = GaussianMLP(h, z2)   # = q(z2_0 | z1_0)
        self.p1 = GaussianMLP(h, z1)
        self.q1 = GaussianMLP(h, z1)
        self.p2 = GaussianMLP(h, z2)         # = q(z2_{t+1} | z1_{t+1}, z2_t, a_t)
        self.decoder = [nn.Dense(w) for w in h] + [nn.Dense(self.x_dim)]
        self.reward = GaussianMLP(h, 1)

    def features(self, x: jax.Array) -> jax.Array:
        h = nn.leaky_relu(self.compress_hidden(x), _LEAK)
        return nn.leaky_relu(self.compress_out(h), _LEAK)

    def first_posterior(self, feat: jax.Array) -> tuple[jax.Array, jax.Array]:
        return self.q1_first(feat)

    def first_z2(self, z1: jax.Array) -> tuple[jax.Array, jax.Array]:
        return self.p2_first(z1)

    def z1_prior(self, z2: jax.Array, a: jax.Array) -> tuple[jax.Array, jax.Array]:
        return self.p1(z2, a)

    def z1_posterior(self, feat: jax.Array, z2: jax.Array,
                     a: jax.Array) -> tuple[jax.Array, jax.Array]:
        return self.q1(feat, z2, a)

    def z2_transition(self, z1: jax.Array, z2: jax.Array,
                      a: jax.Array) -> tuple[jax.Array, jax.Array]:
        return self.p2(z1, z2, a)

    def decode(self, z1: jax.Array, z2: jax.Array) -> jax.Array:
        h = jnp.concatenate([z1, z2], -1)
        for layer in self.decoder[:-1]:
            h = nn.leaky_relu(layer(h), _LEAK)
        return self.decoder[-1](h)

    def reward_dist(self, z1: jax.Array, z2: jax.Array, a: jax.Array, z1n: jax.Array,
                    z2n: jax.Array) -> tuple[jax.Array, jax.Array]:
        mean, std = self.reward(z1, z2, a, z1n, z2n)
        return mean[..., 0], std[..., 0]

    def __call__(self, x: jax.Array, a: jax.Array):
        """Touch every network (for ``init``)."""
        f = self.features(x)
        z1 = self.first_posterior(f)[0]
        z2 = self.first_z2(z1)[0]
        self.z1_prior(z2, a)
        z1n = self.z1_posterior(f, z2, a)[0]
        z2n = self.z2_transition(z1n, z2, a)[0]
        return self.decode(z1, z2), self.reward_dist(z1, z2, a, z1n, z2n)


class SLACCore(SACCore):
    """SLAC's maths on the SAC core (module docstring). Its latent model and the model's
    optimiser live in ``AgentState.aux`` (``slac``, ``opt_slac``); its acting state's memory
    holds the interaction's last K-1 observations (raw) and actions (in [-1, 1]), oldest
    first, zero before the interaction's start."""

    default_boundary = "bootstrap"
    options_key: ClassVar[str] = "slac"
    """Where the options live: ``config.extra[options_key]`` (a variant reads its own)."""
    actor_frames: ClassVar[int | None] = None
    """How many of the K history frames the actor reads (the last ones, with the actions
    between them); None: all K, SLAC's. A variant reads fewer while the model and the
    critic's filter keep K."""
    critic_samples: ClassVar[bool] = True
    """Whether the critic reads a sample of the filter's belief (SLAC's) or, False, the
    filter run on means: every draw of z1 and z2 on the critic's path set to its mean."""

    def __init__(self, obs_dim: int, act_dim: int, horizon: int, config: AgentConfig,
                 boundary: str | None = None) -> None:
        self.options: SLACOptions = dataclass_options(config, self.options_key, SLACOptions)
        self.options.check(config)
        super().__init__(obs_dim, act_dim, horizon, config, boundary)
        self.jit_model_step = partial(core_jit("_model_step"), self)
        self.jit_model_batch = partial(core_jit("_model_batch"), self)

    # -- construction --------------------------------------------------------------------------
    def _build(self) -> None:
        super()._build()
        o = self.options
        self.seq_len = o.sequence_length
        self.lvm = LatentModel(self.x_dim, o.z1_dim, o.z2_dim, o.feature_dim,
                               o.model_hidden)
        self.opt_slac = optax.adam(o.lr_model)

    def _input_dims(self) -> tuple[int, int]:
        o, phase = self.options, int(self.config.phase_feature)
        k = self._actor_k()
        return o.z1_dim + o.z2_dim + phase, k * self.x_dim + (k - 1) * self.act_dim

    def _actor_k(self) -> int:
        return min(self.actor_frames or self.seq_len, self.seq_len)

    def _actor_in(self, frames: jax.Array, actions: jax.Array) -> jax.Array:
        """The actor's input from K frames [..., K, dx] and the K - 1 actions between them: the
        last :meth:`_actor_k` frames and the actions between those (:func:`actor_input`)."""
        k = self._actor_k()
        return actor_input(frames[..., frames.shape[-2] - k:, :],
                           actions[..., actions.shape[-2] - (k - 1):, :])

    def _init_aux(self, key: jax.Array) -> dict[str, Any]:
        # One compiled call: run eagerly, every initialiser compiles on its own (~15 s here).
        params = jax.jit(self.lvm.init)(jax.random.fold_in(key, 1), jnp.zeros((1, self.x_dim)),
                                        jnp.zeros((1, self.act_dim)))
        return {"slac": params, "opt_slac": self.opt_slac.init(params)}

    # -- the model ------------------------------------------------------------------------------
    def _frames_x(self, norm: Normaliser, obs: jax.Array, t: jax.Array,
                  valid: jax.Array) -> jax.Array:
        """Network frames: normalised observation (+ phase), zero where ``valid`` is False."""
        return self._x(norm, obs, t) * valid[..., None]

    def _critic_x(self, z: jax.Array, t: jax.Array) -> jax.Array:
        if not self.config.phase_feature:
            return z
        return jnp.concatenate([z, (t.astype(jnp.float32) / self.horizon)[..., None]], -1)

    def _critic_in(self, z: jax.Array, t: jax.Array, x: jax.Array) -> jax.Array:
        """The critic's input at step ``t`` from the latent sample ``z`` and the network frame
        ``x`` of the observation at t: SLAC's reads the latent only (a variant may read more;
        its width is :meth:`_input_dims`'s first)."""
        return self._critic_x(z, t)

    def _first_latent(self, params: Params, feat: jax.Array, e1: jax.Array, e2: jax.Array
                      ) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
        """An interaction's first latent from its first frame's features [N, f] and standard
        noise e1 [N, z1], e2 [N, z2]: z1 from q(z1_0 | x_0), z2 from p(z2_0 | z1_0). Returns
        (z1, z2, q's mean, q's std)."""
        lvm = self.lvm
        m1, s1 = lvm.apply(params, feat, method=LatentModel.first_posterior)
        z1 = m1 + s1 * e1
        m2, s2 = lvm.apply(params, z1, method=LatentModel.first_z2)
        return z1, m2 + s2 * e2, m1, s1

    def posterior(self, params: Params, x: jax.Array, a: jax.Array, key: jax.Array,
                  sample: bool = True
                  ) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
        """Filter a sequence: frames ``x`` [N, T+1, dx], actions ``a`` [N, T, ad].

        Returns reparameterised samples z1 [N, T+1, z1], z2 [N, T+1, z2] and q(z1)'s (mean,
        std), each [N, T+1, z1]. Frame 0 uses the first-step distributions. ``sample=False``
        draws zero noise: each z is its distribution's mean given the means before it.
        """
        lvm, o = self.lvm, self.options
        n, frames = x.shape[0], x.shape[1]
        k1, k2 = jax.random.split(key)
        e1 = _noise(k1, (frames, n, o.z1_dim), sample)
        e2 = _noise(k2, (frames, n, o.z2_dim), sample)
        feat = lvm.apply(params, x, method=LatentModel.features)
        z1, z2, m1, s1 = self._first_latent(params, feat[:, 0], e1[0], e2[0])

        def step(z2_prev, inp):
            f, a_prev, n1, n2 = inp
            m, s = lvm.apply(params, f, z2_prev, a_prev, method=LatentModel.z1_posterior)
            z1 = m + s * n1
            mz, sz = lvm.apply(params, z1, z2_prev, a_prev, method=LatentModel.z2_transition)
            z2 = mz + sz * n2
            return z2, (z1, z2, m, s)

        xs = (jnp.swapaxes(feat[:, 1:], 0, 1), jnp.swapaxes(a, 0, 1), e1[1:], e2[1:])
        _, (z1s, z2s, ms, ss) = jax.lax.scan(step, z2, xs)

        def cat(first, rest):
            return jnp.concatenate([first[:, None], jnp.swapaxes(rest, 0, 1)], 1)

        return cat(z1, z1s), cat(z2, z2s), cat(m1, ms), cat(s1, ss)

    def elbo_terms(self, params: Params, norm: Normaliser, seq: dict[str, jax.Array],
                   key: jax.Array) -> dict[str, jax.Array]:
        """The negative ELBO of sequences (fields ``win_*`` of :func:`gather_sequences`, [N, ...])
        and its parts, each a sum over time and dims, mean over sequences."""
        lvm = self.lvm
        log_std_x = jnp.log(self.options.decoder_std)
        x = self._frames_x(norm, seq["win_obs"], seq["win_t"], seq["win_valid"])
        a = seq["win_act"]
        r = norm.rew(seq["win_rew"])
        fmask = seq["win_valid"].astype(jnp.float32)
        smask = seq["win_step_valid"].astype(jnp.float32)
        z1, z2, mq, sq = self.posterior(params, x, a, key)
        mp, sp = lvm.apply(params, z2[:, :-1], a, method=LatentModel.z1_prior)
        mp = jnp.concatenate([jnp.zeros_like(mq[:, :1]), mp], 1)
        sp = jnp.concatenate([jnp.ones_like(sq[:, :1]), sp], 1)
        kl = (gaussian_kl(mq, jnp.log(sq), mp, jnp.log(sp)) * fmask).sum(-1)
        x_hat = lvm.apply(params, z1, z2, method=LatentModel.decode)
        obs_nll = -(gaussian_logp(x, x_hat, log_std_x).sum(-1) * fmask).sum(-1)
        rm, rs = lvm.apply(params, z1[:, :-1], z2[:, :-1], a, z1[:, 1:], z2[:, 1:],
                           method=LatentModel.reward_dist)
        rew_nll = -(gaussian_logp(r, rm, jnp.log(rs)) * smask).sum(-1)
        loss = (obs_nll + rew_nll + kl).mean()
        return {"loss": loss, "kl": kl.mean(), "obs_nll": obs_nll.mean(),
                "rew_nll": rew_nll.mean()}

    def _model_step(self, params: Params, opt: Any, norm: Normaliser, seq: dict[str, jax.Array],
                    key: jax.Array):
        (_, terms), grads = jax.value_and_grad(
            lambda p: (lambda d: (d["loss"], d))(self.elbo_terms(p, norm, seq, key)),
            has_aux=True)(params)
        upd, opt = self.opt_slac.update(grads, opt, params)
        return optax.apply_updates(params, upd), opt, terms

    def _model_batch(self, arrays: dict[str, jax.Array], count: jax.Array,
                     key: jax.Array) -> dict[str, jax.Array]:
        seq = sample_sequences(arrays, count, key, self.options.model_batch, 1, self.seq_len)
        return {k: v[:, 0] for k, v in seq.items() if k.startswith("win_")}

    # -- SAC hooks -------------------------------------------------------------------------------
    def _batch(self, state: AgentState, arrays: dict[str, jax.Array], count: jax.Array,
               key: jax.Array) -> dict[str, Any]:
        """RL sequences with the critic's and actor's inputs (detached), plus a model batch."""
        cfg, k = self.config, self.seq_len
        k_rl, k_model, k_z, k_first = jax.random.split(key, 4)
        batch = sample_sequences(arrays, count, k_rl, cfg.batch_interactions,
                                 cfg.per_interaction, k)
        norm, params = state.norm, sg(state.aux["slac"])
        b, m = batch["t"].shape
        flat = lambda v: v.reshape(b * m, *v.shape[2:])  # noqa: E731
        x_win = self._frames_x(norm, batch["win_obs"], batch["win_t"], batch["win_valid"])
        z1, z2, _, _ = self.posterior(params, flat(x_win), flat(batch["win_act"]), k_z,
                                      self.critic_samples)
        z = jnp.concatenate([z1, z2], -1).reshape(b, m, k + 1, -1)
        pos = batch["pos"][..., None, None]
        z_t = jnp.take_along_axis(z, pos, 2)[..., 0, :]
        z_within = jnp.take_along_axis(z, pos + 1, 2)[..., 0, :]
        # The next interaction's first step: what the target bootstraps from at the boundary.
        x_first = self._x(norm, batch["next_first_obs"], 0.0)
        feat = self.lvm.apply(params, x_first, method=LatentModel.features)
        kf1, kf2 = jax.random.split(k_first)
        o, cs = self.options, self.critic_samples
        zf1, zf2, _, _ = self._first_latent(params, feat, _noise(kf1, (b, o.z1_dim), cs),
                                            _noise(kf2, (b, o.z2_dim), cs))
        z_first = jnp.concatenate([zf1, zf2], -1)
        last = batch["last"][..., None]
        z_next = jnp.where(last, z_first[:, None], z_within)
        t_next = jnp.where(batch["last"], 0, batch["t"] + 1)

        x_hist = self._frames_x(norm, batch["hist_obs"], batch["hist_t"], batch["hist_valid"])
        acts = batch["hist_act"]
        pad_x = jnp.zeros((b, k - 1, self.x_dim))
        first_hist = self._actor_in(jnp.concatenate([pad_x, x_first[:, None]], 1),
                                    jnp.zeros((b, k - 1, self.act_dim)))
        x_next = jnp.where(last, x_first[:, None], x_hist[..., k, :])
        out = {key_: batch[key_] for key_ in ("act", "rew", "t", "last", "index")}
        out.update(
            x_critic=self._critic_in(z_t, batch["t"], x_hist[..., k - 1, :]),
            x_actor=self._actor_in(x_hist[..., :k, :], acts[..., : k - 1, :]),
            x_critic_next=self._critic_in(z_next, t_next, x_next),
            x_actor_next=jnp.where(last, first_hist[:, None],
                                   self._actor_in(x_hist[..., 1:, :], acts[..., 1:, :])),
            model=self._model_batch(arrays, count, k_model),
        )
        return out

    def _inputs(self, model: Params, state: AgentState, batch: dict[str, Any]):
        return batch["x_critic"], batch["x_actor"], jnp.zeros((batch["rew"].shape[0], 0))

    def _target_inputs(self, state: AgentState, batch: dict[str, Any]
                       ) -> tuple[jax.Array, jax.Array]:
        return batch["x_critic_next"], batch["x_actor_next"]

    def update(self, state: AgentState, batch: dict[str, Any],
               key: jax.Array) -> tuple[AgentState, dict[str, jax.Array]]:
        # One model step on its own batch and optimiser, then the SAC step; the critic's latents
        # were sampled in _batch from the model before this step (as in the official train step).
        k_model = jax.random.fold_in(key, 1)
        every = self.options.model_every

        def model_step(s):
            return self._model_step(s.aux["slac"], s.aux["opt_slac"], s.norm, batch["model"],
                                    k_model)

        if every == 1:
            params, opt, terms = model_step(state)
        else:
            def skip(s):
                zero = jnp.zeros(())
                return s.aux["slac"], s.aux["opt_slac"], {"loss": zero, "kl": zero,
                                                          "obs_nll": zero, "rew_nll": zero}

            taken = state.updates % every == 0
            params, opt, terms = jax.lax.cond(taken, model_step, skip, state)
            terms = dict(terms, model_steps=taken.astype(jnp.float32))
        state = state.replace(aux=dict(state.aux, slac=params, opt_slac=opt))
        state, metrics = super().update(state, batch, key)
        metrics = dict(metrics, rep_loss=terms.pop("loss"), **terms)
        return state, metrics

    def block(self, state: AgentState, arrays: dict[str, jax.Array], count: jax.Array,
              key: jax.Array) -> tuple[AgentState, dict[str, jax.Array]]:
        state, metrics = super().block(state, arrays, count, key)
        if "model_steps" in metrics:
            # Skipped model steps report zeros: average the model's terms over the steps taken.
            frac = jnp.maximum(metrics.pop("model_steps"), 1e-9)
            metrics = {k: v / frac if k in MODEL_METRICS else v for k, v in metrics.items()}
        return state, metrics

    def pretrain(self, state: AgentState, buffer: InteractionBuffer, steps: int,
                 key: jax.Array) -> tuple[AgentState, np.ndarray]:
        """Run ``steps`` model-only steps on the buffer (fresh batches); return the new state
        and the steps' losses.

        One compiled step called in a loop rather than a scan: the same compiled step serves
        any number of steps, and XLA compiles a scan of it as a separate ~10 s program.
        """
        arrays, count = buffer.arrays, jnp.asarray(buffer.count, jnp.int32)
        params, opt = state.aux["slac"], state.aux["opt_slac"]
        losses = []
        for i in range(steps):
            kb, ke = jax.random.split(jax.random.fold_in(key, i))
            seq = self.jit_model_batch(arrays, count, kb)
            params, opt, terms = self.jit_model_step(params, opt, state.norm, seq, ke)
            losses.append(terms["loss"])
        return state.replace(aux=dict(state.aux, slac=params, opt_slac=opt)), np.asarray(losses)

    def learn_block(self, state: AgentState, buffer: InteractionBuffer,
                    key: jax.Array) -> tuple[AgentState, dict[str, float]]:
        """One fused block of updates; before the very first one, ``pretrain_steps`` model-only
        steps (a function of the state, so a resumed run repeats exactly what it would have).
        The first block's metrics then carry ``pretrain_first`` and ``pretrain_last``, the
        pretraining's first and last loss (a run folder keeps them, as the ELBO's terms, in
        ``block_extras.jsonl``)."""
        steps = self.options.pretrain_steps
        extra: dict[str, float] = {}
        if steps > 0 and int(state.updates) == 0:
            state, losses = self.pretrain(state, buffer, steps, jax.random.fold_in(key, 1))
            extra = {"pretrain_first": float(losses[0]), "pretrain_last": float(losses[-1])}
        state, metrics = super().learn_block(state, buffer, key)
        return state, {**metrics, **extra}

    # -- acting --------------------------------------------------------------------------------
    def initial_acting(self, state: AgentState) -> ActingState:
        """The acting state at the start of an interaction (empty history)."""
        k = self.seq_len
        return ActingState(jnp.zeros(0, jnp.float32), jnp.zeros((), jnp.int32),
                           {"obs": jnp.zeros((k - 1, self.obs_dim), jnp.float32),
                            "act": jnp.zeros((k - 1, self.act_dim), jnp.float32)})

    def history_x(self, norm: Normaliser, obs: jax.Array, t: jax.Array, valid: jax.Array,
                  act: jax.Array) -> jax.Array:
        """The actor's input from K frames (raw obs [K, od], steps [K], valid [K]) and K-1
        actions (what ``_batch`` builds from the buffer for the same step)."""
        return self._actor_in(self._frames_x(norm, obs, t, valid), act * valid[:-1, None])

    def acting_input(self, obs: jax.Array, acting: ActingState
                     ) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
        """(frames [K, od], steps [K], valid [K], actions [K-1, ad]) the actor reads at
        ``acting.t`` given the current ``obs`` (the same layout training gathers)."""
        k = self.seq_len
        frames = jnp.concatenate([acting.memory["obs"], obs[None]], 0)
        steps = acting.t - k + 1 + jnp.arange(k)
        return frames, steps, steps >= 0, acting.memory["act"]

    def _act(self, actor: Params, norm: Normaliser, obs: jax.Array, acting: ActingState,
             key: jax.Array, deterministic: bool) -> tuple[jax.Array, ActingState]:
        frames, steps, valid, act = self.acting_input(obs, acting)
        mean, log_std = self.actor.apply(actor, self.history_x(norm, frames, steps, valid, act))
        a = jnp.tanh(mean) if deterministic else tanh_gaussian(mean, log_std, key)[0]
        memory = {"obs": frames[1:], "act": jnp.concatenate([act[1:], a[None]], 0)}
        return a, ActingState(acting.z, acting.t + 1, memory)


class SLAC(SAC):
    """Stochastic Latent Actor-Critic, the LILI paper's POMDP baseline (module docstring).

    ``SLAC(env, AgentConfig(extra={"slac": {"model_every": 2}}))`` changes one option of
    :class:`SLACOptions`. Its acting state carries the interaction's history: start each
    interaction with :meth:`initial_state` and pass on what :meth:`predict` returns.
    """

    algo = "slac"
    core_cls = SLACCore


register("slac", SLAC, options=SLACOptions)
