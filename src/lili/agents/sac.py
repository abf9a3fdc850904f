"""The shared SAC core and the ``SAC`` agent; every other agent is SAC plus a latent.

One gradient update (critic, actor, temperature, and for latent agents encoder and decoder) is
:meth:`SAC._update`; :meth:`SAC._block` runs all updates of one interaction as one
``jax.lax.scan`` with the batch sampling inside, so a whole block is one compiled call.

Subclasses add a latent by overriding four hooks: :meth:`_init_latent` (parameters),
:meth:`_latents` (z for the batch, with gradient, plus the target-side latents),
:meth:`_rep_loss` (representation loss) and :meth:`_act_latent` (the latent to act with).
The critic target is written once, here, for every boundary mode (see ``AgentConfig.boundary``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, ClassVar

import flax.serialization
import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import optax
from gymnasium import spaces

import lili
from lili.buffer import InteractionBuffer, sample
from lili.config import AgentConfig
from lili.nets import Actor, TwinCritic, tanh_gaussian

__all__ = ["SAC", "Oracle", "CheckpointError", "LatentState"]

Params = Any
sg = jax.lax.stop_gradient


class CheckpointError(ValueError):
    """A checkpoint or saved agent is corrupt or does not match the agent or env."""


class LatentState:
    """What an agent carries between steps while acting: the latent z and the step index t.

    Returned and accepted by :meth:`SAC.predict` (the role SB3 gives ``state`` for recurrent
    policies). Call :meth:`SAC.next_latent_state` after each interaction to move to the latent of
    the next one.
    """

    def __init__(self, z: np.ndarray, t: int = 0) -> None:
        self.z, self.t = z, t

    def __repr__(self) -> str:
        return f"LatentState(z={np.round(self.z, 3).tolist()}, t={self.t})"


def _horizon(env: gym.Env) -> int:
    h = getattr(env.unwrapped, "horizon", None)
    if h is None and env.spec is not None:
        h = env.spec.max_episode_steps
    if not isinstance(h, (int, np.integer)) or h < 1:
        raise ValueError(
            f"env {type(env.unwrapped).__name__} has no interaction length: set an integer "
            "`horizon` >= 1 on it (a RepeatedInteractionEnv does) or register it with "
            "max_episode_steps"
        )
    return int(h)


def _gaussian_normaliser(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean, std = x.mean(0), x.std(0)
    # Constant features (e.g. a coordinate that never moved during warm-up) are left unscaled.
    return mean.astype(np.float32), np.where(std < 1e-6, 1.0, std).astype(np.float32)


class SAC:
    """Soft actor-critic over interactions (no latent): the paper's SAC baseline.

    Construct with a Gymnasium env (continuous Box actions, flat Box observations, a known
    interaction length) and an :class:`AgentConfig`; then ``learn(n_interactions)``,
    ``predict(obs, state)``, ``save(path)`` and ``SAC.load(path, env)``.

    Across the interaction boundary SAC bootstraps from the next interaction's first
    observation (the stream of interactions goes on), like every agent but LILI (no influence).
    """

    algo: ClassVar[str] = "sac"
    uses_latent: ClassVar[bool] = False
    default_boundary: ClassVar[str] = "bootstrap"

    def __init__(self, env: gym.Env, config: AgentConfig | dict | None = None, seed: int = 0):
        if isinstance(config, dict):
            config = AgentConfig.from_dict(config)
        self.config = config or AgentConfig()
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed={seed!r} is invalid; allowed: an integer >= 0")
        self.seed = int(seed)
        self.env = self._wrap(env)
        obs_space, act_space = self.env.observation_space, self.env.action_space
        if not isinstance(obs_space, spaces.Box) or len(obs_space.shape) != 1:
            raise ValueError(f"observation space {obs_space} is not supported; allowed: a flat Box")
        if not isinstance(act_space, spaces.Box) or len(act_space.shape) != 1:
            raise ValueError(
                f"action space {act_space} is not supported; allowed: a flat Box (continuous)"
            )
        if not (np.all(np.isfinite(act_space.low)) and np.all(np.isfinite(act_space.high))):
            raise ValueError(f"action space {act_space} must have finite bounds")
        self.obs_dim, self.act_dim = obs_space.shape[0], act_space.shape[0]
        self.act_low = act_space.low.astype(np.float32)
        self.act_high = act_space.high.astype(np.float32)
        self.horizon = _horizon(self.env)
        self.boundary = self.config.boundary or self.default_boundary
        self.latent_dim = self.config.latent_dim if self.uses_latent else 0
        self.history = self.config.history if self.uses_latent else 0
        self.n_updates = max(1, round(self.config.updates_per_step * self.horizon))
        self.target_entropy = (
            -float(self.act_dim) if self.config.target_entropy is None
            else float(self.config.target_entropy)
        )
        self.num_interactions = 0
        self.wall_time = 0.0
        self.action_log: list[np.ndarray] = []
        self._pending: tuple[np.ndarray, dict] | None = None
        self.buffer = InteractionBuffer(
            self.config.buffer_capacity, self.horizon, self.obs_dim, self.act_dim
        )
        self._build()
        self.state = self._init_state(jax.random.PRNGKey(self.seed))
        self._jit_block = jax.jit(self._block)
        self._jit_act = jax.jit(self._act, static_argnames="deterministic")
        self._jit_latent = jax.jit(self._act_latent)

    # -- construction --------------------------------------------------------------------------
    def _wrap(self, env: gym.Env) -> gym.Env:
        return env

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
            {"critic": "critic", **{k: k for k in self._latent_param_names()}},
        )

    def _latent_param_names(self) -> tuple[str, ...]:
        return ()

    def _init_latent(self, key: jax.Array) -> dict[str, Params]:
        return {}

    def _input_dims(self) -> tuple[int, int]:
        """Sizes of the critic's and the actor's state input (SAC, LILI: the same x)."""
        return self.x_dim, self.x_dim

    def _init_state(self, key: jax.Array) -> dict[str, Any]:
        ka, kc, kl = jax.random.split(key, 3)
        x_critic, x_actor = self._input_dims()
        a = jnp.zeros((1, self.act_dim))
        model = {"critic": self.critic.init(kc, jnp.zeros((1, x_critic)), a)}
        model.update(self._init_latent(kl))
        actor = self.actor.init(ka, jnp.zeros((1, x_actor)))
        target = {k: v for k, v in model.items() if k in ("critic", "encoder")}
        od = self.obs_dim
        norm = {
            "obs_mean": np.zeros(od, np.float32), "obs_std": np.ones(od, np.float32),
            "delta_mean": np.zeros(od, np.float32), "delta_std": np.ones(od, np.float32),
            "rew_mean": np.zeros((), np.float32), "rew_std": np.ones((), np.float32),
        }
        log_alpha = jnp.asarray(np.log(self.config.init_alpha), jnp.float32)
        return {
            "actor": actor,
            "model": model,
            "target": target,
            "log_alpha": log_alpha,
            "opt_actor": self.opt_actor.init(actor),
            "opt_model": self.opt_model.init(model),
            "opt_alpha": self.opt_alpha.init(log_alpha),
            "norm": jax.tree_util.tree_map(jnp.asarray, norm),
            "updates": jnp.zeros((), jnp.int32),
        }

    # -- features ------------------------------------------------------------------------------
    def _x(self, norm: dict, obs: jax.Array, t: jax.Array | float) -> jax.Array:
        """Network input for an observation at step t (before the latent)."""
        x = (obs - norm["obs_mean"]) / norm["obs_std"]
        if self.config.phase_feature:
            phase = jnp.broadcast_to(jnp.asarray(t, jnp.float32) / self.horizon, x.shape[:-1])
            x = jnp.concatenate([x, phase[..., None]], -1)
        return x

    # -- latent hooks (no latent for SAC) --------------------------------------------------------
    def _latents(self, model: Params, target: Params, norm: dict, batch: dict):
        """Return (z with gradient [B, L], zbar of interaction k [B, L], zbar of k+1 [B, L])."""
        empty = jnp.zeros((batch["rew"].shape[0], 0))
        return empty, empty, empty

    def _rep_loss(self, model: Params, norm: dict, batch: dict, z: jax.Array) -> jax.Array:
        return jnp.zeros(())

    def _act_latent(self, model: Params, norm: dict, window: dict) -> jax.Array:
        return jnp.zeros((0,))

    # -- one gradient update ---------------------------------------------------------------
    def _with_z(self, x: jax.Array, z: jax.Array) -> jax.Array:
        """Append the per-interaction latent [B, L] to per-transition inputs [B, M, .]."""
        return jnp.concatenate([x, jnp.broadcast_to(z[:, None, :], (*x.shape[:-1], z.shape[-1]))],
                               -1)

    def _target_inputs(self, state: dict, batch: dict) -> tuple[jax.Array, jax.Array]:
        """(critic input, actor input) at the next state of every transition ([B, M, .]).

        SAC and LILI feed both the same x: the next observation and phase with z^k, or at the
        last step the next interaction's first observation with the boundary mode's latent.
        """
        norm = state["norm"]
        _, zbar, zbar_next = self._latents(state["model"], state["target"], norm, batch)
        zbar, zbar_next = sg(zbar), sg(zbar_next)
        x_within = self._with_z(self._x(norm, batch["next_obs"], batch["t"] + 1), zbar)
        first = jnp.broadcast_to(batch["next_first_obs"][:, None], batch["obs"].shape)
        z_boundary = zbar_next if self.boundary == "influence" else zbar
        x_boundary = self._with_z(self._x(norm, first, 0.0), z_boundary)
        x_next = jnp.where(batch["last"][..., None], x_boundary, x_within)
        return x_next, x_next

    def critic_target(self, state: dict, batch: dict, key: jax.Array) -> jax.Array:
        """The soft Bellman target y for every transition of ``batch`` ([B, M]).

        Within an interaction: y = r + gamma V(s', z^k). At its last step the next state is the
        first observation of interaction k+1 (phase 0), with the latent the boundary mode
        prescribes: E(tau^k) for ``influence``, z^k for ``same_z``, none for ``bootstrap``
        (agents without latent); ``cut`` ends the return there (y = r). V(s, z) =
        min_j Qbar_j(s, a', z) - alpha log pi(a' | s, z), a' ~ pi(. | s, z). Target-side latents
        come from the target encoder.
        """
        x_critic, x_actor = self._target_inputs(state, batch)
        mean, log_std = self.actor.apply(state["actor"], x_actor)
        a_next, logp_next = tanh_gaussian(mean, log_std, key)
        q_next = self.critic.apply(state["target"]["critic"], x_critic, a_next).min(0)
        v_next = q_next - jnp.exp(state["log_alpha"]) * logp_next
        cont = 1.0 - (batch["last"] & (self.boundary == "cut")).astype(jnp.float32)
        return sg(batch["rew"] + self.config.gamma * cont * v_next)

    def _inputs(self, model: Params, state: dict, batch: dict):
        """(critic input, actor input, z) at every transition's state ([B, M, .]).

        The critic's input carries the gradient into the latent's parameters (scaled by
        ``critic_to_encoder``, forward value unchanged); the actor sees the latent detached, so
        only the critic and J_rep shape the encoder. The actor loss evaluates the critic on the
        critic's input (its value only). ``z`` is what ``_rep_loss`` receives.
        """
        norm = state["norm"]
        z, _, _ = self._latents(model, state["target"], norm, batch)
        z_q = sg(z) + self.config.critic_to_encoder * (z - sg(z))
        x = self._x(norm, batch["obs"], batch["t"])
        return self._with_z(x, z_q), self._with_z(x, sg(z)), z

    def _update(self, state: dict, batch: dict, key: jax.Array) -> tuple[dict, dict]:
        cfg = self.config
        k_next, k_pi = jax.random.split(key)
        alpha = jnp.exp(state["log_alpha"])
        norm = state["norm"]
        y = self.critic_target(state, batch, k_next)

        def model_loss(model: Params):
            x, x_pi, z = self._inputs(model, state, batch)
            q = self.critic.apply(model["critic"], x, batch["act"])
            critic_loss = 0.5 * ((q - y) ** 2).mean(axis=(1, 2)).sum()
            rep_loss = self._rep_loss(model, norm, batch, z)
            aux = (critic_loss, rep_loss, x, x_pi, q.mean())
            return critic_loss + cfg.rep_weight * rep_loss, aux

        grads, (critic_loss, rep_loss, x_q, x_pi, q_mean) = jax.grad(model_loss, has_aux=True)(
            state["model"]
        )
        upd, opt_model = self.opt_model.update(grads, state["opt_model"], state["model"])
        model = optax.apply_updates(state["model"], upd)

        def actor_loss(actor: Params):
            mean, log_std = self.actor.apply(actor, x_pi)
            a, logp = tanh_gaussian(mean, log_std, k_pi)
            q = self.critic.apply(model["critic"], x_q, a).min(0)
            return (alpha * logp - q).mean(), logp

        (pi_loss, logp), g_actor = jax.value_and_grad(actor_loss, has_aux=True)(state["actor"])
        upd, opt_actor = self.opt_actor.update(g_actor, state["opt_actor"], state["actor"])
        actor = optax.apply_updates(state["actor"], upd)

        def alpha_loss(log_alpha: jax.Array) -> jax.Array:
            return -(log_alpha * sg(logp + self.target_entropy)).mean()

        g_alpha = jax.grad(alpha_loss)(state["log_alpha"])
        upd, opt_alpha = self.opt_alpha.update(g_alpha, state["opt_alpha"], state["log_alpha"])
        log_alpha = optax.apply_updates(state["log_alpha"], upd)

        target = {
            k: optax.incremental_update(model[k], state["target"][k], cfg.tau)
            for k in state["target"]
        }
        new_state = dict(state, actor=actor, model=model, target=target, log_alpha=log_alpha,
                         opt_actor=opt_actor, opt_model=opt_model, opt_alpha=opt_alpha,
                         updates=state["updates"] + 1)
        metrics = {"critic_loss": critic_loss, "actor_loss": pi_loss, "alpha": alpha,
                   "rep_loss": rep_loss, "q": q_mean, "entropy": -logp.mean()}
        return new_state, metrics

    def _batch(self, state: dict, arrays: dict, count: jax.Array, key: jax.Array) -> dict:
        """One training batch, drawn inside the scan (pure JAX).

        Subclasses may add what the update needs and the gradient does not reach (SLAC: its
        sequences and detached latent samples, computed once per update from ``state``).
        """
        cfg = self.config
        return sample(arrays, count, key, cfg.batch_interactions, cfg.per_interaction,
                      self.history, cfg.encoder_transitions)

    def _block(self, state: dict, arrays: dict, count: jax.Array, key: jax.Array):
        """All updates of one interaction as one scan (sampling inside the scan)."""

        def body(state, k):
            k_batch, k_update = jax.random.split(k)
            return self._update(state, self._batch(state, arrays, count, k_batch), k_update)

        state, metrics = jax.lax.scan(body, state, jax.random.split(key, self.n_updates))
        return state, jax.tree_util.tree_map(jnp.mean, metrics)

    # -- acting ------------------------------------------------------------------------------
    def _act(self, actor: Params, norm: dict, obs: jax.Array, t: jax.Array, z: jax.Array,
             key: jax.Array, deterministic: bool) -> jax.Array:
        x = jnp.concatenate([self._x(norm, obs, t), z], -1)
        mean, log_std = self.actor.apply(actor, x)
        if deterministic:
            return jnp.tanh(mean)
        return tanh_gaussian(mean, log_std, key)[0]

    def initial_state(self) -> LatentState:
        """The acting state at the first interaction (z^1 = 0)."""
        return LatentState(np.zeros(self.latent_dim, np.float32), 0)

    def next_latent_state(self, buffer: InteractionBuffer | None = None) -> LatentState:
        """The acting state for the interaction after the newest one in ``buffer``.

        LILI: z^{i+1} = E(tau^{i-N+1..i}) with the online encoder; SAC: no latent.
        """
        if not self.uses_latent:
            return self.initial_state()
        buf = self.buffer if buffer is None else buffer
        if buf.count < 1:
            raise ValueError("the buffer holds no interaction yet")
        window = buf.window(buf.count - 1, self.history, self.config.encoder_transitions)
        z = self._jit_latent(self.state["model"], self.state["norm"], window)
        return LatentState(np.asarray(z, np.float32), 0)

    def scale_action(self, a: np.ndarray) -> np.ndarray:
        """Map an action in [-1, 1] (the networks' range) to the env's action bounds."""
        span = self.act_high - self.act_low
        return self.act_low + (np.asarray(a, np.float32) + 1.0) * 0.5 * span

    def predict(
        self,
        observation: np.ndarray,
        state: LatentState | None = None,
        deterministic: bool = True,
        key: jax.Array | None = None,
    ) -> tuple[np.ndarray, LatentState]:
        """Action for ``observation`` in env units, and the acting state for the next step.

        ``state`` carries the latent and the step index (start with :meth:`initial_state`);
        pass the returned state back on the next step.
        """
        state = state or self.initial_state()
        obs = np.asarray(observation, np.float32)
        if obs.shape != (self.obs_dim,):
            raise ValueError(f"observation has shape {obs.shape}; expected ({self.obs_dim},)")
        key = jax.random.PRNGKey(0) if key is None else key
        a = self._jit_act(self.state["actor"], self.state["norm"], obs, state.t, state.z, key,
                          deterministic=deterministic)
        return self.scale_action(np.asarray(a)), LatentState(state.z, state.t + 1)

    def policy_action(self, obs: np.ndarray, state: LatentState, key: jax.Array,
                      deterministic: bool) -> np.ndarray:
        """The network's action in [-1, 1] (what the buffer stores)."""
        return np.asarray(self._jit_act(self.state["actor"], self.state["norm"],
                                        np.asarray(obs, np.float32), state.t, state.z, key,
                                        deterministic=deterministic))

    # -- the stream of interactions ----------------------------------------------------------
    def pending_start(self) -> tuple[np.ndarray, dict]:
        """First observation and info of the next interaction to play.

        A fresh agent starts the env's sequence with ``reset(seed=self.seed)``; an agent restored
        from a checkpoint first replays its logged actions so the env is where it was.
        """
        if self._pending is None:
            from lili.train import replay

            self._pending = replay(self)
        return self._pending

    def record(self, traj: dict[str, np.ndarray], next_obs: np.ndarray, next_info: dict) -> None:
        """Store a finished interaction and the start of the next one."""
        self.buffer.add(traj, next_obs)
        self.action_log.append(traj["act"])
        self.num_interactions += 1
        self._pending = (next_obs, next_info)

    def current_latent_state(self) -> LatentState:
        """The acting state for the next interaction (z = 0 before any interaction)."""
        if not self.uses_latent or self.buffer.count == 0:
            return self.initial_state()
        return self.next_latent_state()

    # -- learning --------------------------------------------------------------------------
    def fit_normaliser(self) -> None:
        """Fit the input and decoder-target statistics on the stored (warm-up) interactions."""
        if not self.config.normalize:
            return
        n = min(self.buffer.count, self.buffer.capacity)
        a = self.buffer.arrays
        valid = a["valid"][:n]
        obs, nxt, rew = a["obs"][:n][valid], a["next_obs"][:n][valid], a["rew"][:n][valid]
        om, osd = _gaussian_normaliser(np.concatenate([obs, nxt]))
        dm, dsd = _gaussian_normaliser(nxt - obs)
        rm, rsd = _gaussian_normaliser(rew[:, None])
        norm = {"obs_mean": om, "obs_std": osd, "delta_mean": dm, "delta_std": dsd,
                "rew_mean": rm[0], "rew_std": rsd[0]}
        self.state["norm"] = jax.tree_util.tree_map(jnp.asarray, norm)

    def train_block(self, key: jax.Array) -> dict[str, float]:
        """Run one fused block of ``n_updates`` gradient updates on the buffer."""
        self.state, metrics = self._jit_block(self.state, self.buffer.arrays,
                                              jnp.asarray(self.buffer.count, jnp.int32), key)
        return {k: float(v) for k, v in metrics.items()}

    def learn(self, n_interactions: int, progress: bool = False, callback=None) -> SAC:
        """Train for ``n_interactions`` more interactions on ``self.env`` (see ``lili.train``)."""
        from lili.train import train

        train(self, n_interactions, progress=progress, callback=callback)
        return self

    # -- persistence -------------------------------------------------------------------------
    def _meta(self) -> dict[str, Any]:
        return {
            "format": "lili-agent-1",
            "lili_version": lili.__version__,
            "algo": self.algo,
            "boundary": self.boundary,
            "obs_dim": self.obs_dim,
            "act_dim": self.act_dim,
            "horizon": self.horizon,
            "seed": self.seed,
            "num_interactions": self.num_interactions,
            "config": self.config.to_dict(),
        }

    def state_bytes(self) -> bytes:
        """The learnable state (parameters, optimiser states, normaliser) as Flax msgpack."""
        return flax.serialization.to_bytes(self.state)

    def load_state_bytes(self, data: bytes, source: str = "checkpoint") -> None:
        """Restore :meth:`state_bytes`; raise CheckpointError on a corrupt or mismatched file."""
        try:
            raw = flax.serialization.msgpack_restore(data)
            restored = flax.serialization.from_state_dict(self.state, raw)
        except Exception as e:  # msgpack/flax raise many types on corrupt input
            raise CheckpointError(f"{source} is corrupt or not a lili agent state: {e}") from None
        want = jax.tree_util.tree_map(lambda x: np.shape(x), self.state)
        got = jax.tree_util.tree_map(lambda x: np.shape(x), restored)
        if want != got:
            raise CheckpointError(
                f"{source} does not match this agent: parameter shapes differ "
                f"(saved for another env or network size?)"
            )
        self.state = jax.tree_util.tree_map(jnp.asarray, restored)

    def save(self, path: str | Path) -> Path:
        """Save the agent (parameters, optimiser states, config) to ``path`` (msgpack, no pickle).

        The replay buffer is not included (as in Stable-Baselines3); run folders' checkpoints
        keep it for resuming.
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        blob = flax.serialization.msgpack_serialize(
            {"meta": json.dumps(self._meta()), "state": self.state_bytes()}
        )
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_bytes(blob)
        tmp.replace(path)
        return path

    @classmethod
    def load(cls, path: str | Path, env: gym.Env) -> SAC:
        """Load an agent saved by :meth:`save` for ``env``; CheckpointError if it does not fit."""
        from lili.agents import load_agent

        agent = load_agent(path, env)
        if not isinstance(agent, cls):
            raise CheckpointError(
                f"{path} holds a {agent.algo!r} agent, not a {cls.__name__} "
                "(lili.agents.load_agent picks the class from the file)"
            )
        return agent

    def _check_meta(self, meta: dict, source: str) -> None:
        for key in ("obs_dim", "act_dim", "horizon"):
            if meta[key] != getattr(self, key):
                raise CheckpointError(
                    f"{source} was saved for an env with {key}={meta[key]}; this env has "
                    f"{key}={getattr(self, key)}"
                )


def read_agent_file(path: str | Path) -> tuple[dict[str, Any], bytes]:
    """Read the (meta, state bytes) of a saved agent; CheckpointError if unreadable."""
    p = Path(path)
    if not p.is_file():
        raise CheckpointError(f"agent file {str(p)!r} does not exist")
    try:
        raw = flax.serialization.msgpack_restore(p.read_bytes())
        meta = json.loads(raw["meta"])
        state = raw["state"]
        assert isinstance(state, bytes) and meta.get("format") == "lili-agent-1"
    except Exception:
        raise CheckpointError(f"{str(p)!r} is corrupt or not a lili agent file") from None
    return meta, state


class Oracle(SAC):
    """SAC on :class:`~lili.envs.OracleObservation`: it sees the partner's true strategy.

    Because the first observation of interaction i+1 carries z^{i+1} and the critic bootstraps
    across the boundary, the Oracle can learn to influence too: it bounds LILI from above.
    """

    algo = "oracle"

    def _wrap(self, env: gym.Env) -> gym.Env:
        from lili.envs.wrappers import OracleObservation

        return env if isinstance(env, OracleObservation) else OracleObservation(env)
