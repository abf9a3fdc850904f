"""InteractionBuffer: interactions stored in the order they happened, on the device.

Storage is a ring of ``capacity`` interactions, each padded to the horizon H with a ``valid``
mask, plus each interaction's successor's first observation (what the critic bootstraps from at
the interaction boundary). Interactions are addressed by their logical index k (0, 1, 2, ...);
interaction k lives in slot ``k % capacity``.

Sampling (:func:`sample`) is a pure JAX function of the arrays and a key, so it runs inside the
fused update block and a seed fixes it. A batch holds ``n_interactions`` interaction indices k and
``per_interaction`` transitions of each, plus the window of interactions k-N .. k that the
latent needs: tau^{k-N..k-1} (encoder input for z^k) and tau^{k-N+1..k} (for z^{k+1}).
"""

from __future__ import annotations

from functools import partial
from typing import Any, TypedDict

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["InteractionBuffer", "sample", "buffer_nbytes", "check_buffer_fits", "Batch", "Window"]

FIELDS = ("obs", "act", "rew", "next_obs", "valid")


def buffer_nbytes(capacity: int, horizon: int, obs_dim: int, act_dim: int) -> int:
    """Bytes an :class:`InteractionBuffer` of these sizes allocates (all fields together)."""
    per_step = 4 * (2 * obs_dim + act_dim + 1) + 1  # obs, next_obs, act, rew (float32), valid
    return int(capacity) * (int(horizon) * per_step + 4 + 4 * obs_dim)


def _available_memory() -> int | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def check_buffer_fits(capacity: int, horizon: int, obs_dim: int, act_dim: int,
                      fraction: float = 0.5) -> int:
    """Raise ValueError when the buffer would take more than ``fraction`` of free memory.

    Checked before allocating, so an env with an absurd horizon (1e9) fails with a message that
    names the sizes instead of a MemoryError (or the machine swapping). Returns the byte count.
    """
    need = buffer_nbytes(capacity, horizon, obs_dim, act_dim)
    free = _available_memory()
    if free is not None and need > fraction * free:
        raise ValueError(
            f"a replay buffer of {capacity} interactions x horizon {horizon} (obs {obs_dim}, "
            f"act {act_dim}) needs {need / 2**30:.1f} GiB, more than {fraction:.0%} of the "
            f"{free / 2**30:.1f} GiB available; allowed: a smaller horizon or buffer_capacity"
        )
    return need


class Window(TypedDict, total=False):
    """Interactions k-N .. k as arrays [..., N + 1, S, ...] (S = H or the sampled steps)."""

    obs: jax.Array
    act: jax.Array
    rew: jax.Array
    next_obs: jax.Array
    valid: jax.Array
    weight: jax.Array
    t: jax.Array
    last: jax.Array


class Batch(TypedDict, total=False):
    """A training batch of :func:`sample`: transitions [B, M, ...] of interactions k."""

    obs: jax.Array
    act: jax.Array
    rew: jax.Array
    next_obs: jax.Array
    t: jax.Array
    last: jax.Array
    next_first_obs: jax.Array
    index: jax.Array
    window: Window


@partial(jax.jit, donate_argnums=0)
def _write(arrays: dict[str, jax.Array], slot: jax.Array,
           row: dict[str, jax.Array]) -> dict[str, jax.Array]:
    # Donated: the device arrays are updated in place, so adding an interaction costs its own
    # size, not the buffer's.
    return {k: v.at[slot].set(row[k]) for k, v in arrays.items()}


@partial(jax.jit, static_argnames=("steps",))
def _window(arrays: dict[str, jax.Array], count: jax.Array, idx: jax.Array,
            steps: int | None) -> Window:
    out = _gather_window(arrays, count, idx, None, None)
    out["weight"] = pooling_weights(out["valid"], out["last"], steps)
    return out


