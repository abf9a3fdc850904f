# Over 400 lines: the stacked buffers and the group loop are one unit (act, store, update K runs).
"""Many runs in one program: K runs that share one core train side by side.

:func:`train_many` is :func:`lili.train.train` for K agents at once. The agents must share one
core (same algo, config, observation and action sizes, horizon; their seeds and env kwargs may
differ), so that one compiled program serves them all:

- per env step, one jitted program of the acting step for all K runs; the K Gymnasium envs step
  in Python, and runs whose interaction ended early wait, masked, until the last one ends;
- the K replay buffers live stacked on the device (:class:`StackedBuffers`, arrays shaped
  [K, capacity, ...]) and each interaction is written into them in place by one donated update;
- after each interaction one program of the update block for all runs (:func:`lili.agents.
  multiseed.update_blocks`) and one of the encoder for every run's next latent.

Each program maps its step over the runs with :func:`lili.agents.multiseed.over_seeds`: one run
after another on a CPU, side by side (``vmap``) on an accelerator.

Every run stays a run: its own :class:`~lili.train.Stream` (whose buffer becomes a
:class:`BufferView` onto the stack), its own :class:`~lili.runs.RunLogger` (run folder,
checkpoints, TensorBoard, summary), and the random streams come from (seed, interaction) as in
:func:`~lili.train.train`, so on a CPU each run's numbers are bit for bit those of the same
run trained alone, and on an accelerator equal to float tolerance (vmapped float reductions
round differently in the last bits, and a run drifts apart from them).

Time: each run's ``wall_time`` is the group's wall time (they ran at the same time) and its
``cpu_time`` the group's CPU time divided by K, so per-run costs add up to what the group cost.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from lili.agents.base import AgentState
from lili.agents.core import SACCore
from lili.agents.multiseed import over_seeds, stack, unstack, update_blocks
from lili.buffer import (
    InteractionBuffer,
    Window,
    _available_memory,
    _window,
    _write,
    buffer_nbytes,
)
from lili.env_calls import env_reset, env_step, where
from lili.train import (
    Stream,
    _check_finite,
    _progress_bar,
    interaction_keys,
    plays_at_random,
    train,
)

__all__ = ["train_many", "check_group", "check_group_algo", "check_group_memory",
           "group_streams", "StackedBuffers", "BufferView", "group_nbytes"]


def group_nbytes(agents: Sequence[Any]) -> int:
    """Bytes the stacked replay buffers of ``agents`` take together."""
    return sum(buffer_nbytes(a.config.buffer_capacity, a.horizon, a.obs_dim, a.act_dim)
               for a in agents)


def _check_core_class(algo: str, core_cls: type | None) -> None:
    """ValueError unless ``core_cls`` (None: not a SACCore) runs the shared update block."""
    if core_cls is None:
        raise ValueError(f"algo {algo!r} cannot train in a group (it has no update "
                         "block); allowed: agents built on SACCore")
    if core_cls.learn_block is not SACCore.learn_block:
        raise ValueError(f"algo {algo!r} cannot train in a group (its update is not the "
                         "shared block: SLAC pretrains a model, Random learns nothing); train "
                         "it alone")


def check_group_algo(algo: str) -> None:
    """ValueError (the message :func:`check_group` gives) unless runs of the registered
    ``algo`` can train in one program, read from its class: refusing SLAC costs no agent."""
    from lili.agents.facade import AgentFacade
    from lili.agents.registry import AGENTS, _load_all

    _load_all()
    cls = AGENTS[algo][0]
    _check_core_class(algo, cls.core_cls if issubclass(cls, AgentFacade) else None)


def check_group(agents: Sequence[Any], fraction: float = 0.5) -> None:
    """ValueError (one line naming what differs) unless ``agents`` can train in one program:
    at least one, each a SAC-family agent with the generic update block, one shared core, and
    their buffers together within ``fraction`` of the free memory."""
    if not agents:
        raise ValueError("a run group needs at least one agent")
    first = agents[0]
    for a in agents:
        core = getattr(a, "core", None)
        _check_core_class(a.algo, type(core) if isinstance(core, SACCore) else None)
        if a.algo != first.algo:
            raise ValueError(f"a run group shares one algo: {first.algo!r} and {a.algo!r} "
                             "given; group runs by algo")
        if a.core != first.core:
            what = ("observation size" if a.obs_dim != first.obs_dim else
                    "action size" if a.act_dim != first.act_dim else
                    "horizon" if a.horizon != first.horizon else "agent config")
            raise ValueError(f"a run group shares one core: seed {a.seed} has another {what} "
                             f"than seed {first.seed}; group runs with equal sizes and config")
    check_group_memory(len(agents), group_nbytes(agents) / len(agents), fraction)


def check_group_memory(k: int, each: float, fraction: float = 0.5,
                       free: int | None = None) -> None:
    """ValueError (one line naming the sizes) when ``k`` replay buffers of ``each`` bytes take
    more than ``fraction`` of ``free`` bytes (default: the host's available memory)."""
    free = _available_memory() if free is None else free
    need = k * each
    if free is not None and need > fraction * free:
        raise ValueError(f"a group of {k} runs needs {need / 2**30:.2f} GiB of replay "
                         f"buffers ({each / 2**20:.1f} MiB each), more than {fraction:.0%} of the "
                         f"{free / 2**30:.1f} GiB available; allowed: at most "
                         f"{max(1, int(fraction * free // each))} runs of this size per group")


@partial(jax.jit, donate_argnums=0)
def _write_all(arrays: dict[str, jax.Array], slots: jax.Array, rows: dict[str, jax.Array],
               mask: jax.Array) -> dict[str, jax.Array]:
    # Donated: every run's row is written in place. Masked runs keep their slot's contents.
    k = jnp.arange(slots.shape[0])

    def put(v: jax.Array, r: jax.Array) -> jax.Array:
        keep = mask.reshape((-1,) + (1,) * (r.ndim - 1))
        return v.at[k, slots].set(jnp.where(keep, r, v[k, slots]))

    return {name: put(v, rows[name]) for name, v in arrays.items()}


@partial(jax.jit, static_argnames=("steps",))
def _windows(arrays: dict[str, jax.Array], counts: jax.Array, idx: jax.Array,
             steps: int | None) -> Window:
    return over_seeds(partial(_window, steps=steps))(arrays, counts, idx)


class StackedBuffers:
    """K empty replay buffers of one size as one set of device arrays [K, capacity, ...].

    :meth:`view` gives each run its buffer (checkpoints restore into it in place);
    :meth:`add_all` writes one interaction of every run in place. :meth:`of` stacks K existing
    :class:`~lili.buffer.InteractionBuffer` instead (one copy).
    """

    def __init__(self, k: int, capacity: int, horizon: int, obs_dim: int, act_dim: int) -> None:
        one = InteractionBuffer(capacity, horizon, obs_dim, act_dim)  # checks the sizes
        self.capacity, self.horizon = one.capacity, one.horizon
        self.obs_dim, self.act_dim = one.obs_dim, one.act_dim
        self.arrays: dict[str, jax.Array] = {
            name: jnp.zeros((k, *v.shape), v.dtype) for name, v in one.arrays.items()}
        self.counts = np.zeros(k, np.int64)

    @classmethod
    def of(cls, buffers: Sequence[Any]) -> StackedBuffers:
        """K buffers of one size stacked (their contents copied once)."""
        first = buffers[0]
        for b in buffers:
            if (b.capacity, b.horizon, b.obs_dim, b.act_dim) != \
                    (first.capacity, first.horizon, first.obs_dim, first.act_dim):
                raise ValueError("stacked buffers must have one size")
        out = cls.__new__(cls)
        out.capacity, out.horizon = first.capacity, first.horizon
        out.obs_dim, out.act_dim = first.obs_dim, first.act_dim
        out.arrays = stack([b.arrays for b in buffers])
        out.counts = np.array([b.count for b in buffers], np.int64)
        return out

    def __len__(self) -> int:
        return len(self.counts)

    def add_all(self, trajs: Sequence[dict[str, np.ndarray] | None],
                next_first_obs: Sequence[np.ndarray | None]) -> None:
        """Store one finished interaction per run (None: that run stores nothing now)."""
        k, h = len(self), self.horizon
        rows = {"obs": np.zeros((k, h, self.obs_dim), np.float32),
                "act": np.zeros((k, h, self.act_dim), np.float32),
                "rew": np.zeros((k, h), np.float32),
                "next_obs": np.zeros((k, h, self.obs_dim), np.float32),
                "valid": np.zeros((k, h), bool),
                "length": np.zeros((k,), np.int32),
                "next_first_obs": np.zeros((k, self.obs_dim), np.float32)}
        mask = np.zeros(k, bool)
        for j, traj in enumerate(trajs):
            if traj is None:
                continue
            n = len(traj["rew"])
            if not 1 <= n <= h:
                raise ValueError(f"interaction length {n} is outside 1..{h}")
            for name in ("obs", "act", "rew", "next_obs"):
                rows[name][j, :n] = traj[name]
            rows["valid"][j, :n] = True
            rows["length"][j] = n
            rows["next_first_obs"][j] = next_first_obs[j]
            mask[j] = True
        slots = (self.counts % self.capacity).astype(np.int32)
        self.arrays = _write_all(self.arrays, slots, rows, mask)
        self.counts = self.counts + mask

    def windows(self, steps: int | None, n: int) -> Window:
        """Every run's newest ``n`` interactions as windows [K, n, H, ...] (as
        :meth:`InteractionBuffer.window` for each run)."""
        ends = self.counts - 1
        idx = (ends[:, None] + np.arange(-n + 1, 1)[None, :]).astype(np.int32)
        return _windows(self.arrays, jnp.asarray(self.counts, jnp.int32), idx, steps)

    def view(self, j: int) -> BufferView:
        return BufferView(self, j)


class BufferView:
    """Run ``j``'s buffer inside :class:`StackedBuffers`, with the read side of
    :class:`~lili.buffer.InteractionBuffer` (what streams, checkpoints and resumes use)."""

    def __init__(self, stacked: StackedBuffers, j: int) -> None:
        self._stacked, self._j = stacked, j
        self.capacity, self.horizon = stacked.capacity, stacked.horizon
        self.obs_dim, self.act_dim = stacked.obs_dim, stacked.act_dim

    @property
    def count(self) -> int:
        return int(self._stacked.counts[self._j])

    @property
    def arrays(self) -> dict[str, jax.Array]:
        """This run's arrays (a copy out of the stack: for checkpoints and the normaliser)."""
        return {k: v[self._j] for k, v in self._stacked.arrays.items()}

    def _own(self) -> InteractionBuffer:
        buf = InteractionBuffer.__new__(InteractionBuffer)
        buf.capacity, buf.horizon = self.capacity, self.horizon
        buf.obs_dim, buf.act_dim = self.obs_dim, self.act_dim
        buf.arrays, buf.count = self.arrays, self.count
        return buf

    def window(self, end: int, n: int, steps: int | None = None) -> Window:
        return self._own().window(end, n, steps)

    def last_next_obs(self, index: int) -> np.ndarray:
        return self._own().last_next_obs(index)

    def stored(self, index: int) -> bool:
        return self.count - self.capacity <= index < self.count

    def state_dict(self) -> dict[str, Any]:
        return self._own().state_dict()

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restore a checkpoint's buffer into this run's slot of the stack (ValueError as
        :meth:`InteractionBuffer.load_state_dict`)."""
        own = InteractionBuffer(self.capacity, self.horizon, self.obs_dim, self.act_dim)
        own.load_state_dict(d)
        st = self._stacked
        # One run's slot of the stack, written in place as InteractionBuffer.add writes a slot.
        st.arrays = _write(st.arrays, np.int32(self._j), own.arrays)
        st.counts[self._j] = own.count

    def add(self, traj: dict[str, np.ndarray], next_first_obs: np.ndarray) -> int:
        trajs: list[Any] = [None] * len(self._stacked)
        nxt: list[Any] = [None] * len(self._stacked)
        trajs[self._j], nxt[self._j] = traj, next_first_obs
        self._stacked.add_all(trajs, nxt)
        return self.count - 1


@partial(jax.jit, static_argnums=0)
def _act_all(core: Any, actors: Any, norms: Any, obs: jax.Array, acting: Any,
             keys: jax.Array) -> tuple[jax.Array, Any]:
    def one(actor, norm, o, s, k):
        return core._act_step(actor, norm, o, s, k, False)

    return over_seeds(one)(actors, norms, obs, acting, keys)


@partial(jax.jit, static_argnums=0)
def _next_acting_all(core: Any, states: AgentState, windows: Window) -> Any:
    return over_seeds(core.next_acting)(states, windows)


@partial(jax.jit, static_argnums=0)
def _initial_acting_all(core: Any, states: AgentState) -> Any:
    return over_seeds(core.initial_acting)(states)


def _next_acting(agents: Sequence[Any], states: AgentState, stacked: StackedBuffers) -> Any:
    core = agents[0].core
    if not core.uses_latent or int(stacked.counts.min()) < 1:
        return _initial_acting_all(core, states)
    return _next_acting_all(core, states, stacked.windows(core.window_steps, core.history))


def group_streams(agents: Sequence[Any]) -> list[Stream]:
    """Fresh streams for ``agents`` (a group that :func:`check_group` accepts) whose buffers are
    views of one :class:`StackedBuffers`, so the group's buffers are allocated once, stacked."""
    check_group(agents)
    a = agents[0]
    stacked = StackedBuffers(len(agents), a.config.buffer_capacity, a.horizon, a.obs_dim,
                             a.act_dim)
    return [Stream(ag.env, stacked.view(j), ag.seed, ag.scale_action)
            for j, ag in enumerate(agents)]


def train_many(agents: Sequence[Any], streams: Sequence[Stream], n_interactions: int,
               loggers: Sequence[Any] | None = None, progress: bool = False) -> list[list[dict]]:
    """Train K ``agents`` on their ``streams`` for ``n_interactions`` more interactions each, in
    one program (module docstring). ``loggers`` (one :class:`~lili.runs.RunLogger` per run, or
    None) write each run's folder. Runs that start behind the others (resumed from an older
    checkpoint) first catch up alone. Returns each run's rows, as :func:`lili.train.train`.
    """
    if isinstance(n_interactions, bool) or not isinstance(n_interactions, (int, np.integer)) \
            or n_interactions < 0:
        raise ValueError(f"n_interactions={n_interactions!r} is invalid; allowed: an integer >= 0")
    if len(streams) != len(agents) or (loggers is not None and len(loggers) != len(agents)):
        raise ValueError(f"{len(agents)} agents need as many streams and loggers; got "
                         f"{len(streams)} streams and "
                         f"{'no' if loggers is None else len(loggers)} loggers")
    check_group(agents)
    loggers = list(loggers) if loggers is not None else [None] * len(agents)
    rows: list[list[dict]] = [[] for _ in agents]
    # Catch up: the group then moves in step, so warm-up and the first block fall together.
    ahead = max(s.count for s in streams)
    end = ahead + int(n_interactions)
    for j, (a, s) in enumerate(zip(agents, streams, strict=True)):
        if s.count < ahead:
            rows[j] += train(a, s, ahead - s.count, logger=loggers[j])
    if n_interactions == 0:
        return rows
    return _train_together(list(agents), list(streams), loggers, end, rows, progress)


def _train_together(agents: list[Any], streams: list[Stream], loggers: list[Any], end: int,
                    rows: list[list[dict]], progress: bool) -> list[list[dict]]:
    k = len(agents)
    core, cfg = agents[0].core, agents[0].config
    for a, s in zip(agents, streams, strict=True):
        a.stream = s
        s.start()
    views = [s.buffer for s in streams]
    if all(isinstance(v, BufferView) for v in views) and \
            len({id(v._stacked) for v in views}) == 1 and len(views[0]._stacked) == k:
        stacked = views[0]._stacked
    else:
        stacked = StackedBuffers.of(views)
        for j, s in enumerate(streams):
            s.buffer = stacked.view(j)
    states = stack([a.state for a in agents])
    acting = _next_acting(agents, states, stacked)
    start = streams[0].count
    t0 = time.perf_counter() - max(s.wall_time for s in streams)
    c0 = time.process_time() - sum(s.cpu_time for s in streams)
    obs_dim = agents[0].obs_dim
    bar = task = None
    if progress:
        bar, task = _progress_bar(f"{agents[0].algo} x{k}", start, end)
        bar.start()
    synced = True
    try:
        for i in range(start, end):
            keys = [interaction_keys(a.seed, i) for a in agents]
            act_keys = jnp.stack([kk[0] for kk in keys])
            rand = [plays_at_random(a.seed, i, cfg.warmup_interactions, cfg.random_interactions)
                    for a in agents]
            rngs = [np.random.default_rng([a.seed, i]) if r else None
                    for a, r in zip(agents, rand, strict=True)]
            done = _play_all(agents, streams, states, acting, act_keys, rngs, obs_dim, i)
            nexts = []
            for s, d in zip(streams, done, strict=True):
                nxt, info = env_reset(s.env, where(i + 1))
                _check_finite(i, d["traj"], nxt, {})
                nexts.append((nxt, info))
            stacked.add_all([d["traj"] for d in done], [n[0] for n in nexts])
            for s, d, n in zip(streams, done, nexts, strict=True):
                s.action_log.append(d["traj"]["act"])
                s.pending = n
            metrics: list[dict[str, float]] = [{} for _ in agents]
            if i + 1 >= cfg.warmup_interactions:
                if i + 1 == cfg.warmup_interactions:
                    states = stack([core.fit_normaliser(st, v) for st, v in
                                    zip(unstack(states, k), [s.buffer for s in streams],
                                        strict=True)])
                upd = jnp.stack([kk[1] for kk in keys])
                states, m = update_blocks(core, states, stacked.arrays,
                                          jnp.asarray(stacked.counts, jnp.int32), upd)
                host = {name: np.asarray(v) for name, v in m.items()}
                metrics = [{name: float(v[j]) for name, v in host.items()} for j in range(k)]
                synced = False
                for j, d in enumerate(done):
                    _check_finite(i, d["traj"], nexts[j][0], metrics[j])
            acting = _next_acting(agents, states, stacked)
            wall, cpu = time.perf_counter() - t0, (time.process_time() - c0) / k
            checkpoint = any(lg is not None and (i + 1) % lg.checkpoint_every == 0
                             for lg in loggers)
            if checkpoint and not synced:
                _sync(agents, states)
                synced = True
            for j, (a, s, d) in enumerate(zip(agents, streams, done, strict=True)):
                s.wall_time, s.cpu_time = wall, cpu
                row = {"interaction": i, "return": d["ret"], "length": d["length"],
                       "success": d["success"], "random": rand[j], "strategy": d["strategy"],
                       "strategy_id": d["strategy_id"], **metrics[j], "wall_time": wall}
                rows[j].append(row)
                if loggers[j] is not None:
                    loggers[j].log(row, a, s)
            if bar is not None:
                bar.update(task, completed=i + 1,
                           stats=f"return {np.mean([d['ret'] for d in done]):8.3f}")
    finally:
        if bar is not None:
            bar.stop()
        _sync(agents, states)
    return rows


def _sync(agents: Sequence[Any], states: AgentState) -> None:
    for a, st in zip(agents, unstack(states, len(agents)), strict=True):
        a.state = st


def _play_all(agents: Sequence[Any], streams: Sequence[Stream], states: AgentState, acting: Any,
              act_keys: jax.Array, rngs: Sequence[np.random.Generator | None],
              obs_dim: int, index: int) -> list[dict[str, Any]]:
    """Play one interaction of every run; runs that end early wait for the others."""
    k, core = len(agents), agents[0].core
    horizon = agents[0].horizon
    obs = np.zeros((k, obs_dim), np.float32)
    infos = []
    for j, s in enumerate(streams):
        o, info = s.start()
        obs[j] = o
        infos.append(info)
    logs: list[dict[str, list]] = [{"obs": [], "act": [], "rew": [], "next_obs": []}
                                   for _ in range(k)]
    live = np.ones(k, bool)
    success: list[Any] = [None] * k
    every_random = all(r is not None for r in rngs)
    for t in range(horizon + 1):
        if t == horizon:
            from lili.envs.checker import EnvContractError

            raise EnvContractError(f"the interaction did not end within the env's horizon "
                                   f"({horizon} steps): an env must terminate or truncate its "
                                   "episodes by then")
        if every_random:
            actions = None
        else:
            actions, acting = _act_all(core, states.actor, states.norm, jnp.asarray(obs),
                                       acting, act_keys)
            actions = np.asarray(actions)
        for j in np.flatnonzero(live):
            a = (rngs[j].uniform(-1.0, 1.0, agents[j].act_dim) if rngs[j] is not None
                 else actions[j])
            a = np.asarray(a, np.float32)
            nxt, r, terminated, truncated, step_info = env_step(
                streams[j].env, agents[j].scale_action(a), where(index, t))
            log = logs[j]
            log["obs"].append(obs[j].copy())
            log["act"].append(a)
            log["rew"].append(r)
            log["next_obs"].append(nxt)
            obs[j] = nxt
            if terminated or truncated:
                success[j] = step_info.get("success")
                live[j] = False
        if not live.any():
            break
    out = []
    for j in range(k):
        log = logs[j]
        strategy = np.asarray(infos[j].get("strategy", np.zeros(0)), np.float32).ravel()
        out.append({"traj": {name: np.asarray(v, np.float32) for name, v in log.items()},
                    "ret": float(np.sum(log["rew"])), "length": len(log["rew"]),
                    "success": None if success[j] is None else bool(success[j]),
                    "strategy": strategy, "strategy_id": int(infos[j].get("strategy_id", -1))})
    return out

