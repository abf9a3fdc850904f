"""The Stable-Baselines3-style facade every agent shares: ``Agent(env).learn(n).save(path)``.

:class:`AgentFacade` owns an agent's state and, once it learns, the stream of interactions the
training loop plays (:class:`lili.train.Stream`); its maths is a core of pure functions
(:class:`lili.agents.core.SACCore` or a subclass, ``agent.core``). It checks the user's env,
config and seed, acts (``predict``), and saves and loads itself (msgpack, no pickle; the
format tag and the reader are :mod:`lili.agents.registry`'s, beside ``load_agent``).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import flax.serialization
import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces

import lili
from lili.agents.base import (
    ActingState,
    AgentState,
    CheckpointError,
    check_seed,
    env_horizon,
)
from lili.agents.core import SACCore
from lili.agents.registry import AGENT_FORMAT, agent_options, check_config, load_agent
from lili.buffer import InteractionBuffer
from lili.config import AgentConfig

__all__ = ["AgentFacade", "to_bounds"]

def _as_config(config: Any) -> AgentConfig:
    if config is None:
        return AgentConfig()
    if isinstance(config, dict):
        return AgentConfig.from_dict(config)
    if not isinstance(config, AgentConfig):
        raise ValueError(f"config={config!r} is invalid; allowed: an AgentConfig, a dict of its "
                         "fields, or None (the defaults)")
    return config


def _as_env(env: Any) -> gym.Env:
    if isinstance(env, str):
        import lili.envs  # noqa: F401 - registers the ids

        try:
            return gym.make(env)
        except gym.error.Error as e:
            raise ValueError(f"env {env!r} could not be made: {e}") from None
    if not isinstance(env, gym.Env):
        raise ValueError(f"env={env!r} is invalid; allowed: a gymnasium.Env or a registered env "
                         "id such as 'lili/PointMass-v0'")
    return env


def to_bounds(a: Any, low: Any, high: Any) -> Any:
    """An action in [-1, 1] mapped to the bounds [low, high] (NumPy or JAX arrays; the one
    home of the mapping, also for the jitted loop of :mod:`lili.jax_train`)."""
    return low + (a + 1.0) * 0.5 * (high - low)


class AgentFacade:
    """An agent as a user holds it (the base of every agent; :class:`lili.agents.sac.SAC` with
    the plain SAC core is the simplest).

    ``Agent(env, config=None, seed=0)`` with a Gymnasium env (or a registered id; continuous Box
    actions, flat Box observations, a known interaction length) and an :class:`AgentConfig`;
    then ``learn(n_interactions)``, ``predict(obs, state)``, ``save(path)`` and
    ``Agent.load(path, env)``. ``agent.core`` is the pure maths, ``agent.state`` the learnable
    state, ``agent.stream`` the interactions played so far (after ``learn``).
    """

    algo: ClassVar[str] = "sac"
    core_cls: ClassVar[type[SACCore]] = SACCore
    needs_strategy: ClassVar[bool] = False

    def __init__(self, env: gym.Env | str, config: AgentConfig | dict | None = None,
                 seed: int = 0) -> None:
        self.config = _as_config(config)
        check_config(self.algo, self.config)
        self.seed = check_seed(seed)
        self.env = self.wrap_env(_as_env(env))
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
        self.horizon = env_horizon(self.env)
        self.core = self._make_core()
        self.state: AgentState = self.core.init(jax.random.PRNGKey(self.seed))
        self.stream: Any = None  # a lili.train.Stream, made by learn() or a run folder
        self.trained_interactions = 0  # of a loaded agent, before any stream of its own

    def _make_core(self) -> SACCore:
        return self.core_cls(self.obs_dim, self.act_dim, self.horizon, self.config)

    def wrap_env(self, env: gym.Env) -> gym.Env:
        """``env`` as this agent observes it (the Oracles add the partner's strategy); every
        loop that plays a user's env with this agent wraps it with this first."""
        return env

    def wrap_jax_env(self, env: Any) -> Any:
        """A JAX-native env (:mod:`lili.envs.jax`) as this agent observes it, the twin of
        :meth:`wrap_env` for :mod:`lili.jax_train`."""
        return env

    # -- what the loops read ---------------------------------------------------------------------
    @property
    def boundary(self) -> str:
        return self.core.boundary

    @property
    def history(self) -> int:
        return self.core.history

    @property
    def latent_dim(self) -> int:
        return self.core.latent_dim

    @property
    def options(self) -> Any:
        """The agent's own options (``AgentConfig.extra[algo]`` as the algo's options dataclass,
        e.g. :class:`lili.agents.slac.SLACOptions`), or None for an algo without options."""
        return agent_options(self.algo, self.config)

    @property
    def num_interactions(self) -> int:
        """Interactions this agent has been trained on."""
        return self.stream.count if self.stream is not None else self.trained_interactions

    # -- acting ------------------------------------------------------------------------------
    def initial_state(self) -> ActingState:
        """The acting state at the first interaction of a sequence."""
        return self.core.initial_acting(self.state)

    def next_state(self, buffer: InteractionBuffer) -> ActingState:
        """The acting state for the interaction after the newest one in ``buffer``.

        LILI: z^{i+1} = E(tau^{i-N+1..i}) with the online encoder; SAC: no latent.
        """
        if buffer.count < 1 or not self.core.uses_latent:
            return self.initial_state()
        window = buffer.window(buffer.count - 1, self.history, self.core.window_steps)
        return self.core.next_acting(self.state, window)

    next_latent_state = next_state  # the name of earlier releases

    def scale_action(self, a: np.ndarray) -> np.ndarray:
        """Map an action in [-1, 1] (the networks' range) to the env's action bounds."""
        return to_bounds(np.asarray(a, np.float32), self.act_low, self.act_high)

    def act(self, observation: np.ndarray, state: ActingState, key: jax.Array,
            deterministic: bool) -> tuple[np.ndarray, ActingState]:
        """The network's action in [-1, 1] (what the buffer stores) and the next acting state;
        ``key`` is the interaction's (see :meth:`SACCore.act`)."""
        a, state = self.core.jit_act(self.state.actor, self.state.norm,
                                     np.asarray(observation, np.float32), state, key,
                                     deterministic=deterministic)
        return np.asarray(a), state

    def predict(
        self,
        observation: np.ndarray,
        state: ActingState | None = None,
        deterministic: bool = True,
        key: jax.Array | None = None,
    ) -> tuple[np.ndarray, ActingState]:
        """Action for ``observation`` in env units, and the acting state for the next step.

        ``state`` carries the latent, the step index and any memory of the interaction so far
        (start with :meth:`initial_state`, or None); pass the returned state back on the next
        step, and at the start of the next interaction use :meth:`next_state`.
        """
        fresh = self.initial_state()
        state = fresh if state is None else state
        shapes = jax.tree_util.tree_map(np.shape, (state.z, state.memory)) \
            if isinstance(state, ActingState) else None
        if shapes != jax.tree_util.tree_map(np.shape, (fresh.z, fresh.memory)):
            # e.g. another agent's state, or one without the history SLAC acts on.
            raise ValueError(f"state={state!r} is invalid for {self.algo}; allowed: None or the "
                             "ActingState that its initial_state(), next_state() or predict() "
                             "returned")
        obs = np.asarray(observation, np.float32)
        if obs.shape != (self.obs_dim,):
            raise ValueError(f"observation has shape {obs.shape}; expected ({self.obs_dim},)")
        key = jax.random.PRNGKey(0) if key is None else key
        a, state = self.act(obs, state, key, deterministic)
        return self.scale_action(a), state

    # -- learning --------------------------------------------------------------------------
    def fit_normaliser(self, buffer: InteractionBuffer) -> None:
        """Fit the input and decoder-target statistics on ``buffer`` (the warm-up)."""
        self.state = self.core.fit_normaliser(self.state, buffer)

    def train_block(self, buffer: InteractionBuffer, key: jax.Array) -> dict[str, float]:
        """Run one fused block of updates on ``buffer``; return its mean metrics."""
        self.state, metrics = self.core.learn_block(self.state, buffer, key)
        return metrics

    def learn(self, n_interactions: int, progress: bool = False,
              callback: Callable[[dict[str, Any]], bool | None] | None = None) -> AgentFacade:
        """Train for ``n_interactions`` more interactions on ``self.env`` (see ``lili.train``).

        ``callback(row)`` gets each interaction's metrics row; returning ``False`` stops
        training after that interaction, as in Stable-Baselines3."""
        from lili.train import Stream, train

        # train() attaches the stream to the agent (one place does).
        stream = self.stream if self.stream is not None else Stream.for_agent(self, self.env)
        train(self, stream, n_interactions, progress=progress, callback=callback)
        return self

    # -- persistence -------------------------------------------------------------------------
    def _meta(self) -> dict[str, Any]:
        return {
            "format": AGENT_FORMAT,
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
        want = jax.tree_util.tree_map(np.shape, self.state)
        got = jax.tree_util.tree_map(np.shape, restored)
        if want != got:
            raise CheckpointError(
                f"{source} does not match this agent: parameter shapes differ "
                f"(saved for another env or network size?)"
            )
        leaves = jax.tree_util.tree_leaves(restored)
        if not all(np.all(np.isfinite(x)) for x in leaves
                   if np.issubdtype(np.asarray(x).dtype, np.floating)):
            raise CheckpointError(f"{source} holds non-finite (NaN or inf) parameters")
        self.state = jax.tree_util.tree_map(jnp.asarray, restored)

    def save(self, path: str | Path) -> Path:
        """Save the agent (parameters, optimiser states, config) to ``path`` (msgpack, no pickle).

        The replay buffer is not included (as in Stable-Baselines3); run folders' checkpoints
        keep the stream apart for resuming.
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
    def load(cls, path: str | Path, env: gym.Env | str) -> AgentFacade:
        """Load an agent saved by :meth:`save` for ``env``; CheckpointError if it does not fit."""
        agent = load_agent(path, env)
        # Exactly this class: LILI subclasses SAC, so SAC.load of a LILI file would otherwise
        # return a LILI without a word (AgentFacade.load takes any agent, as load_agent does).
        if not isinstance(agent, cls) or (cls is not AgentFacade and type(agent) is not cls):
            raise CheckpointError(
                f"{path} holds a {agent.algo!r} agent, not a {cls.__name__} "
                "(lili.agents.load_agent picks the class from the file)"
            )
        return agent

    def check_meta(self, meta: dict, source: str) -> None:
        """CheckpointError unless a saved agent's meta fits this agent's env."""
        for key in ("obs_dim", "act_dim", "horizon"):
            if meta.get(key) != getattr(self, key):
                raise CheckpointError(
                    f"{source} was saved for an env with {key}={meta.get(key)}; this env has "
                    f"{key}={getattr(self, key)}"
                )
