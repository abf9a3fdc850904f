# Over 400 lines: the one jitted program (play, store, update) and the run loop that logs it.
"""Many runs as one jitted program per interaction, on the JAX-native envs (``--backend jax``).

:class:`JaxRuns` trains K runs of one core (SAC, LILI, LILI without influence or an Oracle) on
the JAX twin of their env (:mod:`lili.envs.jax`: Point Mass with any partner, Driving (2D), the
influence suite). Where :func:`lili.many.train_many` steps K Gymnasium envs in Python, here one
interaction of all K runs is ONE call of one jitted program, mapped over the runs
(:func:`lili.agents.multiseed.over_seeds`: vmapped on an accelerator, PureJaxRL's ``make_train``
idea; one run after another inside the program on a CPU):

1. play: a ``lax.scan`` over the horizon of the core's acting step and the env's step (uniform
   random actions for the runs that play this interaction at random, as in the warm-up);
2. store: the interaction goes into the stacked replay buffers (arrays [K, capacity, ...],
   donated, so it is written in place);
3. learn: the core's update block (:meth:`lili.agents.core.SACCore.block`) once the warm-up is
   over;
4. the next acting state (LILI: z from the encoder over the newest interactions).

The maths is the core's and the buffer's: nothing here computes a loss or samples a batch. The
randomness comes from (seed, interaction), as in :func:`lili.train.train`: the agent's acting
and update keys are :func:`lili.train.interaction_keys`'s, the env's and the random actions'
another stream of the same seed. So a run's numbers do not depend on the other runs of its
group: bit for bit on a CPU, to float tolerance on an accelerator (vmapped reductions round
with the group's size). They are not the numbers
of the same seed on the Gymnasium path, whose partner draws come from NumPy's generator.

A Python loop over interactions writes each run's row to its own run folder
(:class:`lili.runs.RunLogger`: metrics.csv, TensorBoard, checkpoints, summary.json), so ``lili
report`` reads them as any other run. The one host step is the normaliser's fit at the end of
the warm-up (:meth:`~lili.agents.core.SACCore.fit_normaliser`, NumPy): that interaction takes
two calls of the program (play; fit; learn without playing), every other interaction one.

Checkpoints hold the agent and the run's interactions as ``lili train`` writes them; a group
resumes (:meth:`JaxRuns.resume`, ``lili train --backend jax --resume``) by loading them and
replaying each run's logged actions through its JAX env with the same keys.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Mapping, Sequence
from functools import partial
from types import SimpleNamespace
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from lili.agents.base import ActingState, AgentState
from lili.agents.core import SACCore
from lili.agents.facade import to_bounds
from lili.agents.multiseed import over_seeds, stack
from lili.buffer import _available_memory, _write, buffer_nbytes
from lili.many import StackedBuffers, _windows, check_group_memory
from lili.metrics_file import plays_at_random
from lili.train import NonFiniteError, Stream, _progress_bar, run_interaction_keys

__all__ = ["JAX_ALGOS", "JaxRuns", "check_jax_run", "why_not_jax"]

JAX_ALGOS = ("sac", "lili", "lili-no-influence", "oracle", "oracle-last", "lili-critic-ln",
             "lili-prediction-critic", "lili-set-encoder")
"""The algos this path trains: the generic SAC core and LILI's (their update is the shared
block), the Oracles on their observation of the JAX env (:meth:`wrap_jax_env`,
:mod:`lili.envs.jax.wrappers`), and of the contrib algos those whose core only swaps a network
or the critic's input (``lili-critic-ln``, ``lili-prediction-critic``, ``lili-set-encoder``:
the same pure functions); the other contrib algos are not checked on this path."""

# fold_in datum of the env's key stream (interaction indices stay far below it).
_ENV_STREAM = 2**31 - 1


@struct.dataclass
class _Carry:
    """What the program carries from one interaction to the next, every leaf stacked [K, ...]."""

    states: AgentState
    arrays: dict[str, jax.Array]
    counts: jax.Array
    env_state: Any
    obs: jax.Array
    acting: ActingState


def check_jax_run(algo: str, env: str) -> str:
    """The registered env id of ``env`` when ``algo`` on ``env`` can train on this path; else
    ValueError (one line naming the bad value and what is allowed)."""
    from lili.envs.core import resolve_env_id
    from lili.envs.jax import JAX_ENVS

    env_id = resolve_env_id(env)
    if env_id not in JAX_ENVS:
        raise ValueError(f"env {env!r} has no JAX version (--backend jax); allowed: "
                         f"{', '.join(JAX_ENVS)}")
    if algo not in JAX_ALGOS:
        raise ValueError(f"algo {algo!r} has no JAX-native training (--backend jax); allowed: "
                         f"{', '.join(JAX_ALGOS)}")
    return env_id


def why_not_jax(algo: str, env: str, env_kwargs: Mapping[str, Any] | None = None) -> str | None:
    """None when runs of ``algo`` on ``env`` with ``env_kwargs`` can train on this path (what
    ``lili reproduce --backend jax`` sends through it), else why not (one phrase)."""
    from lili.envs import jax as jax_envs

    try:
        env_id = check_jax_run(algo, env)
        jax_envs.make(env_id, **dict(env_kwargs or {}))
    except ValueError as e:
        return str(e).split(";")[0].replace(" (--backend jax)", "")
    return None


def _device_free() -> int | None:
    """Free bytes of the device JAX computes on (an accelerator's own memory), else the host's."""
    try:
        stats = jax.devices()[0].memory_stats()
    except Exception:  # not every backend reports memory
        stats = None
    if stats and "bytes_limit" in stats:
        return int(stats["bytes_limit"]) - int(stats.get("bytes_in_use", 0))
    return _available_memory()


def _env_reset_key(root: jax.Array) -> jax.Array:
    """The key of a run's env ``reset`` (its first strategy), from the run's root key."""
    return jax.random.split(jax.random.fold_in(root, _ENV_STREAM))[0]


def _env_keys(root: jax.Array, index: jax.Array) -> jax.Array:
    """Interaction ``index``'s env keys: its steps', its random actions' and its successor's
    start (three keys, from the run's root key)."""
    play_root = jax.random.split(jax.random.fold_in(root, _ENV_STREAM))[1]
    return jax.random.split(jax.random.fold_in(play_root, index), 3)


def _play(core: SACCore, env: Any, bounds: jax.Array, index: jax.Array, play: jax.Array,
          state: AgentState, arrays: dict[str, jax.Array], count: jax.Array, env_state: Any,
          obs: jax.Array, acting: ActingState, params: Any, root: jax.Array,
          at_random: jax.Array):
    """One run's interaction ``index``: played (one scan over the horizon) and stored in its
    buffer; with ``play`` False nothing changes (the warm-up's last interaction learns apart)."""
    act_key, _ = run_interaction_keys(root, index)
    k_steps, k_random, k_next = _env_keys(root, index)

    def step(carry, t):
        o, es, ac = carry
        a, ac = core._act_step(state.actor, state.norm, o, ac, act_key, False)
        uniform = jax.random.uniform(jax.random.fold_in(k_random, t), a.shape, jnp.float32,
                                     -1.0, 1.0)
        a = jnp.where(at_random, uniform, a)
        nxt, es, r, _, info = env.step(jax.random.fold_in(k_steps, t), es,
                                       to_bounds(a, bounds[0], bounds[1]), params)
        out = {"obs": o, "act": a, "rew": r, "next_obs": nxt, "valid": info["active"],
               "success": info.get("success", jnp.zeros((), bool)),
               "strategy": info["strategy"], "strategy_id": info["strategy_id"]}
        return (nxt, es, ac), out

    (_, end_state, _), tr = jax.lax.scan(step, (obs, env_state, acting),
                                         jnp.arange(core.horizon))
    valid = tr["valid"]
    length = valid.sum().astype(jnp.int32)
    first_obs, next_state = env.next_interaction(k_next, end_state, params)

    def masked(x: jax.Array) -> jax.Array:
        return jnp.where(valid.reshape(valid.shape + (1,) * (x.ndim - 1)), x, 0).astype(x.dtype)

    row = {"obs": masked(tr["obs"]), "act": masked(tr["act"]), "rew": masked(tr["rew"]),
           "next_obs": masked(tr["next_obs"]), "valid": valid, "length": length,
           "next_first_obs": first_obs}
    slot = jnp.mod(count, arrays["rew"].shape[0])
    old = {k: v[slot] for k, v in arrays.items()}
    arrays = _write(arrays, slot, jax.tree.map(lambda n, o: jnp.where(play, n, o), row, old))
    finite = (jnp.isfinite(row["obs"]).all() & jnp.isfinite(row["next_obs"]).all()
              & jnp.isfinite(row["rew"]).all() & jnp.isfinite(first_obs).all())
    last = jnp.maximum(length - 1, 0)
    out = {"return": row["rew"].sum(), "length": length, "success": tr["success"][last],
           "strategy": tr["strategy"][0], "strategy_id": tr["strategy_id"][0],
           "act": row["act"], "finite": finite}
    env_state = jax.tree.map(lambda n, o: jnp.where(play, n, o), next_state, env_state)
    obs = jnp.where(play, first_obs, obs)
    return arrays, count + play.astype(count.dtype), env_state, obs, out


@partial(jax.jit, static_argnums=(0, 1), donate_argnums=(2,))
def _program(core: SACCore, env: Any, carry: _Carry, params: Any, roots: jax.Array,
             bounds: jax.Array, index: jax.Array, at_random: jax.Array, play: jax.Array,
             learn: jax.Array) -> tuple[_Carry, dict[str, Any]]:
    """Interaction ``index`` of every run (module docstring): play and store (where ``play``),
    the update block (where ``learn``; a real branch, the flag being one for all runs), then
    every run's next acting state. The carry is donated: the buffers are written in place."""
    arrays, counts, env_state, obs, out = over_seeds(
        partial(_play, core, env, bounds, index, play))(
        carry.states, carry.arrays, carry.counts, carry.env_state, carry.obs, carry.acting,
        params, roots, at_random)
    upd_keys = jax.vmap(lambda r: run_interaction_keys(r, index)[1])(roots)

    def block(states):
        return over_seeds(core.block)(states, arrays, counts, upd_keys)

    def skip(states):
        shapes = jax.eval_shape(block, states)[1]
        return states, jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)

    states, metrics = jax.lax.cond(learn, block, skip, carry.states)
    if core.uses_latent:
        idx = counts[:, None] - 1 + jnp.arange(-core.history + 1, 1)[None, :]
        windows = _windows(arrays, counts, idx, core.window_steps)
        acting = over_seeds(core.next_acting)(states, windows)
    else:
        acting = over_seeds(core.initial_acting)(states)
    finite = out.pop("finite") & jnp.stack(
        [jnp.isfinite(v) for v in jax.tree.leaves(metrics)]).all(0)
    out.update(metrics=metrics, finite=finite)
    return _Carry(states=states, arrays=arrays, counts=counts, env_state=env_state, obs=obs,
                  acting=acting), out


@partial(jax.jit, static_argnums=(0, 1))
def _replay(env: Any, horizon: int, params: Any, roots: jax.Array, bounds: jax.Array,
            actions: jax.Array) -> tuple[jax.Array, Any]:
    """Every run's env brought to the start of interaction n by replaying its logged actions
    [K, n, H, ...] with the keys :func:`_play` drew them with: ``(obs, env state)``. Steps after
    an interaction's end change nothing (the JAX env's rule), so the zero padding is harmless."""

    def one(params, root, acts):
        obs, state = env.reset(_env_reset_key(root), params)

        def interaction(carry, x):
            _, state = carry
            index, acts_i = x
            k_steps, _, k_next = _env_keys(root, index)

            def step(state, t):
                a = to_bounds(acts_i[t], bounds[0], bounds[1])
                return env.step(jax.random.fold_in(k_steps, t), state, a, params)[1], None

            state, _ = jax.lax.scan(step, state, jnp.arange(horizon))
            return env.next_interaction(k_next, state, params), None

        (obs, state), _ = jax.lax.scan(interaction, (obs, state),
                                       (jnp.arange(acts.shape[0], dtype=jnp.int32), acts))
        return obs, state

    return over_seeds(one)(params, roots, actions)


class JaxRuns:
    """K runs of ``algo`` on the JAX twin of ``env``, one per seed, trained together
    (module docstring).

    ``env_kwargs``: the env's keyword arguments, one mapping for all runs or one per run (e.g.
    the noisy partner's ``step_noise`` at K sigmas: runs that share a core share a program).
    ``config``: the :class:`~lili.config.AgentConfig` (or dict) every run shares.
    ValueError, before anything is allocated, for an algo or env this path cannot train, env
    kwargs the JAX env does not take, or a group whose buffers do not fit in ``fraction`` of
    the device's free memory.
    """

    def __init__(self, algo: str, env: str, seeds: Sequence[int], config: Any = None,
                 env_kwargs: Mapping[str, Any] | Sequence[Mapping[str, Any]] | None = None,
                 fraction: float = 0.5) -> None:
        from lili.agents import check_seed, make_agent
        from lili.envs import jax as jax_envs
        from lili.envs.spec import make_env

        self.env_id = check_jax_run(algo, env)
        self.seeds = [check_seed(s) for s in seeds]
        if not self.seeds:
            raise ValueError("JaxRuns needs at least one seed")
        if len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"seeds {self.seeds[:20]} name a seed twice; allowed: distinct "
                             "seeds")
        k = len(self.seeds)
        if env_kwargs is None or isinstance(env_kwargs, Mapping):
            env_kwargs = [dict(env_kwargs or {})] * k
        self.env_kwargs = [dict(kw) for kw in env_kwargs]
        if len(self.env_kwargs) != k:
            raise ValueError(f"{k} seeds need one env kwargs mapping or {k}; got "
                             f"{len(self.env_kwargs)}")
        # Runs with the same env kwargs share one params pytree (4096 runs: one make).
        made_by: dict[str, Any] = {}
        for kw in self.env_kwargs:
            key = repr(sorted(kw.items()))
            if key not in made_by:
                made_by[key] = jax_envs.make(self.env_id, **kw)
        made = [made_by[repr(sorted(kw.items()))] for kw in self.env_kwargs]
        # The core and the action bounds are the Gymnasium agent's: one definition of both.
        self.agent = make_agent(algo, make_env(self.env_id, self.env_kwargs[0]), config,
                                self.seeds[0])
        core = self.core = self.agent.core
        # What the agent observes of the JAX env (the Oracles: the strategy appended).
        self.env = self.agent.wrap_jax_env(made[0][0])
        if tuple(self.env.observation_shape) != (core.obs_dim,):
            raise ValueError(f"{algo} observes {core.obs_dim} numbers of {self.env_id}'s "
                             f"Gymnasium env and {self.env.observation_shape} of its JAX twin; "
                             "the two must agree")
        horizons = sorted({int(p.horizon) for _, p in made})
        if horizons != [core.horizon]:
            raise ValueError(f"the runs of one group share one horizon; env kwargs give "
                             f"{horizons}, the agent's core {core.horizon}")
        cfg = self.config = self.agent.config
        each = buffer_nbytes(cfg.buffer_capacity, core.horizon, core.obs_dim, core.act_dim)
        check_group_memory(k, each, fraction, _device_free())
        self.params = jax_envs.stack([p for _, p in made])
        self.bounds = jnp.stack([jnp.asarray(self.agent.act_low),
                                 jnp.asarray(self.agent.act_high)])
        self.roots = jnp.stack([jax.random.PRNGKey(s) for s in self.seeds])
        self.stacked = StackedBuffers(k, cfg.buffer_capacity, core.horizon, core.obs_dim,
                                      core.act_dim)
        states = jax.jit(over_seeds(core.init))(self.roots)
        obs, env_state = jax.jit(over_seeds(self.env.reset))(jax.vmap(_env_reset_key)(self.roots),
                                                          self.params)
        self.carry = _Carry(states=states, arrays=self.stacked.arrays,
                            counts=jnp.zeros(k, jnp.int32), env_state=env_state, obs=obs,
                            acting=over_seeds(core.initial_acting)(states))
        self.count = 0
        self.has_success = "success" in jax.eval_shape(
            self.env.step, jax.random.PRNGKey(0), jax.tree.map(lambda x: x[0], env_state),
            jnp.zeros(self.env.action_shape, jnp.float32),
            jax.tree.map(lambda x: x[0], self.params))[4]
        self.wall_time = self.cpu_time = 0.0
        self._agents: list[Any] | None = None
        self._streams: list[Stream] | None = None

    def __len__(self) -> int:
        return len(self.seeds)

    # -- per-run views (run folders) -----------------------------------------------------------
    def streams(self) -> list[Stream]:
        """One :class:`~lili.train.Stream` per run over its slot of the stacked buffers (what a
        :class:`~lili.runs.RunLogger` checkpoints); their action logs fill while training."""
        if self._streams is None:
            self._streams = [Stream(None, self.stacked.view(j), s, self.agent.scale_action)
                             for j, s in enumerate(self.seeds)]
        return self._streams

    def agents(self) -> list[Any]:
        """One agent facade per run (the prototype's class, this run's seed and state), synced
        with the device state, each attached to its stream."""
        streams = self.streams()
        if self._agents is None:
            self._agents = []
            for s, stream in zip(self.seeds, streams, strict=True):
                a = copy.copy(self.agent)
                a.seed, a.stream = s, stream
                self._agents.append(a)
        states = self.carry.states
        for j, a in enumerate(self._agents):
            a.state = jax.tree.map(lambda x, j=j: x[j], states)
        return self._agents

    def resume(self, run_dirs: Sequence[Any], strategy_dim: int) -> int:
        """Load every run's latest checkpoint from its folder (:func:`lili.runs.resume_run`:
        agent, buffer, action log, checked against ``metrics.csv``) and bring its env to where
        the run stopped by replaying the logged actions, so that training goes on with the
        numbers of an uninterrupted run. Returns the interactions done (0: no checkpoint yet).
        CheckpointError (from the folders) or ValueError when the runs stopped at different
        interactions; nothing is written."""
        from lili.agents.base import CheckpointError
        from lili.runs import resume_run

        if self.count:
            raise ValueError("resume() restores fresh runs; these have trained already")
        agents, streams = self.agents(), self.streams()
        starts = [resume_run(d, a, s, strategy_dim)
                  for d, a, s in zip(run_dirs, agents, streams, strict=True)]
        if len(set(starts)) != 1:
            raise ValueError(f"the runs' checkpoints are at different interactions "
                             f"({sorted(set(starts))}); resume the runs of one point together")
        n = starts[0]
        if n == 0:
            return 0
        core, k = self.core, len(self)
        actions = np.zeros((k, n, core.horizon, core.act_dim), np.float32)
        for j, s in enumerate(streams):
            for i, a in enumerate(s.action_log):
                actions[j, i, :len(a)] = a
        obs, env_state = _replay(self.env, core.horizon, self.params, self.roots, self.bounds,
                                 jnp.asarray(actions))
        slot = (n - 1) % self.stacked.capacity
        stored = np.asarray(self.stacked.arrays["next_first_obs"][:, slot])
        bad = ~np.isclose(np.asarray(obs), stored, atol=1e-5).all(-1)
        if bad.any():
            j = int(np.argmax(bad))
            raise CheckpointError(f"replaying seed {self.seeds[j]}'s logged actions to resume "
                                  "gave another observation than its checkpoint; was it trained "
                                  "with other env kwargs or another version of the env?")
        states = stack([a.state for a in agents])
        self.carry = _Carry(states=states, arrays=self.stacked.arrays,
                            counts=jnp.asarray(self.stacked.counts, jnp.int32),
                            env_state=env_state, obs=obs,
                            acting=over_seeds(core.initial_acting)(states))
        self.count = n
        # The acting state the runs stopped with (z from their newest interactions).
        self._call(n - 1, np.zeros(k, bool), False, False)
        self.wall_time = max(s.wall_time for s in streams)
        self.cpu_time = float(np.mean([s.cpu_time for s in streams]))
        return n

    # -- training ------------------------------------------------------------------------------
    def _call(self, index: int, at_random: np.ndarray, play: bool, learn: bool) -> dict:
        self.carry, out = _program(self.core, self.env, self.carry, self.params, self.roots,
                                   self.bounds, jnp.int32(index), jnp.asarray(at_random),
                                   jnp.asarray(play), jnp.asarray(learn))
        self.stacked.arrays = self.carry.arrays
        return out

    def _fit_normalisers(self) -> None:
        """Every run's normaliser fitted on its warm-up, by the core's own (NumPy) fit."""
        if not self.config.normalize:
            return
        n = min(self.count, self.stacked.capacity)
        host = {k: np.asarray(self.carry.arrays[k][:, :n]) for k in
                ("valid", "obs", "next_obs", "rew")}
        states = self.carry.states
        norms = [self.core.fit_normaliser(states, SimpleNamespace(
            count=self.count, capacity=self.stacked.capacity,
            arrays={k: v[j] for k, v in host.items()})).norm for j in range(len(self))]
        self.carry = self.carry.replace(states=states.replace(norm=stack(norms)))

    def _at_random(self, i: int) -> np.ndarray:
        cfg = self.config
        if cfg.random_interactions <= 0 or i < cfg.warmup_interactions:
            return np.full(len(self), i < cfg.warmup_interactions)
        return np.array([plays_at_random(s, i, cfg.warmup_interactions, cfg.random_interactions)
                         for s in self.seeds])

    def train(self, n_interactions: int, loggers: Sequence[Any] | None = None,
              progress: bool = False, keep_rows: bool = True) -> list[list[dict]]:
        """Train every run ``n_interactions`` more interactions. ``loggers``: one
        :class:`~lili.runs.RunLogger` per run (or None), each given the run's rows as
        :func:`lili.train.train` gives them. Returns each run's rows (empty lists without
        ``keep_rows``). Stops with :class:`~lili.train.NonFiniteError` naming the run at the
        first NaN or inf, before that interaction is logged."""
        if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
                or n_interactions < 0:
            raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an "
                             "integer >= 0")
        k, cfg = len(self), self.config
        if loggers is not None and len(loggers) != k:
            raise ValueError(f"{k} runs need {k} loggers; got {len(loggers)}")
        streams = self.streams() if loggers is not None else None
        agents = self.agents() if loggers is not None else None
        rows: list[list[dict]] = [[] for _ in range(k)]
        start, end = self.count, self.count + int(n_interactions)
        t0, c0 = time.perf_counter() - self.wall_time, time.process_time() - self.cpu_time * k
        bar = task = None
        if progress:
            bar, task = _progress_bar(f"{self.agent.algo} x{k} (jax)", start, end)
            bar.start()
        try:
            for i in range(start, end):
                at_random = self._at_random(i)
                fit = i + 1 == cfg.warmup_interactions
                learn = i + 1 >= cfg.warmup_interactions
                out = self._call(i, at_random, True, learn and not fit)
                self.count += 1
                self.stacked.counts = self.stacked.counts + 1
                if fit:
                    self._fit_normalisers()
                    metrics = self._call(i, at_random, False, True)
                    out.update(metrics=metrics["metrics"],
                               finite=out["finite"] & metrics["finite"])
                host = jax.device_get(out)
                self._check_finite(i, host["finite"])
                self.wall_time = time.perf_counter() - t0
                self.cpu_time = (time.process_time() - c0) / k
                if keep_rows or loggers is not None:
                    self._rows(i, host, at_random, learn, rows, loggers, streams, agents,
                               keep_rows)
                if bar is not None:
                    bar.update(task, completed=i + 1,
                               stats=f"return {float(np.mean(host['return'])):8.3f}")
        finally:
            if bar is not None:
                bar.stop()
        if agents is not None:
            self.agents()
        return rows

    def _check_finite(self, i: int, finite: np.ndarray) -> None:
        if not finite.all():
            j = int(np.argmin(finite))
            raise NonFiniteError(f"seed {self.seeds[j]}, interaction {i}: a non-finite "
                                 "observation, reward or loss; training stopped (lower the "
                                 "learning rates, or check the env's reward scale)")

    def _rows(self, i: int, host: dict, at_random: np.ndarray, learn: bool,
              rows: list[list[dict]], loggers: Sequence[Any] | None,
              streams: list[Stream] | None, agents: list[Any] | None, keep: bool) -> None:
        k = len(self)
        checkpoint = loggers is not None and any(
            lg is not None and (i + 1) % lg.checkpoint_every == 0 for lg in loggers)
        if checkpoint:
            self.agents()  # the loggers checkpoint the runs' current states
        metric_names = sorted(host["metrics"]) if learn else []
        for j in range(k):
            length = int(host["length"][j])
            row = {"interaction": i, "return": float(host["return"][j]), "length": length,
                   "success": bool(host["success"][j]) if self.has_success else None,
                   "random": bool(at_random[j]), "strategy": host["strategy"][j],
                   "strategy_id": int(host["strategy_id"][j]),
                   **{m: float(host["metrics"][m][j]) for m in metric_names},
                   "wall_time": self.wall_time}
            if keep:
                rows[j].append(row)
            if loggers is not None and loggers[j] is not None:
                s = streams[j]
                s.action_log.append(np.asarray(host["act"][j, :length]))
                s.wall_time, s.cpu_time = self.wall_time, self.cpu_time
                loggers[j].log(row, agents[j], s)
