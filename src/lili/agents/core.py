"""The shared SAC core as pure functions of an explicit, typed agent state.

:class:`SACCore` is the maths: a frozen description of the networks and hyperparameters whose
methods are pure functions of an explicit, typed :class:`~lili.agents.base.AgentState`:
:meth:`~SACCore.init`, :meth:`~SACCore.act` (observation and acting state in, action and the
next acting state out), :meth:`~SACCore.block` (all gradient updates of one interaction as one
``jax.lax.scan`` with the batch sampling inside) and :meth:`~SACCore.next_latent`. A core holds
no env, no buffer and no state, so the same maths can be ``jax.vmap``-ed over seeds
(:mod:`lili.agents.multiseed`) and driven step by step by evaluation or the play page.

Latent agents subclass the core and override its hooks: :meth:`~SACCore._init_latent`
(parameters), :meth:`~SACCore._latents` (z for the batch, with gradient, plus the target-side
latents), :meth:`~SACCore._rep_loss` (representation loss) and :meth:`~SACCore._act_latent` (the
latent to act with); :meth:`~SACCore._rep_noise` says whether the representation loss draws
noise (it then finds its key in the batch). The critic target is written once, here, for every
boundary mode (see ``AgentConfig.boundary``). The facade a user holds is
:class:`lili.agents.sac.SAC`.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import cache, partial
from typing import Any, ClassVar

import jax
import jax.numpy as jnp
import numpy as np
import optax

from lili.agents.base import ActingState, AgentState, Normaliser, Params
from lili.buffer import Batch, InteractionBuffer, Window, sample
from lili.config import AgentConfig
from lili.dists import tanh_gaussian
from lili.nets import Actor, TwinCritic

__all__ = ["SACCore", "core_jit", "sg"]

sg = jax.lax.stop_gradient


@cache
def core_jit(method: str, *static_names: str) -> Callable[..., Any]:
    """``core.<method>(...)`` jitted once for all cores, the core being a static argument."""

    def call(core: SACCore, *args: Any, **kwargs: Any) -> Any:
        return getattr(core, method)(*args, **kwargs)

    return jax.jit(call, static_argnums=0, static_argnames=static_names or None)


class SACCore:
    """Soft actor-critic over interactions, as pure functions of an :class:`AgentState`.

    Built from the env's sizes and an :class:`AgentConfig`; treat it as immutable (it is the
    static part of every jitted function). Across the interaction boundary SAC bootstraps from
    the next interaction's first observation (the stream of interactions goes on).
    """

    uses_latent: ClassVar[bool] = False
    default_boundary: ClassVar[str] = "bootstrap"

    def __init__(self, obs_dim: int, act_dim: int, horizon: int, config: AgentConfig,
                 boundary: str | None = None) -> None:
        self.config = config
        self.obs_dim, self.act_dim, self.horizon = int(obs_dim), int(act_dim), int(horizon)
        self.boundary = config.boundary or boundary or self.default_boundary
        self.latent_dim = config.latent_dim if self.uses_latent else 0
        self.history = config.history if self.uses_latent else 0
        self.n_updates = max(1, round(config.updates_per_step * self.horizon))
        self.target_entropy = (
            -float(self.act_dim) if config.target_entropy is None
            else float(config.target_entropy)
        )
        self._build()
        self._key = (type(self), self.obs_dim, self.act_dim, self.horizon, self.boundary,
                     json.dumps(config.to_dict(), sort_keys=True))
        self.jit_block = partial(core_jit("block"), self)
        self.jit_act = partial(core_jit("_act_step", "deterministic"), self)
        self.jit_latent = partial(core_jit("_act_latent"), self)

    # Cores with the same class, sizes and config are the same maths: equal and hashable, so
    # the compiled functions (jitted with the core as a static argument) are shared between
    # them: loading a checkpoint or evaluating a copy of an agent compiles nothing new.
    def __eq__(self, other: object) -> bool:
        return isinstance(other, SACCore) and self._key == other._key

    def __hash__(self) -> int:
        return hash(self._key)

    # -- construction --------------------------------------------------------------------------
    def _build(self) -> None:
        cfg = self.config
        self.actor = Actor(cfg.hidden, self.act_dim)
        self.critic = TwinCritic(cfg.hidden)
        self.x_dim = self.obs_dim + int(cfg.phase_feature) + self.latent_dim
        self.opt_actor = optax.adam(cfg.lr_actor)
        self.opt_alpha = optax.adam(cfg.lr_alpha)
        self.opt_model = optax.multi_transform(
            {
                "critic": optax.adam(cfg.lr_critic),
                "encoder": optax.adam(cfg.lr_encoder),
                "decoder": optax.adam(cfg.lr_decoder),
            },
            {"critic": "critic",
             **{k: self._OPTIMISER_OF.get(k, k) for k in self._latent_param_names()}},
        )

    _OPTIMISER_OF: ClassVar[dict[str, str]] = {}
    """Latent parameter groups trained by another group's optimiser (same learning rate)."""

    def _latent_param_names(self) -> tuple[str, ...]:
        return ()

    def _init_latent(self, key: jax.Array) -> dict[str, Params]:
        return {}

    def _input_dims(self) -> tuple[int, int]:
        """Sizes of the critic's and the actor's state input (SAC, LILI: the same x)."""
        return self.x_dim, self.x_dim

    def init(self, key: jax.Array) -> AgentState:
        """A fresh agent state (parameters, optimiser states, identity normaliser)."""
        ka, kc, kl = jax.random.split(key, 3)
        x_critic, x_actor = self._input_dims()
        a = jnp.zeros((1, self.act_dim))
        model = {"critic": self.critic.init(kc, jnp.zeros((1, x_critic)), a)}
        model.update(self._init_latent(kl))
        actor = self.actor.init(ka, jnp.zeros((1, x_actor)))
        target = {k: v for k, v in model.items() if k in ("critic", "encoder")}
        log_alpha = jnp.asarray(np.log(self.config.init_alpha), jnp.float32)
        return AgentState(
            actor=actor, model=model, target=target, log_alpha=log_alpha,
            opt_actor=self.opt_actor.init(actor), opt_model=self.opt_model.init(model),
            opt_alpha=self.opt_alpha.init(log_alpha), norm=Normaliser.identity(self.obs_dim),
            updates=jnp.zeros((), jnp.int32), aux=self._init_aux(key),
        )

    def _init_aux(self, key: jax.Array) -> dict[str, Any]:
        return {}

    # -- features ------------------------------------------------------------------------------
    def _x(self, norm: Normaliser, obs: jax.Array, t: jax.Array | float) -> jax.Array:
        """Network input for an observation at step t (before the latent)."""
        x = norm.obs(obs)
        if self.config.phase_feature:
            phase = jnp.broadcast_to(jnp.asarray(t, jnp.float32) / self.horizon, x.shape[:-1])
            x = jnp.concatenate([x, phase[..., None]], -1)
        return x

    # -- latent hooks (no latent for SAC) --------------------------------------------------------
    def _latents(self, model: Params, target: Params, norm: Normaliser, batch: Batch):
        """Return (z with gradient [B, L], zbar of interaction k [B, L], zbar of k+1 [B, L])."""
        empty = jnp.zeros((batch["rew"].shape[0], 0))
        return empty, empty, empty

    def _rep_loss(self, model: Params, norm: Normaliser, batch: Batch, z: jax.Array) -> jax.Array:
        return jnp.zeros(())

    def _rep_noise(self) -> bool:
        """Whether ``_rep_loss`` draws noise. The hooks get no key, so :meth:`update` then
        splits one off its key and passes it in the batch as ``rep_key``."""
        return False

    def _act_latent(self, model: Params, norm: Normaliser, window: Window) -> jax.Array:
        return jnp.zeros((0,))

    def critic_code(self, model: Params, z: jax.Array) -> jax.Array:
        """What the critic reads of latents ``z`` [B, L] beside the state, in its Q input
        (:meth:`_inputs`) and its target (:meth:`_target_inputs`) alike: ``z`` itself here (a
        variant in :mod:`lili.contrib` reads what ``z`` predicts instead, and then gives its
        width in :meth:`_input_dims`)."""
        return z

    # -- one gradient update ---------------------------------------------------------------
    def _with_z(self, x: jax.Array, z: jax.Array) -> jax.Array:
        """Append the per-interaction latent [B, L] to per-transition inputs [B, M, .]."""
        return jnp.concatenate([x, jnp.broadcast_to(z[:, None, :], (*x.shape[:-1], z.shape[-1]))],
                               -1)

    def _target_inputs(self, state: AgentState, batch: Batch) -> tuple[jax.Array, jax.Array]:
        """(critic input, actor input) at the next state of every transition ([B, M, .]).

        Both read the next observation and phase with z^k, or at the last step the next
        interaction's first observation with the boundary mode's latent; the critic reads its
        :meth:`critic_code` of that latent (SAC and LILI: the latent, so the same x).
        """
        norm, code = state.norm, self.critic_code
        _, zbar, zbar_next = self._latents(state.model, state.target, norm, batch)
        zbar, zbar_next = sg(zbar), sg(zbar_next)
        x_critic = self._next_x(norm, batch, code(state.model, zbar), code(state.model, zbar_next))
        return x_critic, self._next_x(norm, batch, zbar, zbar_next)

    def _next_x(self, norm: Normaliser, batch: Batch, z: jax.Array,
                z_next: jax.Array) -> jax.Array:
        """The input at every transition's next state ([B, M, .]): the next observation and
        phase with ``z`` (interaction k's latent), or at the last step the next interaction's
        first observation with the boundary mode's latent (``z_next`` for ``influence``)."""
        x_within = self._with_z(self._x(norm, batch["next_obs"], batch["t"] + 1), z)
        first = jnp.broadcast_to(batch["next_first_obs"][:, None], batch["obs"].shape)
        z_boundary = z_next if self.boundary == "influence" else z
        x_boundary = self._with_z(self._x(norm, first, 0.0), z_boundary)
        return jnp.where(batch["last"][..., None], x_boundary, x_within)

    def critic_target(self, state: AgentState, batch: Batch, key: jax.Array) -> jax.Array:
        """The soft Bellman target y for every transition of ``batch`` ([B, M]).

        Within an interaction: y = r + gamma V(s', z^k). At its last step the next state is the
        first observation of interaction k+1 (phase 0), with the latent the boundary mode
        prescribes: E(tau^k) for ``influence``, z^k for ``same_z``, none for ``bootstrap``
        (agents without latent); ``cut`` ends the return there (y = r). Every step discounts by
        ``gamma``; with ``boundary_discount="horizon"`` a last step at t < H - 1 also by
        ``gamma ** (H - 1 - t)``.
        V(s, z) = min_j Qbar_j(s, a', z) - alpha log pi(a' | s, z), a' ~ pi(. | s, z).
        Target-side latents come from the target encoder.
        """
        x_critic, x_actor = self._target_inputs(state, batch)
        mean, log_std = self.actor.apply(state.actor, x_actor)
        a_next, logp_next = tanh_gaussian(mean, log_std, key)
        q_next = self.critic.apply(state.target["critic"], x_critic, a_next).min(0)
        v_next = q_next - jnp.exp(state.log_alpha) * logp_next
        cont = 1.0 - (batch["last"] & (self.boundary == "cut")).astype(jnp.float32)
        cfg = self.config
        gamma = cfg.gamma
        if cfg.boundary_discount == "horizon":
            # The steps an early end skipped still count, so ending sooner does not bring the
            # next interaction's value closer.
            skipped = (self.horizon - 1 - batch["t"]).astype(jnp.float32)
            gamma = gamma * jnp.where(batch["last"], cfg.gamma ** skipped, 1.0)
        return sg(batch["rew"] + gamma * cont * v_next)

    def _inputs(self, model: Params, state: AgentState, batch: Batch):
        """(critic input, actor input, z) at every transition's state ([B, M, .]).

        The critic's input carries the gradient into the latent's parameters (scaled by
        ``critic_to_encoder``, forward value unchanged); the actor sees the latent detached, so
        only the critic and J_rep shape the encoder. The actor loss evaluates the critic on the
        critic's input (its value only). ``z`` is what ``_rep_loss`` receives.
        """
        norm = state.norm
        z, _, _ = self._latents(model, state.target, norm, batch)
        z_q = sg(z) + self.config.critic_to_encoder * (z - sg(z))
        x = self._x(norm, batch["obs"], batch["t"])
        return self._with_z(x, self.critic_code(model, z_q)), self._with_z(x, sg(z)), z

    def update(self, state: AgentState, batch: Batch,
               key: jax.Array) -> tuple[AgentState, dict[str, jax.Array]]:
        """One gradient step of critic (and latent model), actor and temperature on ``batch``."""
        cfg = self.config
        if self._rep_noise():
            k_rep, key = jax.random.split(key)
            batch = dict(batch, rep_key=k_rep)
        k_next, k_pi = jax.random.split(key)
        alpha = jnp.exp(state.log_alpha)
        norm = state.norm
        y = self.critic_target(state, batch, k_next)

        def model_loss(model: Params):
            x, x_pi, z = self._inputs(model, state, batch)
            q = self.critic.apply(model["critic"], x, batch["act"])
            critic_loss = 0.5 * ((q - y) ** 2).mean(axis=(1, 2)).sum()
            rep_loss = self._rep_loss(model, norm, batch, z)
            aux = (critic_loss, rep_loss, x, x_pi, q.mean())
            return critic_loss + cfg.rep_weight * rep_loss, aux

        grads, (critic_loss, rep_loss, x_q, x_pi, q_mean) = jax.grad(model_loss, has_aux=True)(
            state.model
        )
        upd, opt_model = self.opt_model.update(grads, state.opt_model, state.model)
        model = optax.apply_updates(state.model, upd)

        def actor_loss(actor: Params):
            mean, log_std = self.actor.apply(actor, x_pi)
            a, logp = tanh_gaussian(mean, log_std, k_pi)
            q = self.critic.apply(model["critic"], x_q, a).min(0)
            return (alpha * logp - q).mean(), logp

        (pi_loss, logp), g_actor = jax.value_and_grad(actor_loss, has_aux=True)(state.actor)
        upd, opt_actor = self.opt_actor.update(g_actor, state.opt_actor, state.actor)
        actor = optax.apply_updates(state.actor, upd)

        def alpha_loss(log_alpha: jax.Array) -> jax.Array:
            return -(log_alpha * sg(logp + self.target_entropy)).mean()

        g_alpha = jax.grad(alpha_loss)(state.log_alpha)
        upd, opt_alpha = self.opt_alpha.update(g_alpha, state.opt_alpha, state.log_alpha)
        log_alpha = optax.apply_updates(state.log_alpha, upd)

        target = {
            k: optax.incremental_update(model[k], state.target[k], cfg.tau)
            for k in state.target
        }
        new_state = state.replace(actor=actor, model=model, target=target, log_alpha=log_alpha,
                                  opt_actor=opt_actor, opt_model=opt_model, opt_alpha=opt_alpha,
                                  updates=state.updates + 1)
        metrics = {"critic_loss": critic_loss, "actor_loss": pi_loss, "alpha": alpha,
                   "rep_loss": rep_loss, "q": q_mean, "entropy": -logp.mean()}
        return new_state, metrics

    @property
    def window_steps(self) -> int | None:
        """How many transitions of each interaction the encoder reads (None: all of them, in
        their order): ``encoder_transitions`` here; a variant whose encoder needs every step in
        place says None."""
        return self.config.encoder_transitions

    def _batch(self, state: AgentState, arrays: dict[str, jax.Array], count: jax.Array,
               key: jax.Array) -> Batch:
        """One training batch, drawn inside the scan (pure JAX).

        Subclasses may add what the update needs and the gradient does not reach (SLAC: its
        sequences and detached latent samples, computed once per update from ``state``).
        """
        cfg = self.config
        return sample(arrays, count, key, cfg.batch_interactions, cfg.per_interaction,
                      self.history, self.window_steps)

    def block(self, state: AgentState, arrays: dict[str, jax.Array], count: jax.Array,
              key: jax.Array) -> tuple[AgentState, dict[str, jax.Array]]:
        """All ``n_updates`` updates of one interaction as one scan (sampling inside the scan).

        ``arrays`` and ``count`` are an :class:`~lili.buffer.InteractionBuffer`'s device arrays
        and its number of interactions. Returns the new state and the block's mean metrics.
        """

        def body(state, k):
            k_batch, k_update = jax.random.split(k)
            return self.update(state, self._batch(state, arrays, count, k_batch), k_update)

        state, metrics = jax.lax.scan(body, state, jax.random.split(key, self.n_updates))
        return state, jax.tree_util.tree_map(jnp.mean, metrics)

    def learn_block(self, state: AgentState, buffer: InteractionBuffer,
                    key: jax.Array) -> tuple[AgentState, dict[str, float]]:
        """The block the training loop runs after each interaction (host side: metrics as
        floats). SLAC overrides it to pretrain its model before the first block."""
        state, metrics = self.jit_block(state, buffer.arrays,
                                        jnp.asarray(buffer.count, jnp.int32), key)
        return state, {k: float(v) for k, v in metrics.items()}

    def fit_normaliser(self, state: AgentState, buffer: InteractionBuffer) -> AgentState:
        """Fit the input and decoder-target statistics on the stored (warm-up) interactions."""
        if not self.config.normalize:
            return state
        n = min(buffer.count, buffer.capacity)
        a = {k: np.asarray(buffer.arrays[k][:n]) for k in ("valid", "obs", "next_obs", "rew")}
        valid = a["valid"]
        return state.replace(norm=Normaliser.fit(a["obs"][valid], a["next_obs"][valid],
                                                 a["rew"][valid]))

    # -- acting ------------------------------------------------------------------------------
    def initial_acting(self, state: AgentState) -> ActingState:
        """The acting state at the first interaction of a sequence (z^1 = 0)."""
        return ActingState(jnp.zeros(self.latent_dim, jnp.float32), jnp.zeros((), jnp.int32))

    def next_acting(self, state: AgentState, window: Window) -> ActingState:
        """The acting state at the start of the interaction after ``window`` (its newest
        interaction last): LILI's z^{i+1} = E(tau^{i-N+1..i}); agents without latent reset."""
        if not self.uses_latent:
            return self.initial_acting(state)
        z = self.jit_latent(state.model, state.norm, window)
        return ActingState(z, jnp.zeros((), jnp.int32))

    def act(self, state: AgentState, obs: jax.Array, acting: ActingState, key: jax.Array,
            deterministic: bool) -> tuple[jax.Array, ActingState]:
        """The network's action in [-1, 1] for ``obs`` and the acting state of the next step.

        ``key`` is the interaction's key: step t samples with ``fold_in(key, t)``, so one key
        serves a whole interaction and the loop needs no per-step key of its own.
        """
        return self._act_step(state.actor, state.norm, obs, acting, key, deterministic)

    def _act_step(self, actor: Params, norm: Normaliser, obs: jax.Array, acting: ActingState,
                  key: jax.Array, deterministic: bool) -> tuple[jax.Array, ActingState]:
        return self._act(actor, norm, obs, acting, jax.random.fold_in(key, acting.t),
                         deterministic)

    def _act(self, actor: Params, norm: Normaliser, obs: jax.Array, acting: ActingState,
             key: jax.Array, deterministic: bool) -> tuple[jax.Array, ActingState]:
        # What acting reads of the state, so that a jitted step does not flatten the optimiser
        # states at every call.
        x = jnp.concatenate([self._x(norm, obs, acting.t), acting.z], -1)
        mean, log_std = self.actor.apply(actor, x)
        a = jnp.tanh(mean) if deterministic else tanh_gaussian(mean, log_std, key)[0]
        return a, acting.replace(t=acting.t + 1)
