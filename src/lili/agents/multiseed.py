"""Many seeds in one program: the pure update block ``jax.vmap``-ed over stacked agent states.

The update half of :func:`lili.many.train_many` (``lili train --seeds``), which trains K runs
that share one core together: one program keeps an accelerator busy, and on a CPU it saves the
per-run dispatch of acting and updating; ``benchmarks/many_runs.py`` measures what it gains.

Usage: build one agent per seed, each with its own buffer, then::

    states = stack([a.state for a in agents])
    arrays, counts = stack([b.arrays for b in buffers]), jnp.array([b.count for b in buffers])
    states, metrics = update_blocks(agents[0].core, states, arrays, counts, keys)

Every seed's block is exactly the single-seed :meth:`SACCore.block` (the test suite checks
that three seeds in one program agree with their single-seed blocks to float tolerance).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import jax
import jax.numpy as jnp

from lili.agents.base import AgentState
from lili.agents.core import SACCore

__all__ = ["stack", "unstack", "update_blocks"]


def stack(trees: list[Any]) -> Any:
    """Stack pytrees of the same structure along a new leading axis (one entry per seed)."""
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *trees)


def unstack(tree: Any, n: int) -> list[Any]:
    """The inverse of :func:`stack`."""
    return [jax.tree_util.tree_map(lambda x, i=i: x[i], tree) for i in range(n)]


@partial(jax.jit, static_argnums=0)
def update_blocks(core: SACCore, states: AgentState, arrays: dict[str, jax.Array],
                  counts: jax.Array, keys: jax.Array) -> tuple[AgentState, dict[str, jax.Array]]:
    """One update block for every seed at once: ``core.block`` vmapped over the leading axis
    of ``states``, ``arrays`` (each seed's buffer), ``counts`` and ``keys``."""
    return jax.vmap(core.block)(states, arrays, counts, keys)
