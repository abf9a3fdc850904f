"""The one training loop for every algorithm, and the stream of interactions it owns.

For each interaction: act with the acting state (uniform random actions during warm-up), store
the interaction, start the next one (its first observation is the boundary target's next state),
run one fused block of gradient updates, compute the next acting state, log, and checkpoint.

The :class:`Stream` (env, buffer, action log, pending first observation, counters) belongs to
the loop, not to the agent: the agent is its learnable state and pure functions of it.
Randomness is derived from (seed, interaction index) rather than carried along, so a run resumed
from a checkpoint draws exactly the numbers an uninterrupted run draws.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import jax
import numpy as np

from lili.agents.base import ActingState, Agent, CheckpointError
from lili.buffer import InteractionBuffer
from lili.env_calls import env_reset, env_step, where
from lili.metrics_file import plays_at_random

__all__ = ["train", "rollout", "Interaction", "Stream", "NonFiniteError", "interaction_keys",
           "run_interaction_keys", "plays_at_random"]


class NonFiniteError(ValueError):
    """Training met a NaN or inf (observation, reward or loss) and stopped."""


class Interaction(dict):
    """One finished interaction: ``traj`` arrays and its per-interaction metrics."""


ActFn = Callable[[np.ndarray, ActingState], tuple[np.ndarray, ActingState]]


def rollout(
    env: gym.Env,
    obs: np.ndarray,
    info: dict[str, Any],
    act: ActFn,
    acting: ActingState,
    to_env: Callable[[np.ndarray], np.ndarray],
    horizon: int,
    index: int | None = None,
) -> Interaction:
    """Play one interaction from its first observation.

    ``act(obs, acting)`` returns an action in [-1, 1] and the next acting state, which is what
    the next step receives; ``to_env`` maps actions to the env's bounds. ``index`` (the
    interaction's number) is named in an :class:`lili.env_calls.EnvError` when the env fails.
    """
    obs_l, act_l, rew_l, nxt_l = [], [], [], []
    success = None
    for t in range(horizon + 1):
        if t == horizon:
            from lili.envs.checker import EnvContractError

            raise EnvContractError(
                f"the interaction did not end within the env's horizon ({horizon} steps): "
                "an env must terminate or truncate its episodes by then"
            )
        a, acting = act(obs, acting)
        a = np.asarray(a, np.float32)
        nxt, r, terminated, truncated, step_info = env_step(env, to_env(a), where(index, t))
        obs_l.append(obs)
        act_l.append(a)
        rew_l.append(r)
        nxt_l.append(nxt)
        obs = nxt
        if terminated or truncated:
            success = step_info.get("success")
            break
    traj = {
        "obs": np.asarray(obs_l, np.float32),
        "act": np.asarray(act_l, np.float32),
        "rew": np.asarray(rew_l, np.float32),
        "next_obs": np.asarray(nxt_l, np.float32),
    }
    strategy = np.asarray(info.get("strategy", np.zeros(0)), np.float32).ravel()
    return Interaction(
        traj=traj,
        ret=float(np.sum(rew_l)),
        length=len(rew_l),
        success=None if success is None else bool(success),
        strategy=strategy,
        strategy_id=int(info.get("strategy_id", -1)),
    )


def interaction_keys(seed: int, i: int) -> tuple[jax.Array, jax.Array]:
    """(acting key, update key) of interaction ``i``."""
    return run_interaction_keys(jax.random.PRNGKey(seed), i)


def run_interaction_keys(root: jax.Array, i: Any) -> tuple[jax.Array, jax.Array]:
    """(acting key, update key) of interaction ``i`` of the run whose root key is ``root``
    (``PRNGKey(seed)``); pure JAX, so a jitted loop derives them as :func:`interaction_keys`."""
    k = jax.random.fold_in(root, i)
    return tuple(jax.random.split(k))  # type: ignore[return-value]


class Stream:
    """The stream of interactions one training run plays: env, replay buffer, action log,
    the pending first observation of the next interaction, and the wall and CPU time so far.

    ``count`` interactions have been played. A fresh stream starts the env's sequence with
    ``reset(seed=seed)``; a restored one (:meth:`load_state_dict`) replays its logged actions
    first (:meth:`replay`) so the env is where it was.
    """

    def __init__(self, env: gym.Env, buffer: InteractionBuffer, seed: int,
                 to_env: Callable[[np.ndarray], np.ndarray]) -> None:
        self.env, self.buffer, self.seed, self.to_env = env, buffer, int(seed), to_env
        self.action_log: list[np.ndarray] = []
        self.pending: tuple[np.ndarray, dict[str, Any]] | None = None
        self.wall_time = 0.0
        # CPU-seconds of the processes that trained it (all threads); NaN when a checkpoint
        # from before it was kept resumed the run. Costs are estimated from it, because wall
        # time depends on what else shares the machine.
        self.cpu_time = 0.0

    @classmethod
    def for_agent(cls, agent: Agent, env: gym.Env) -> Stream:
        """A fresh stream sized for ``agent`` on ``env`` (already wrapped as the agent needs)."""
        buffer = InteractionBuffer(agent.config.buffer_capacity, agent.horizon, agent.obs_dim,
                                   agent.act_dim)
        return cls(env, buffer, agent.seed, agent.scale_action)

    @property
    def count(self) -> int:
        return self.buffer.count

    def start(self) -> tuple[np.ndarray, dict[str, Any]]:
        """First observation and info of the next interaction to play."""
        if self.pending is None:
            self.pending = self.replay()
        return self.pending

    def record(self, traj: dict[str, np.ndarray], next_obs: np.ndarray,
               next_info: dict[str, Any]) -> None:
        """Store a finished interaction and the start of the next one."""
        self.buffer.add(traj, next_obs)
        self.action_log.append(traj["act"])
        self.pending = (next_obs, next_info)

    def replay(self) -> tuple[np.ndarray, dict[str, Any]]:
        """Bring the env to the start of interaction ``len(action_log)``.

        Restarts the sequence with ``reset(seed)`` and replays the logged actions. The env
        contract makes this exact (``reset(seed)`` replays the same sequence for the same
        actions); the stored transitions are compared on the way, so an env that breaks the
        contract fails loudly instead of resuming to different numbers.
        """
        obs, info = env_reset(self.env, where(0), seed=self.seed)
        buf = self.buffer
        for i, acts in enumerate(self.action_log):
            for t, a in enumerate(acts):
                obs, _, terminated, truncated, _ = env_step(self.env, self.to_env(a),
                                                            where(i, t))
                if (terminated or truncated) != (t == len(acts) - 1):
                    raise CheckpointError(
                        f"replaying interaction {i} to resume: the env ended it after {t + 1} "
                        f"steps, the log after {len(acts)}; the env is not deterministic under "
                        "reset(seed)"
                    )
            if buf.stored(i) and not np.allclose(buf.last_next_obs(i), obs, atol=1e-5):
                raise CheckpointError(
                    f"replaying interaction {i} to resume gave a different final observation "
                    f"than the checkpoint; the env is not deterministic under reset(seed)"
                )
            obs, info = env_reset(self.env, where(i + 1))
        return obs, info

    def state_dict(self) -> dict[str, np.ndarray]:
        """The stream's part of a checkpoint: buffer arrays, action log, wall and CPU time."""
        horizon, act_dim = self.buffer.horizon, self.buffer.act_dim
        lengths = np.array([len(a) for a in self.action_log], np.int32)
        acts = np.zeros((len(lengths), horizon, act_dim), np.float32)
        for j, a in enumerate(self.action_log):
            acts[j, : len(a)] = a
        d = {f"buffer.{k}": v for k, v in self.buffer.state_dict().items()}
        d.update(actions=acts, lengths=lengths, wall_time=np.array(self.wall_time),
                 cpu_time=np.array(self.cpu_time))
        return d

    def load_state_dict(self, d: dict[str, np.ndarray], source: str = "checkpoint") -> None:
        """Restore :meth:`state_dict`; CheckpointError naming ``source`` when it does not fit."""
        try:
            self.buffer.load_state_dict({k[len("buffer."):]: v for k, v in d.items()
                                         if k.startswith("buffer.")})
            acts, lengths = d["actions"], d["lengths"]
            wall = float(d["wall_time"])
            cpu = float(d["cpu_time"]) if "cpu_time" in d else float("nan")
        except (KeyError, ValueError, TypeError) as e:
            raise CheckpointError(f"{source} has a corrupt stream (buffer or action log): {e}") \
                from None
        if len(lengths) != self.buffer.count or acts.shape[1:] != (self.buffer.horizon,
                                                                   self.buffer.act_dim):
            raise CheckpointError(f"{source} is inconsistent: its buffer holds "
                                  f"{self.buffer.count} interactions, its action log "
                                  f"{len(lengths)}")
        self.action_log = [acts[j, :n].copy() for j, n in enumerate(lengths)]
        self.wall_time, self.cpu_time = wall, cpu
        self.pending = None


