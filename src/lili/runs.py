# Over 400 lines: the run folder's one reader and writer (config, metrics, checkpoints, resume).
"""Run folders: ``<out>/<env>/<algo>/seed_<k>/`` with config, metrics, TensorBoard, checkpoints.

- ``config.yaml``: the resolved configuration (env id and kwargs, algo, seed, budget, agent).
- ``metrics.csv``: one row per interaction (return, length, success, whether it was played at
  random, strategy, losses, time; :mod:`lili.metrics_file`).
- ``tb/``: TensorBoard event files (tensorboardX): the numbers of ``metrics.csv``, written
  anew from it when a run resumes.
- ``checkpoints/``: the newest checkpoint ``ckpt_<n>/``, in two parts written apart: the agent
  (``agent.msgpack``: parameters, optimiser states, normaliser, config) and the stream
  (``stream.npz``: replay buffer, action log, wall time), plus ``latest.json`` pointing at it;
  the pointer is replaced atomically after the checkpoint is complete, so a run killed at any
  moment loses at most one checkpoint interval.
- ``block_extras.jsonl``: what a block of updates reports beyond the columns (SLAC's ELBO terms
  and pretraining losses; :data:`lili.metrics_file.EXTRAS`), also in TensorBoard and, the
  newest value of each, in ``summary.json``'s ``block_extras``.
- ``summary.json``: final metrics, versions, git commit, wall time.

Resuming (:func:`resume_run`) checks everything it reads (config, pointer, both checkpoint
parts, and that ``metrics.csv`` still holds the rows the checkpoint logged, unedited) before
anything in the folder is written. A ``metrics.csv`` written before the ``random`` column
existed resumes too: the logger rewrites it with the column (:func:`lili.metrics_file.
random_column`).
"""

from __future__ import annotations

import csv
import json
import math
import platform
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any, TextIO

import numpy as np
import yaml

import lili
from lili.agents import CheckpointError, load_agent
from lili.agents.registry import stored_config
from lili.agents.sac import SAC
from lili.config import AgentConfig
from lili.errors import shown
from lili.metrics_file import (
    EXTRAS,
    METRIC_COLUMNS,
    RANDOM,
    left_out_of_policy,
    metric_columns,
    random_column,
    read_extras,
)
from lili.train import Stream
from lili.yaml_bounds import YAMLTooLarge, safe_load

__all__ = ["RunLogger", "run_dir_for", "load_checkpoint", "METRIC_COLUMNS", "final_mean",
           "final_window", "latest_checkpoint", "read_run_config", "metric_columns",
           "resume_run", "check_out_dir", "load_run_agent", "load_trained"]


def check_out_dir(path: str | Path, flag: str = "--out") -> Path:
    """``path`` as a Path, or ValueError when it (or its nearest existing parent) is a file or
    not writable: checked before anything is written (``lili train``, ``report``,
    ``reproduce``)."""
    p = Path(path)
    for folder in (p, *p.parents):
        if folder.exists():
            if not folder.is_dir():
                raise ValueError(f"{flag} {str(path)!r} is invalid: {str(folder)!r} is a file; "
                                 "allowed: a folder, existing or to be created")
            # Tried, not asked (os.access): root may "access" /sys, where mkdir still fails.
            try:
                Path(tempfile.mkdtemp(prefix=".lili-probe-", dir=folder)).rmdir()
            except OSError as e:
                raise ValueError(f"{flag} {str(path)!r} is invalid: {str(folder)!r} is not "
                                 f"writable ({e.strerror}); allowed: a folder you can write "
                                 "to") from None
            break
    return p


def run_dir_for(out: str | Path, env_id: str, algo: str, seed: int) -> Path:
    """The run folder of (env, algo, seed) under the experiment folder ``out``."""
    return Path(out) / env_id.split("/")[-1].replace(":", "_") / algo / f"seed_{seed}"


def final_window(n: int, frac: float = 0.1) -> int:
    """How many of ``n`` interactions the final performance averages: the last ``frac`` of
    them, rounded up, at least one (at 15 interactions: 2). The one definition, used by
    ``summary.json`` and by every report."""
    return max(1, math.ceil(n * frac - 1e-9))


def final_mean(values: list[float] | np.ndarray, frac: float = 0.1) -> float:
    """Mean over the last ``frac`` of the values (:func:`final_window`): the paper's final
    performance."""
    return float(np.mean(np.asarray(values, float)[-final_window(len(values), frac):]))


