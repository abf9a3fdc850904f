"""The one training loop for every algorithm.

For each interaction: act with the current latent (uniform random actions during warm-up), store
the interaction, start the next one (its first observation is the boundary target's next state),
run one fused block of gradient updates, compute the next latent, log, and checkpoint.

Randomness is derived from (seed, interaction index) rather than carried along, so a run resumed
from a checkpoint draws exactly the numbers an uninterrupted run draws.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import jax
import numpy as np

from lili.agents.sac import LatentState

if TYPE_CHECKING:
    from lili.agents.sac import SAC

__all__ = ["train", "rollout", "Interaction"]


class Interaction(dict):
    """One finished interaction: ``traj`` arrays and its per-interaction metrics."""


def rollout(
    env: gym.Env,
    obs: np.ndarray,
    info: dict[str, Any],
    act: Callable[[np.ndarray, int], np.ndarray],
    to_env: Callable[[np.ndarray], np.ndarray],
    horizon: int,
) -> Interaction:
    """Play one interaction from its first observation; ``act(obs, t)`` returns an action in
    [-1, 1] and ``to_env`` maps it to the env's bounds.
    """
    obs_l, act_l, rew_l, nxt_l = [], [], [], []
    success = None
    for t in range(horizon + 1):
        if t == horizon:
            from lili.envs.checker import EnvContractError

            raise EnvContractError(
                f"the interaction did not end within the env's horizon ({horizon} steps): "
                "a RepeatedInteractionEnv must terminate or truncate by then"
            )
        a = np.asarray(act(obs, t), np.float32)
        nxt, r, terminated, truncated, step_info = env.step(to_env(a))
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
    k = jax.random.fold_in(jax.random.PRNGKey(seed), i)
    return tuple(jax.random.split(k))  # type: ignore[return-value]


def train(
    agent: SAC,
    n_interactions: int,
    progress: bool = False,
    callback: Callable[[dict[str, Any]], None] | None = None,
    logger: Any = None,
) -> list[dict[str, Any]]:
    """Train ``agent`` on ``agent.env`` for ``n_interactions`` more interactions.

    ``callback(row)`` is called after every interaction with its metrics row; ``logger`` (a
    :class:`lili.runs.RunLogger`) writes the run folder and checkpoints. Returns the rows.
    """
    if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
            or n_interactions < 0:
        raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an integer >= 0")
    env, cfg = agent.env, agent.config
    obs, info = agent.pending_start()
    state = agent.current_latent_state()
    start = agent.num_interactions
    end = start + int(n_interactions)
    rows: list[dict[str, Any]] = []
    recent: deque[float] = deque(maxlen=20)
    t0 = time.perf_counter() - agent.wall_time

    bar = None
    if progress:
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
        task = bar.add_task(f"{agent.algo}", total=end, completed=start, stats="")
        bar.start()
    try:
        for i in range(start, end):
            act_key, upd_key = interaction_keys(agent.seed, i)
            if i < cfg.warmup_interactions:
                rng = np.random.default_rng([agent.seed, i])

                def act(o, t, rng=rng):
                    return rng.uniform(-1.0, 1.0, agent.act_dim)
            else:
                def act(o, t, key=act_key, z=state.z):
                    s = LatentState(z, t)
                    return agent.policy_action(o, s, jax.random.fold_in(key, t), False)

            done = rollout(env, obs, info, act, agent.scale_action, agent.horizon)
            obs, info = env.reset()
            agent.record(done["traj"], obs, info)
            metrics: dict[str, float] = {}
            if i + 1 >= cfg.warmup_interactions:
                if i + 1 == cfg.warmup_interactions:
                    agent.fit_normaliser()
                metrics = agent.train_block(upd_key)
            state = agent.current_latent_state()
            agent.wall_time = time.perf_counter() - t0
            row = {
                "interaction": i,
                "return": done["ret"],
                "length": done["length"],
                "success": done["success"],
                "strategy": done["strategy"],
                "strategy_id": done["strategy_id"],
                **metrics,
                "wall_time": agent.wall_time,
            }
            rows.append(row)
            recent.append(done["ret"])
            if callback is not None:
                callback(row)
            if logger is not None:
                logger.log(row, agent)
            if bar is not None:
                stats = f"return(20) {np.mean(recent):8.3f}"
                if done["success"] is not None:
                    stats += f"  success {int(done['success'])}"
                bar.update(task, completed=i + 1, stats=stats)
    finally:
        if bar is not None:
            bar.stop()
    return rows


def replay(agent: SAC) -> tuple[np.ndarray, dict[str, Any]]:
    """Bring ``agent.env`` to the start of interaction ``len(agent.action_log)``.

    Restarts the sequence with ``reset(seed=agent.seed)`` and replays the logged actions. The
    env contract makes this exact (``reset(seed)`` replays the same sequence for the same
    actions); the stored transitions are compared on the way, so an env that breaks the
    contract fails loudly instead of resuming to different numbers.
    """
    from lili.agents.sac import CheckpointError

    env = agent.env
    obs, info = env.reset(seed=agent.seed)
    buf = agent.buffer
    for i, acts in enumerate(agent.action_log):
        for t, a in enumerate(acts):
            obs, _, terminated, truncated, _ = env.step(agent.scale_action(a))
            if (terminated or truncated) != (t == len(acts) - 1):
                raise CheckpointError(
                    f"replaying interaction {i} to resume: the env ended it after {t + 1} steps, "
                    f"the log after {len(acts)}; the env is not deterministic under reset(seed)"
                )
        if i > buf.count - 1 - buf.capacity:
            stored = buf.arrays["next_obs"][i % buf.capacity, len(acts) - 1]
            if not np.allclose(stored, obs, atol=1e-5):
                raise CheckpointError(
                    f"replaying interaction {i} to resume gave a different final observation "
                    f"than the checkpoint; the env is not deterministic under reset(seed)"
                )
        obs, info = env.reset()
    return obs, info
