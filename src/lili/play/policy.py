"""The one adapter between the play page and the agent API (lili.agents, lili.buffer).

Everything the page needs from a trained blocker goes through :class:`Blocker` (shared by all
connections: it holds the parameters) and :class:`BlockerGame` (one per game: the acting state
and the buffer of finished interactions). The latent is updated exactly as in training and in
``lili.evaluate``: z^1 = 0, and after interaction i ends, z^{i+1} = E(tau^i) with
``agent.next_state(buffer)`` on an InteractionBuffer holding the finished interactions.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["Blocker", "BlockerGame", "ScriptedBlocker", "ScriptedGame", "SHIPPED_AGENT",
           "agent_file_for_run", "make_play_env", "train_and_save", "interaction_steps"]

SHIPPED_AGENT = Path(__file__).with_name("agents") / "air_hockey.msgpack"


def agent_file_for_run(run: str | Path) -> tuple[Path, dict[str, Any]]:
    """The newest checkpoint's agent file of a run folder and the run's resolved config.

    Raises ValueError naming the folder when it is not a run folder or has no checkpoint.
    """
    from lili.runs import latest_checkpoint, read_run_config

    cfg = read_run_config(run)
    ck, _ = latest_checkpoint(run)
    return ck / "agent.msgpack", cfg


class Blocker:
    """A trained agent acting as the air hockey blocker (deterministic actions, no learning)."""

    def __init__(self, agent: Any, source: str) -> None:
        self.agent = agent
        self.source = source
        self.algo: str = agent.algo
        self.latent_dim: int = int(agent.latent_dim)
        self.interactions: int = int(agent.num_interactions)

    @classmethod
    def load(cls, path: str | Path, env: gym.Env) -> Blocker:
        """Load a saved agent for ``env``; ValueError (CheckpointError) when it does not fit."""
        from lili.agents import load_agent
        from lili.envs.wrappers import OracleObservation

        agent = load_agent(path, env)
        if isinstance(agent.env, OracleObservation):
            # The Oracle is told the mode of the shot it is blocking, which a person's shot
            # reveals to nobody before it is played; the last-interaction Oracle is told only
            # the last shot's, which the session knows, so it may play.
            raise ValueError(f"{path} holds an {agent.algo!r} agent, told each shot's mode "
                             "before it is played, which a person's shot does not reveal; "
                             "allowed: every algo but oracle")
        return cls(agent, str(path))

    def wrap(self, env: gym.Env) -> gym.Env:
        """The env the agent acts on, built around the play env (the last-interaction Oracle
        appends the last shot; the others act on the env itself)."""
        return self.agent.wrap_env(env)

    def new_game(self) -> BlockerGame:
        """Acting state for a fresh sequence of interactions (z^1 = 0)."""
        return BlockerGame(self)


class BlockerGame:
    """One game's acting state: call :meth:`act` each step, :meth:`observe` after it, and
    :meth:`end_interaction` when the shot is over."""

    def __init__(self, blocker: Blocker) -> None:
        from lili.buffer import InteractionBuffer

        agent = blocker.agent
        self.agent = agent
        history = int(getattr(agent, "history", 1) or 1)
        self.buffer = InteractionBuffer(max(2, history + 1), agent.horizon, agent.obs_dim,
                                        agent.act_dim)
        self._next = agent.initial_state()
        self._acting = self._next
        self._traj: dict[str, list] = {k: [] for k in ("obs", "act", "rew", "next_obs")}

    @property
    def latent(self) -> np.ndarray:
        """The latent the agent will act with in the next (or current) interaction."""
        return np.asarray(self._next.z, np.float32)

    def begin(self, info: dict[str, Any]) -> None:
        """The interaction's first info; a learned blocker is never told the striker's mode."""

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The action for ``obs`` in env units."""
        if not self._traj["obs"]:
            self._acting = self._next
        action, self._acting = self.agent.predict(obs, self._acting, deterministic=True)
        a = np.asarray(action, np.float32)
        # The buffer holds actions in the networks' [-1, 1] range, as the training loop stores.
        low, high = self.agent.act_low, self.agent.act_high
        self._traj["obs"].append(np.asarray(obs, np.float32))
        self._traj["act"].append(2.0 * (a - low) / (high - low) - 1.0)
        return a

    def observe(self, reward: float, next_obs: np.ndarray) -> None:
        """Record the step's reward and next observation."""
        self._traj["rew"].append(float(reward))
        self._traj["next_obs"].append(np.asarray(next_obs, np.float32))

    def end_interaction(self, next_first_obs: np.ndarray) -> np.ndarray:
        """Store the finished interaction and move to z^{i+1} = E(tau^i); return it.

        ``next_first_obs`` only feeds the training target's bootstrap, never the latent.
        """
        traj = {k: np.asarray(v, np.float32) for k, v in self._traj.items()}
        self.buffer.add(traj, np.asarray(next_first_obs, np.float32))
        self._next = self.agent.next_state(self.buffer)
        self._traj = {k: [] for k in self._traj}
        return self.latent


