"""Many seeds in one program: the pure update block mapped over stacked agent states.

The update half of :func:`lili.many.train_many` (``lili train --seeds``), which trains K runs
that share one core together: one program keeps an accelerator busy, and on a CPU it saves the
per-run dispatch of acting and updating; ``benchmarks/many_runs.py`` measures what it gains.

Usage: build one agent per seed, each with its own buffer, then::

    states = stack([a.state for a in agents])
    arrays, counts = stack([b.arrays for b in buffers]), jnp.array([b.count for b in buffers])
    states, metrics = update_blocks(agents[0].core, states, arrays, counts, keys)

Every seed's block is the single-seed :meth:`SACCore.block`. On a CPU it is that block bit for
bit: :func:`over_seeds` runs the seeds one after another inside the program (``lax.map``),
because a vmapped XLA program rounds differently with the group's size (three Lunar Lander
seeds vmapped differed from each seed alone in the last bits of most parameters after one
block, and RL turns those bits into another run within a few hundred interactions). On an
accelerator the seeds run side by side (``vmap``), where that is the point, and agree with
their single-seed blocks to float tolerance (the test suite checks the CPU's equality).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp

from lili.agents.base import AgentState
from lili.agents.core import SACCore

__all__ = ["over_seeds", "stack", "unstack", "update_blocks"]


def stack(trees: list[Any]) -> Any:
    """Stack pytrees of the same structure along a new leading axis (one entry per seed)."""
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *trees)


def unstack(tree: Any, n: int) -> list[Any]:
    """The inverse of :func:`stack`."""
    return [jax.tree_util.tree_map(lambda x, i=i: x[i], tree) for i in range(n)]


def over_seeds(f: Callable[..., Any]) -> Callable[..., Any]:
    """``f`` over the leading (seed) axis of each argument, to be traced inside ``jax.jit``.

    On a CPU ``lax.map``: one seed after another in one program, each bit for bit what ``f``
    gives the seed alone (on two cores it measured no slower than ``vmap`` for three Lunar
    Lander seeds); a group of one maps two copies of its seed and keeps the first, the price of
    the same bits as in any larger group. Elsewhere ``vmap``: the seeds side by side, equal to
    float tolerance.
    """
    def mapped(*args: Any) -> Any:
        if jax.default_backend() != "cpu":
            return jax.vmap(f)(*args)
        if jax.tree.leaves(args)[0].shape[0] == 1:
            # XLA compiles a map over one seed otherwise (its axes of size one are dropped),
            # which rounds the seed's last bits off its bits in any larger group: map two
            # copies and keep the first.
            twice = jax.lax.map(lambda a: f(*a), jax.tree.map(lambda x: jnp.concatenate([x, x]),
                                                              args))
            return jax.tree.map(lambda x: x[:1], twice)
        return jax.lax.map(lambda a: f(*a), args)

    return mapped


@partial(jax.jit, static_argnums=0)
def update_blocks(core: SACCore, states: AgentState, arrays: dict[str, jax.Array],
                  counts: jax.Array, keys: jax.Array) -> tuple[AgentState, dict[str, jax.Array]]:
    """One update block for every seed at once: ``core.block`` over the leading axis of
    ``states``, ``arrays`` (each seed's buffer), ``counts`` and ``keys`` (:func:`over_seeds`)."""
    return over_seeds(core.block)(states, arrays, counts, keys)