def _check_finite(i: int, traj: dict[str, np.ndarray], next_obs: np.ndarray,
                  metrics: dict[str, float]) -> None:
    if not np.all(np.isfinite(traj["obs"][0])):
        raise NonFiniteError(f"interaction {i}: the env's reset() returned a non-finite "
                             "observation; training stopped (the env must return finite values)")
    bad_obs = ~np.isfinite(traj["next_obs"]).all(-1)
    bad_rew = ~np.isfinite(traj["rew"])
    if bad_obs.any() or bad_rew.any():
        step = int(np.argmax(bad_obs | bad_rew))
        what = "observation" if bad_obs[step] else "reward"
        raise NonFiniteError(f"interaction {i}, step {step}: the env returned a non-finite "
                             f"{what}; training stopped (the env must return finite values)")
    if not np.all(np.isfinite(next_obs)):
        raise NonFiniteError(f"interaction {i + 1}: the env's reset() returned a non-finite "
                             "observation; training stopped")
    bad = sorted(k for k, v in metrics.items() if not np.isfinite(v))
    if bad:
        raise NonFiniteError(f"interaction {i}: the update gave non-finite {', '.join(bad)}; "
                             "training stopped (lower the learning rates, or check the env's "
                             "reward scale)")


def _progress_bar(algo: str, start: int, end: int):
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    bar = Progress(TextColumn("[bold]{task.description}"), BarColumn(),
                   MofNCompleteColumn(), TextColumn("{task.fields[stats]}"),
                   TimeRemainingColumn(), transient=False)
    task = bar.add_task(algo, total=end, completed=start, stats="")
    return bar, task