def _final(values: list[float] | np.ndarray) -> float | None:
    """:func:`final_mean` over the values that are not NaN; None when there are none."""
    values = np.asarray(values, float)
    values = values[~np.isnan(values)]
    return final_mean(values) if values.size else None


def _git_commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                             cwd=Path(__file__).parent, timeout=5)
        return out.stdout.strip() or None
    except Exception:
        return None


def _cpu_model() -> str:
    """The CPU's model name where Linux gives it, else the architecture."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.partition(":")[2].strip()
    except OSError:
        pass
    return platform.machine()


def _versions() -> dict[str, str]:
    """What the numbers of a run depend on besides its config and seed. XLA compiles for the
    CPU it runs on and optax does the updates, so both are here: a Drift run's sixth digit
    once moved between two checkouts with the same code and the same jax/flax/numpy."""
    import flax
    import gymnasium
    import jax
    import jaxlib
    import optax

    return {"lili": lili.__version__, "python": platform.python_version(), "jax": jax.__version__,
            "jaxlib": jaxlib.__version__, "flax": flax.__version__, "optax": optax.__version__,
            "gymnasium": gymnasium.__version__, "numpy": np.__version__, "cpu": _cpu_model()}


def read_run_config(run_dir: str | Path) -> dict[str, Any]:
    """The ``config.yaml`` of a run folder; ValueError naming the file when it is missing or
    not the mapping ``lili train`` writes."""
    path = Path(run_dir) / "config.yaml"
    if not path.is_file():
        raise ValueError(f"{Path(run_dir)} is not a run folder (config.yaml is missing)")
    try:
        cfg = safe_load(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not UTF-8 text; restore it or start a new run") from None
    except YAMLTooLarge as e:
        raise ValueError(f"{path} is refused: {e}; restore it or start a new run") from None
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ValueError(f"{path} is not valid YAML{where}; restore it or start a new run") \
            from None
    keys = ("env", "env_kwargs", "algo", "seed", "interactions", "agent")
    if not isinstance(cfg, dict) or any(k not in cfg for k in keys):
        raise ValueError(f"{path} is not a lili run config (it must map {', '.join(keys)})")
    # The fields its algo does not read at their defaults: runs of earlier releases took any.
    return {**cfg, "agent": stored_config(cfg["algo"], cfg["agent"])}


def latest_checkpoint(run_dir: str | Path) -> tuple[Path, int]:
    """(folder, interactions) of the run's newest complete checkpoint; CheckpointError naming
    the file when there is none or the pointer is corrupt."""
    root = Path(run_dir) / "checkpoints"
    pointer = root / "latest.json"
    if not pointer.is_file():
        raise CheckpointError(f"{Path(run_dir)} has no checkpoint (checkpoints/latest.json is "
                              "missing)")
    try:
        data = json.loads(pointer.read_text())
        name, n = data["checkpoint"], data["interactions"]
        ok = isinstance(name, str) and "/" not in name and isinstance(n, int) and n >= 0
    except (ValueError, KeyError, TypeError):
        ok = False
    if not ok:
        raise CheckpointError(f"{pointer} is corrupt (expected {{\"checkpoint\": \"ckpt_<n>\", "
                              "\"interactions\": n}); restore it or start a new run")
    ck = root / name
    if not (ck / "agent.msgpack").is_file():
        raise CheckpointError(f"{pointer} points at {ck}, which holds no agent.msgpack")
    return ck, n


def load_run_agent(ck: Path, run_dir: str | Path, env: Any, algo: str,
                   config: AgentConfig) -> SAC:
    """The agent of checkpoint ``ck`` on ``env``; CheckpointError unless it is the run's
    ``algo`` with the run's agent ``config`` (the one check of ``--resume`` and ``lili
    eval``)."""
    loaded = load_agent(ck / "agent.msgpack", env)
    if loaded.algo != algo:
        raise CheckpointError(f"{ck} holds a {loaded.algo!r} agent; this run is {algo!r} (its "
                              "config.yaml)")
    if loaded.config != config:
        raise CheckpointError(f"{ck} was trained with another agent config than {run_dir}")
    return loaded


def load_trained(run_dir: str | Path, render_mode: str | None = None
                 ) -> tuple[SAC, Any, dict[str, Any], int]:
    """The agent of run folder ``run_dir``'s newest checkpoint on a fresh env of the run's
    config: (agent, env, resolved config, interactions the checkpoint holds), for playing a
    trained run (``lili eval``, ``benchmarks/greedy_eval.py``). ValueError (CheckpointError)
    naming the file when the folder, its config, its checkpoint or the agent in it does not
    fit, the env's own error when it cannot be made; an env made for an agent that does not
    load is closed."""
    from lili.envs.spec import make_env

    cfg = read_run_config(run_dir)
    ck, at = latest_checkpoint(run_dir)
    try:
        stored = AgentConfig.from_dict(cfg["agent"])
    except (TypeError, ValueError) as e:
        raise ValueError(f"{Path(run_dir) / 'config.yaml'}: agent: {e}") from None
    env = make_env(cfg["env"], cfg.get("env_kwargs", {}), render_mode)
    try:
        return load_run_agent(ck, run_dir, env, cfg["algo"], stored), env, cfg, at
    except ValueError:
        env.close()
        raise


def load_checkpoint(run_dir: str | Path, agent: SAC, stream: Stream) -> int:
    """Restore ``agent``'s state and ``stream`` from the run's latest checkpoint; return the
    number of interactions it holds. CheckpointError naming the file on any mismatch. The
    training loop attaches the stream to the agent when it goes on (:func:`lili.train.train`).
    """
    ck, n = latest_checkpoint(run_dir)
    loaded = load_run_agent(ck, run_dir, agent.env, agent.algo, agent.config)
    try:
        with np.load(ck / "stream.npz", allow_pickle=False) as d:
            parts = dict(d)
    except Exception:
        raise CheckpointError(f"{ck / 'stream.npz'} is missing or corrupt") from None
    stream.load_state_dict(parts, str(ck / "stream.npz"))
    if stream.count != n or loaded.trained_interactions != n:
        raise CheckpointError(f"{ck} is inconsistent: latest.json says {n} interactions, the "
                              f"stream holds {stream.count}, the agent "
                              f"{loaded.trained_interactions}")
    agent.state = loaded.state
    return n


def _read_rows(path: Path, columns: list[str]) -> tuple[list[list[str]], bool]:
    """The rows of ``metrics.csv`` under its header ``columns``, and whether the file is one
    written before the ``random`` column existed (then its rows lack that cell)."""
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise CheckpointError(f"{path} cannot be read: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise CheckpointError(f"{path} is not UTF-8 text (byte {e.start}); restore the file or "
                              "start a new run") from None
    legacy = [c for c in columns if c != RANDOM]
    if not rows or rows[0] not in (columns, legacy):
        got = shown(rows[0]) if rows else "nothing"
        raise CheckpointError(f"{path} has columns {got}; expected {columns} (was it edited?)")
    return rows[1:], rows[0] == legacy


def _check_logged(path: Path, rows: list[list[str]], stream: Stream, n: int) -> None:
    """The first ``n`` rows must be interactions 0..n-1 whose returns match the buffer."""
    if len(rows) < n:
        raise CheckpointError(f"{path} holds {len(rows)} rows but the checkpoint is at "
                              f"interaction {n}: rows were deleted; restore the file or start "
                              "a new run")
    buf = stream.buffer
    rew = np.asarray(buf.arrays["rew"]).sum(-1)
    for j, r in enumerate(rows[:n]):
        try:
            index, ret = int(r[0]), float(r[1])
        except (ValueError, IndexError):
            raise CheckpointError(f"{path} line {j + 2} is not a number where one belongs "
                                  f"({r[:2]}); restore the file or start a new run") from None
        if index != j:
            raise CheckpointError(f"{path} line {j + 2} is interaction {index}, expected {j}: "
                                  "rows were deleted or reordered")
        if buf.stored(j) and not math.isclose(ret, float(rew[j % buf.capacity]),
                                              rel_tol=1e-4, abs_tol=1e-4):
            raise CheckpointError(f"{path} line {j + 2} says return {ret}, the checkpoint "
                                  f"{float(rew[j % buf.capacity]):.6g}: the file was edited")


def resume_run(run_dir: str | Path, agent: SAC, stream: Stream,
               strategy_dim: int) -> int:
    """Load the run's latest checkpoint into ``agent`` and ``stream`` and check that
    ``metrics.csv`` still holds what it logged. Writes nothing; returns the interactions done.
    A run killed before its first checkpoint restarts from 0."""
    run_dir = Path(run_dir)
    if not (run_dir / "checkpoints" / "latest.json").exists():
        return 0
    n = load_checkpoint(run_dir, agent, stream)
    path = run_dir / "metrics.csv"
    _check_logged(path, _read_rows(path, metric_columns(strategy_dim))[0], stream, n)
    try:
        read_extras(run_dir / EXTRAS, n)
    except (ValueError, OSError, UnicodeDecodeError) as e:
        raise CheckpointError(f"{e}; restore the file or start a new run") from None
    return n


_ROW_KEYS = frozenset({"interaction", "return", "length", "success", RANDOM, "strategy",
                       "strategy_id", "wall_time", *METRIC_COLUMNS})
"""The keys of a training row that ``metrics.csv`` holds; any other goes to ``block_extras``."""


class RunLogger:
    """Writes one run folder while :func:`lili.train.train` runs (see the module docstring).

    Construct it only after every input is validated (:func:`resume_run` for a resume): it
    writes ``config.yaml``, cuts ``metrics.csv`` back to ``start`` rows and opens TensorBoard.
    ``config`` is what ``config.yaml`` holds; on a resume of a file without the ``random``
    column, that column is recomputed from it for the rows kept.
    """

    def __init__(self, run_dir: Path, config: dict[str, Any], strategy_dim: int,
                 checkpoint_every: int, start: int = 0) -> None:
        self.dir = Path(run_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.checkpoint_every = checkpoint_every
        # The code that trains is what was imported now; the checkout may move on before the
        # run ends (a commit while it trains), so the summary names this commit, not that one.
        self.git_commit = _git_commit()
        self.columns = metric_columns(strategy_dim)
        self.strategy_dim = strategy_dim
        path = self.dir / "metrics.csv"
        rows, legacy = _read_rows(path, self.columns) if start > 0 else ([], False)
        rows = rows[:start]
        if legacy:
            at = self.columns.index(RANDOM)
            drawn = random_column(config, len(rows))
            rows = [r[:at] + [str(int(d))] + r[at:] for r, d in zip(rows, drawn, strict=True)]
        (self.dir / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
        with path.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(self.columns)
            w.writerows(rows)
        self._csv_file = path.open("a", newline="")
        self._csv = csv.writer(self._csv_file)
        from tensorboardX import SummaryWriter

        # TensorBoard holds what metrics.csv holds: a resumed run's old event files go (a run
        # killed after its last checkpoint, or before its first, wrote events that the resumed
        # run writes again) and the rows kept are written anew, at 6 digits as in the CSV.
        for old in (self.dir / "tb").glob("events.out.tfevents.*"):
            old.unlink()
        self.tb = SummaryWriter(str(self.dir / "tb"))
        success = self.columns.index("success")
        self.returns, self.successes = [], []
        for r in rows:
            cells = dict(zip(self.columns, r, strict=False))
            self._record(int(r[0]), float(r[1]),
                         None if r[success] == "" else float(r[success]),
                         {k: float(cells[k]) for k in METRIC_COLUMNS if cells.get(k, "") != ""})
        self.random = [r[self.columns.index(RANDOM)] == "1" for r in rows]
        # Opened on the first line to write, so that runs whose blocks report nothing beyond the
        # columns get no file; a resume keeps the lines of the interactions it keeps.
        self.extras: dict[str, float] = {}
        self._extras_file: TextIO | None = None
        kept = read_extras(self.dir / EXTRAS, start) if start > 0 else []
        (self.dir / EXTRAS).unlink(missing_ok=True)
        for line in kept:
            self._write_extras(line)

    def _record(self, i: int, ret: float, success: float | bool | None,
                metrics: dict[str, float]) -> None:
        """Interaction ``i``'s return, success and losses into the in-memory lists (one success
        cell per interaction, NaN where the env reports none) and TensorBoard."""
        self.returns.append(ret)
        self.tb.add_scalar("interaction/return", ret, i)
        self.successes.append(math.nan if success is None else float(success))
        if success is not None:
            self.tb.add_scalar("interaction/success", float(success), i)
        for k, v in metrics.items():
            self.tb.add_scalar(f"train/{k}", v, i)

    def _write_extras(self, line: dict[str, Any]) -> None:
        """One ``block_extras.jsonl`` line into the file, TensorBoard and the newest values."""
        if self._extras_file is None:
            self._extras_file = (self.dir / EXTRAS).open("a")
        self._extras_file.write(json.dumps(line) + "\n")
        self._extras_file.flush()
        i = line["interaction"]
        for k, v in line.items():
            if k != "interaction":
                self.extras[k] = v
                self.tb.add_scalar(f"train/{k}", v, i)

    def log(self, row: dict[str, Any], agent: SAC, stream: Stream) -> None:
        """Append one interaction's row; checkpoint every ``checkpoint_every`` interactions."""
        i = row["interaction"]
        success = row["success"]
        values = [i, f"{row['return']:.6g}", row["length"],
                  "" if success is None else int(success), int(row["random"])]
        # An env that reports no strategy (or not on every interaction) leaves the cells empty.
        strategy = [f"{v:.6g}" for v in row["strategy"]][: self.strategy_dim]
        values += strategy + [""] * (self.strategy_dim - len(strategy))
        values += [row["strategy_id"]]
        values += [f"{row[k]:.6g}" if k in row else "" for k in METRIC_COLUMNS]
        values += [f"{row['wall_time']:.3f}"]
        self._csv.writerow(values)
        self._csv_file.flush()
        self._record(i, row["return"], success, {k: row[k] for k in METRIC_COLUMNS if k in row})
        self.random.append(bool(row["random"]))
        extras = {k: float(v) for k, v in row.items() if k not in _ROW_KEYS}
        if extras:
            self._write_extras({"interaction": i, **extras})
        if (i + 1) % self.checkpoint_every == 0:
            self.checkpoint(agent, stream)

    def checkpoint(self, agent: SAC, stream: Stream) -> Path:
        """Write ``checkpoints/ckpt_<n>`` completely, then point ``latest.json`` at it."""
        self.tb.flush()
        root = self.dir / "checkpoints"
        n = stream.count
        ck = root / f"ckpt_{n}"
        if ck.exists():
            shutil.rmtree(ck)
        ck.mkdir(parents=True)
        agent.save(ck / "agent.msgpack")
        np.savez(ck / "stream.npz", **stream.state_dict())
        tmp = root / "latest.json.tmp"
        tmp.write_text(json.dumps({"checkpoint": ck.name, "interactions": n}))
        tmp.replace(root / "latest.json")
        for old in root.glob("ckpt_*"):
            if old != ck:
                shutil.rmtree(old, ignore_errors=True)
        return ck

    def finish(self, agent: SAC, stream: Stream, config: dict[str, Any]) -> dict[str, Any]:
        """Final checkpoint and ``summary.json``.

        With ``AgentConfig.random_interactions`` the summary also holds
        ``final_return_policy`` / ``final_success_policy``: the same final means over the
        policy's own interactions (those played at random after the warm-up left out, as
        ``lili report --policy-only`` does), since ``final_return`` counts every interaction.
        """
        if stream.count % self.checkpoint_every != 0:
            self.checkpoint(agent, stream)
        summary = {
            "env": config["env"],
            "algo": config["algo"],
            "seed": config["seed"],
            "interactions": stream.count,
            "final_return": _final(self.returns),
            "final_success": _final(self.successes),
            **self._policy_only(agent),
            **({"block_extras": dict(self.extras)} if self.extras else {}),
            "wall_time_s": round(stream.wall_time, 2),
            "cpu_time_s": (round(stream.cpu_time, 2) if np.isfinite(stream.cpu_time)
                           else None),
            "versions": _versions(),
            "git_commit": self.git_commit,
        }
        (self.dir / "summary.json").write_text(json.dumps(summary, indent=2))
        self.close()
        return summary

    def _policy_only(self, agent: SAC) -> dict[str, float | None]:
        """The final means over the policy's own interactions; empty without random ones."""
        cfg = agent.config
        if cfg.random_interactions <= 0:
            return {}
        own = ~left_out_of_policy(np.asarray(self.random), cfg.warmup_interactions)
        return {"final_return_policy": _final(np.asarray(self.returns)[own]),
                "final_success_policy": _final(np.asarray(self.successes)[own])}

    def close(self) -> None:
        self.tb.close()
        self._csv_file.close()
        if self._extras_file is not None:
            self._extras_file.close()
