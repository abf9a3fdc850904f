"""The partners' shared pieces in JAX (:mod:`lili.envs.partners` is the reference): the
majority of the last N outcomes, kept in a fixed-size memory so that N can be a param."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

__all__ = ["Votes", "check_history", "no_votes", "push_vote"]


def check_history(history: int, max_history: int, env: str) -> None:
    """Refuse a ``history`` above the env's ``max_history`` (the size of its memory)."""
    if history > max_history:
        raise ValueError(f"history={history!r} is invalid; allowed: an integer from 1 to "
                         f"max_history={max_history} (make {env}(max_history=...))")


@struct.dataclass
class Votes:
    """The last outcomes (bools), most recent first; the first ``n`` are real."""

    items: jax.Array
    n: jax.Array


def no_votes(max_history: int) -> Votes:
    """An empty memory of ``max_history`` outcomes."""
    return Votes(items=jnp.zeros(max_history, bool), n=jnp.asarray(0, jnp.int32))


def push_vote(votes: Votes, outcome: jax.Array, history: jax.Array) -> tuple[Votes, jax.Array]:
    """Record ``outcome`` and return the majority of the last ``history`` outcomes: a tie goes
    to the most recent tied outcome, as in :class:`lili.envs.partners.MajorityHistory` (of two
    kinds of outcome, that is the one just recorded)."""
    items = jnp.concatenate([jnp.asarray(outcome, bool)[None], votes.items[:-1]])
    n = jnp.minimum(votes.n + 1, items.shape[0])
    window = jnp.minimum(n, history)
    yes = jnp.sum(items & (jnp.arange(items.shape[0]) < window))
    no = window - yes
    return Votes(items=items, n=n), jnp.where(yes == no, items[0], yes > no)