def train(
    agent: Any,
    stream: Stream,
    n_interactions: int,
    progress: bool = False,
    callback: Callable[[dict[str, Any]], bool | None] | None = None,
    logger: Any = None,
) -> list[dict[str, Any]]:
    """Train ``agent`` on ``stream`` for ``n_interactions`` more interactions.

    ``callback(row) -> bool | None`` is called after every interaction (after the logger
    has written it) with its metrics row: ``interaction``, ``return``, ``length``,
    ``success`` (None where the env reports none), ``random`` (whether it was played with
    uniform random actions, :func:`plays_at_random`), ``strategy``, ``strategy_id``, the losses
    of the interaction's update once learning has started (``critic_loss``, ``actor_loss``,
    ``alpha``, ...) and ``wall_time``. Returning ``False`` stops training after that
    interaction, as a Stable-Baselines3 callback does; None (no return) or True goes on.
    ``logger`` (a :class:`lili.runs.RunLogger`) writes the run folder and checkpoints.
    Returns the rows of the interactions played.
    Stops with :class:`NonFiniteError` at the first NaN or inf in an observation, a reward or a
    loss, before that interaction is logged or checkpointed (the last checkpoint stays good).
    """
    if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
            or n_interactions < 0:
        raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an integer >= 0")
    env, cfg, buf = stream.env, agent.config, stream.buffer
    # The agent's record of how long it trained (what it saves) is the stream it trains on.
    agent.stream = stream
    obs, info = stream.start()
    acting = agent.next_state(buf)
    start = stream.count
    end = start + int(n_interactions)
    rows: list[dict[str, Any]] = []
    recent: deque[float] = deque(maxlen=20)
    t0 = time.perf_counter() - stream.wall_time
    c0 = time.process_time() - stream.cpu_time

    bar = task = None
    if progress:
        bar, task = _progress_bar(agent.algo, start, end)
        bar.start()
    try:
        for i in range(start, end):
            act_key, upd_key = interaction_keys(agent.seed, i)
            at_random = plays_at_random(agent.seed, i, cfg.warmup_interactions,
                                        cfg.random_interactions)
            if at_random:
                rng = np.random.default_rng([agent.seed, i])

                def act(o, s, rng=rng):
                    return rng.uniform(-1.0, 1.0, agent.act_dim), s
            else:
                def act(o, s, key=act_key):
                    return agent.act(o, s, key, False)

            done = rollout(env, obs, info, act, acting, agent.scale_action, agent.horizon, i)
            obs, info = env_reset(env, where(i + 1))
            metrics: dict[str, float] = {}
            _check_finite(i, done["traj"], obs, metrics)
            stream.record(done["traj"], obs, info)
            if i + 1 >= cfg.warmup_interactions:
                if i + 1 == cfg.warmup_interactions:
                    agent.fit_normaliser(buf)
                metrics = agent.train_block(buf, upd_key)
                _check_finite(i, done["traj"], obs, metrics)
            acting = agent.next_state(buf)
            stream.wall_time = time.perf_counter() - t0
            stream.cpu_time = time.process_time() - c0
            row = {
                "interaction": i,
                "return": done["ret"],
                "length": done["length"],
                "success": done["success"],
                "random": at_random,
                "strategy": done["strategy"],
                "strategy_id": done["strategy_id"],
                **metrics,
                "wall_time": stream.wall_time,
            }
            rows.append(row)
            recent.append(done["ret"])
            if logger is not None:
                logger.log(row, agent, stream)
            if callback is not None and callback(row) is False:
                break
            if bar is not None:
                stats = f"return(20) {np.mean(recent):8.3f}"
                if done["success"] is not None:
                    stats += f"  success {int(done['success'])}"
                bar.update(task, completed=i + 1, stats=stats)
    finally:
        if bar is not None:
            bar.stop()
    return rows