class InteractionBuffer:
    """Storage of whole interactions on the device (see the module docstring).

    ``arrays`` are JAX arrays that the fused update block reads as they are; :meth:`add` writes
    one interaction into them inside a jitted, donated update.
    """

    def __init__(self, capacity: int, horizon: int, obs_dim: int, act_dim: int) -> None:
        if isinstance(capacity, bool) or not isinstance(capacity, (int, np.integer)) \
                or capacity < 2:
            raise ValueError(f"buffer capacity={capacity!r} is invalid; allowed: an integer >= 2")
        check_buffer_fits(capacity, horizon, obs_dim, act_dim)
        self.capacity, self.horizon = int(capacity), int(horizon)
        self.obs_dim, self.act_dim = int(obs_dim), int(act_dim)
        c, h = self.capacity, self.horizon
        self.arrays: dict[str, jax.Array] = {
            "obs": jnp.zeros((c, h, obs_dim), jnp.float32),
            "act": jnp.zeros((c, h, act_dim), jnp.float32),
            "rew": jnp.zeros((c, h), jnp.float32),
            "next_obs": jnp.zeros((c, h, obs_dim), jnp.float32),
            "valid": jnp.zeros((c, h), bool),
            "length": jnp.zeros((c,), jnp.int32),
            "next_first_obs": jnp.zeros((c, obs_dim), jnp.float32),
        }
        self.count = 0

    def add(self, traj: dict[str, np.ndarray], next_first_obs: np.ndarray) -> int:
        """Store one finished interaction; return its logical index.

        ``traj`` holds ``obs``, ``act``, ``rew``, ``next_obs`` with the interaction's length as
        leading dimension (1 .. H).
        """
        n = len(traj["rew"])
        if not 1 <= n <= self.horizon:
            raise ValueError(f"interaction length {n} is outside 1..{self.horizon}")
        row = {}
        for key in ("obs", "act", "rew", "next_obs"):
            v = np.asarray(traj[key], np.float32)
            pad = np.zeros((self.horizon, *v.shape[1:]), np.float32)
            pad[:n] = v
            row[key] = pad
        row["valid"] = np.arange(self.horizon) < n
        row["length"] = np.int32(n)
        row["next_first_obs"] = np.asarray(next_first_obs, np.float32)
        self.arrays = _write(self.arrays, np.int32(self.count % self.capacity), row)
        self.count += 1
        return self.count - 1

    def window(self, end: int, n: int, steps: int | None = None) -> Window:
        """Interactions end-n+1 .. end as [n, H, ...] arrays (missing ones fully masked), with
        each step's index ``t``, ``last`` flag and pooling ``weight``.

        With ``steps`` = S (the encoder reads S sampled transitions during updates, see
        :func:`_gather_window`), the weights make the mean over all steps equal the expected
        mean over such a sample: the last step weighs 1/S and the earlier ones share
        (S - 1)/S. Plain weights would give the last step 1/H at acting time against 1/S in
        training, a shift of the latent that measurably hurt (README example: 0.96 -> 0.5).
        """
        idx = np.arange(end - n + 1, end + 1, dtype=np.int32)
        return _window(self.arrays, np.int32(self.count), idx, steps)

    def last_next_obs(self, index: int) -> np.ndarray:
        """The final observation of interaction ``index`` (still stored)."""
        slot = index % self.capacity
        length = int(self.arrays["length"][slot])
        return np.asarray(self.arrays["next_obs"][slot, length - 1])

    def stored(self, index: int) -> bool:
        """Whether interaction ``index`` is still in the ring."""
        return self.count - self.capacity <= index < self.count

    def state_dict(self) -> dict[str, Any]:
        """Arrays for a checkpoint (only the filled slots), as NumPy."""
        filled = min(self.count, self.capacity)
        d: dict[str, Any] = {k: np.asarray(v[:filled]) for k, v in self.arrays.items()}
        d["count"] = np.array(self.count)
        return d

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restore :meth:`state_dict`; ValueError naming the field when shapes do not fit."""
        try:
            count = int(d["count"])
        except (KeyError, TypeError, ValueError):
            raise ValueError("checkpoint buffer has no valid 'count'") from None
        if count < 0:
            raise ValueError(f"checkpoint buffer count={count} is invalid")
        filled = min(count, self.capacity)
        new = {}
        for k, v in self.arrays.items():
            if k not in d:
                raise ValueError(f"checkpoint buffer has no field {k!r}")
            if d[k].shape[1:] != v.shape[1:] or d[k].shape[0] != filled:
                raise ValueError(f"checkpoint buffer field {k!r} has shape {d[k].shape}; "
                                 f"expected ({filled}, {', '.join(map(str, v.shape[1:]))})")
            new[k] = v.at[:filled].set(jnp.asarray(d[k], v.dtype))
        self.arrays = new
        self.count = count


def pooling_weights(valid, last, steps: int | None):
    """Weights of a full window's steps in the encoder's mean (see ``InteractionBuffer.window``).

    Works on NumPy and JAX arrays alike (JAX inside jit).
    """
    xp = np if isinstance(valid, np.ndarray) else jnp
    valid_f = valid.astype(np.float32)
    if steps is None:
        return valid_f
    last_f = last.astype(np.float32)
    early = valid_f - last_f
    n_early = early.sum(-1, keepdims=True)
    return last_f + early * (steps - 1) / xp.maximum(n_early, 1.0)


def _gather_window(arrays: dict[str, jax.Array], count: jax.Array, idx: jax.Array,
                   key: jax.Array, steps: int | None):
    """Interactions at logical indices ``idx`` [B, W] with out-of-range ones masked.

    With ``steps`` = S, each interaction is represented by S of its transitions: S - 1 drawn
    uniformly from the steps before its last, plus the last step (how it ended is what the
    partner reacts to). LILI's original code encoded 8 such transitions; encoding every step of
    every sampled interaction dominated the update cost (calibration note, point 5).
    """
    capacity, horizon = arrays["rew"].shape
    ok = (idx >= 0) & (idx > count - 1 - capacity) & (idx < count)
    slots = jnp.mod(idx, capacity)
    length = arrays["length"][slots]
    if steps is None:
        out = {k: arrays[k][slots] for k in FIELDS}
        t = jnp.broadcast_to(jnp.arange(horizon), out["valid"].shape)
        out["valid"] = out["valid"] & ok[..., None]
        last = (t == length[..., None] - 1) & out["valid"]
        out["weight"] = pooling_weights(out["valid"], last, None)
    else:
        u = jax.random.uniform(key, (*idx.shape, steps - 1))
        early = jnp.minimum((u * (length[..., None] - 1)).astype(jnp.int32),
                            jnp.maximum(length[..., None] - 2, 0))
        t = jnp.concatenate([early, length[..., None] - 1], -1)
        rows = slots[..., None]
        out = {k: arrays[k][rows, t] for k in FIELDS}
        out["valid"] = jnp.broadcast_to(ok[..., None], t.shape)
        out["weight"] = out["valid"].astype(jnp.float32)
    out["t"] = t
    out["last"] = (t == length[..., None] - 1) & out["valid"]
    return out


def sample(
    arrays: dict[str, jax.Array],
    count: jax.Array,
    key: jax.Array,
    n_interactions: int,
    per_interaction: int,
    history: int = 0,
    window_steps: int | None = None,
) -> Batch:
    """Sample a batch (pure JAX; see the module docstring).

    ``history`` = N: how many preceding interactions the latent needs (0 for agents without a
    latent). Only interactions k >= N (and still fully stored with their N predecessors) are
    drawn. Returns transitions shaped [n_interactions, per_interaction, ...] with their step
    index ``t`` and ``last`` flag, ``next_first_obs`` [n_interactions, obs_dim], and, when
    N > 0, ``window`` with fields shaped [n_interactions, N + 1, S, ...] for k-N .. k, where
    S = H or ``window_steps`` (see :func:`_gather_window`), with each step's ``t`` and ``last``.
    """
    capacity = arrays["rew"].shape[0]
    k_key, t_key, w_key = jax.random.split(key, 3)
    lo = jnp.maximum(history, count - capacity + history)
    k = lo + jax.random.randint(k_key, (n_interactions,), 0, jnp.maximum(count - lo, 1))
    slot = jnp.mod(k, capacity)
    length = arrays["length"][slot]
    u = jax.random.uniform(t_key, (n_interactions, per_interaction))
    t = jnp.minimum((u * length[:, None]).astype(jnp.int32), length[:, None] - 1)
    rows = slot[:, None]
    batch = {
        "obs": arrays["obs"][rows, t],
        "act": arrays["act"][rows, t],
        "rew": arrays["rew"][rows, t],
        "next_obs": arrays["next_obs"][rows, t],
        "t": t,
        "last": t == length[:, None] - 1,
        "next_first_obs": arrays["next_first_obs"][slot],
        "index": k,
    }
    if history > 0:
        idx = k[:, None] + jnp.arange(-history, 1)[None, :]
        batch["window"] = _gather_window(arrays, count, idx, w_key, window_steps)
    # Materialise the gathered batch: left to itself XLA fuses the gathers into their
    # consumers (the encoder's first layer) and recomputes them per use, which measured ~3x
    # slower updates for LILI.
    return jax.lax.optimization_barrier(batch)