class ScriptedBlocker:
    """A scripted blocker of :mod:`lili.envs.air_hockey.scripted` in the learned blocker's place.

    The scripted blockers that are *told* the shot's mode (``greedy``, ``crossing``,
    ``influencer``) read it from the interaction's first info, which in a play session is the
    mode the shot is recorded as (lapses included). Against a striker with aim noise they give
    the ceiling of any blocker that sees what the learned one sees (its paddle and the puck's
    position along the table, never the puck's lateral position): knowing the mode leaves
    only the aim noise to miss on.
    """

    def __init__(self, name: str, bank_shots: bool = True, seed: int = 0) -> None:
        from lili.envs.air_hockey.scripted import BLOCKERS

        if name not in BLOCKERS:
            raise ValueError(f"scripted blocker {name!r} is unknown; allowed: "
                             f"{', '.join(BLOCKERS)}")
        self.name, self.bank_shots, self.seed = name, bool(bank_shots), int(seed)
        self.algo = f"scripted-{name}"
        self.source = f"lili.envs.air_hockey.scripted ({name})"
        self.latent_dim = 0
        self.interactions = 0

    def wrap(self, env: gym.Env) -> gym.Env:
        """The env the blocker plays on, built around the play env (the predictor reads the
        last shot's mode and side from ``LastInteractionObservation``)."""
        from lili.envs.air_hockey.scripted import blocker_env

        return blocker_env(self.name, env)

    def new_game(self) -> ScriptedGame:
        from lili.envs.air_hockey.scripted import make_blocker

        return ScriptedGame(make_blocker(self.name, self.seed, self.bank_shots))


class ScriptedGame:
    """One game of a :class:`ScriptedBlocker` (the :class:`BlockerGame` protocol)."""

    latent = np.zeros(0, np.float32)

    def __init__(self, policy: Any) -> None:
        self.policy = policy
        self.info: dict[str, Any] = {}

    def begin(self, info: dict[str, Any]) -> None:
        """Keep the interaction's first info: the told blockers read the mode from it."""
        self.info = dict(info)

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.asarray(self.policy(np.asarray(obs, np.float32), self.info), np.float32)

    def observe(self, reward: float, next_obs: np.ndarray) -> None:
        """A scripted blocker keeps nothing of the interaction."""

    def end_interaction(self, next_first_obs: np.ndarray) -> np.ndarray:
        return self.latent


def interaction_steps(env: gym.Env, game: BlockerGame, obs: np.ndarray
                      ) -> Iterator[tuple[int, float, bool, dict[str, Any]]]:
    """Play one interaction from its first observation ``obs`` with the blocker; after every
    step yield ``(t, reward, done, info)``. The caller ends the interaction in ``game``."""
    t, done = 0, False
    while not done:
        action = game.act(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        game.observe(reward, obs)
        t += 1
        done = bool(terminated or truncated)
        yield t, float(reward), done, info


def train_and_save(algo: str, interactions: int, seed: int, out: str | Path,
                   env_kwargs: dict[str, Any] | None = None,
                   config: dict[str, Any] | None = None, progress: bool = False) -> Path:
    """Train ``algo`` on air hockey for ``interactions`` and save the agent file to ``out``."""
    import lili.envs  # noqa: F401 - registers the ids
    from lili.agents import make_agent

    env = gym.make("lili/AirHockey-v0", **(env_kwargs or {}))
    agent = make_agent(algo, env, config, seed)
    agent.learn(interactions, progress=progress)
    return agent.save(out)


def make_play_env(env_kwargs: dict[str, Any]) -> gym.Env:
    """The air hockey env of training with ``env_kwargs`` (ValueError when they do not fit)."""
    import lili.envs  # noqa: F401 - registers the ids

    try:
        return gym.make("lili/AirHockey-v0", **env_kwargs)
    except TypeError as e:
        raise ValueError(f"air hockey does not accept the env kwargs {env_kwargs}: {e}") from None
