"""What every agent shares, as a leaf module: the typed state, the acting state, the agent
protocol, the checkpoint error and the checks of a user's env and seed.

Nothing here imports another ``lili.agents`` module, and the training loop, evaluation, run
folders and the play page depend on this module rather than on a concrete agent.
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol, runtime_checkable

import flax.struct
import jax
import jax.numpy as jnp
import numpy as np

from lili.config import MAX_SEED, check_seed
from lili.envs.core import env_horizon

__all__ = ["ActingState", "AgentState", "Normaliser", "CheckpointError", "Agent", "Params",
           "check_seed", "env_horizon", "MAX_SEED"]

Params = Any
"""A Flax parameter tree (nested dicts of arrays)."""

class CheckpointError(ValueError):
    """A checkpoint or saved agent is corrupt or does not match the agent or env."""


@flax.struct.dataclass
class Normaliser:
    """Standardisation of observations, state changes and rewards (identity until fitted).

    The one place where ``(x - mean) / std`` is written.
    """

    obs_mean: jax.Array
    obs_std: jax.Array
    delta_mean: jax.Array
    delta_std: jax.Array
    rew_mean: jax.Array
    rew_std: jax.Array

    @classmethod
    def identity(cls, obs_dim: int) -> Normaliser:
        zeros, ones = jnp.zeros(obs_dim, jnp.float32), jnp.ones(obs_dim, jnp.float32)
        return cls(zeros, ones, zeros, ones, jnp.zeros((), jnp.float32),
                   jnp.ones((), jnp.float32))

    @classmethod
    def fit(cls, obs: np.ndarray, next_obs: np.ndarray, rew: np.ndarray) -> Normaliser:
        """Fit on flat arrays of transitions: obs and next_obs [N, od], rew [N]."""
        om, osd = _moments(np.concatenate([obs, next_obs]))
        dm, dsd = _moments(next_obs - obs)
        rm, rsd = _moments(rew[:, None])
        return cls(*(jnp.asarray(v) for v in (om, osd, dm, dsd, rm[0], rsd[0])))

    def obs(self, x: jax.Array) -> jax.Array:
        return (x - self.obs_mean) / self.obs_std

    def delta(self, obs: jax.Array, next_obs: jax.Array) -> jax.Array:
        return (next_obs - obs - self.delta_mean) / self.delta_std

    def rew(self, r: jax.Array) -> jax.Array:
        return (r - self.rew_mean) / self.rew_std


def _moments(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean, std = x.mean(0), x.std(0)
    # Constant features (e.g. a coordinate that never moved during warm-up) are left unscaled.
    return mean.astype(np.float32), np.where(std < 1e-6, 1.0, std).astype(np.float32)


@flax.struct.dataclass
class AgentState:
    """An agent's learnable state: everything a checkpoint of the agent holds.

    ``model`` holds the critic and, for latent agents, the encoder and decoder (one optimiser
    with per-part learning rates); ``target`` their Polyak-averaged copies (critic, encoder).
    ``aux`` holds what one agent adds (SLAC: its latent model and its optimiser).
    """

    actor: Params
    model: Params
    target: Params
    log_alpha: jax.Array
    opt_actor: Any
    opt_model: Any
    opt_alpha: Any
    norm: Normaliser
    updates: jax.Array
    aux: dict[str, Any] = flax.struct.field(default_factory=dict)


@flax.struct.dataclass
class ActingState:
    """What acting carries from one step to the next: the latent, the step index and any memory.

    ``z`` is the latent held for the whole interaction (empty for agents without one), ``t`` the
    step within the interaction, ``memory`` what an agent needs of the steps so far (SLAC: the
    last K-1 observations and actions). Every loop passes on the state that acting returns
    (the role Stable-Baselines3 gives ``state`` for recurrent policies).
    """

    z: jax.Array
    t: jax.Array
    memory: dict[str, jax.Array] = flax.struct.field(default_factory=dict)

    def __repr__(self) -> str:
        return f"ActingState(z={np.round(np.asarray(self.z), 3).tolist()}, t={int(self.t)})"


@runtime_checkable
class Agent(Protocol):
    """The surface the training loop, evaluation, run folders and the play page rely on."""

    algo: ClassVar[str]
    config: Any
    seed: int
    horizon: int
    history: int
    obs_dim: int
    act_dim: int

    def initial_state(self) -> ActingState: ...

    def act(self, observation: np.ndarray, state: ActingState, key: jax.Array,
            deterministic: bool) -> tuple[np.ndarray, ActingState]: ...

    def next_state(self, buffer: Any) -> ActingState: ...

    def scale_action(self, a: np.ndarray) -> np.ndarray: ...

    def wrap_env(self, env: Any) -> Any:
        """``env`` as the agent observes it (the Oracles add the partner's strategy)."""
        ...
