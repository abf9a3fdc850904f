"""Run folders: ``<out>/<env>/<algo>/seed_<k>/`` with config, metrics, TensorBoard, checkpoints.

- ``config.yaml``: the resolved configuration (env id and kwargs, algo, seed, budget, agent).
- ``metrics.csv``: one row per interaction (return, length, success, strategy, losses, time).
- ``tb/``: TensorBoard event files (tensorboardX).
- ``checkpoints/``: the newest checkpoint ``ckpt_<n>/`` (agent, buffer, action log) and
  ``latest.json`` pointing at it; the pointer is replaced atomically after the checkpoint is
  complete, so a run killed at any moment loses at most one checkpoint interval.
- ``summary.json``: final metrics, versions, git commit, wall time.
"""

from __future__ import annotations

import csv
import json
import platform
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import yaml

import lili
from lili.agents.sac import SAC, CheckpointError

__all__ = ["RunLogger", "run_dir_for", "load_checkpoint", "METRIC_COLUMNS", "final_mean"]

METRIC_COLUMNS = ("critic_loss", "actor_loss", "alpha", "rep_loss", "q", "entropy")


def run_dir_for(out: str | Path, env_id: str, algo: str, seed: int) -> Path:
    """The run folder of (env, algo, seed) under the experiment folder ``out``."""
    return Path(out) / env_id.split("/")[-1] / algo / f"seed_{seed}"


def final_mean(values: list[float], frac: float = 0.1) -> float:
    """Mean over the last ``frac`` of the values (at least one): the paper's final performance."""
    n = max(1, int(round(len(values) * frac)))
    return float(np.mean(values[-n:]))


def _git_commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                             cwd=Path(__file__).parent, timeout=5)
        return out.stdout.strip() or None
    except Exception:
        return None


def _versions() -> dict[str, str]:
    import flax
    import gymnasium
    import jax

    return {"lili": lili.__version__, "python": platform.python_version(), "jax": jax.__version__,
            "flax": flax.__version__, "gymnasium": gymnasium.__version__,
            "numpy": np.__version__}


class RunLogger:
    """Writes one run folder while :func:`lili.train.train` runs (see the module docstring)."""

    def __init__(self, run_dir: Path, config: dict[str, Any], strategy_dim: int,
                 checkpoint_every: int, start: int = 0) -> None:
        self.dir = Path(run_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.checkpoint_every = checkpoint_every
        (self.dir / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
        self.columns = (["interaction", "return", "length", "success"]
                        + [f"strategy_{j}" for j in range(strategy_dim)]
                        + ["strategy_id", *METRIC_COLUMNS, "wall_time"])
        path = self.dir / "metrics.csv"
        if start > 0 and path.exists():
            self._truncate(path, start)
        else:
            with path.open("w", newline="") as f:
                csv.writer(f).writerow(self.columns)
        self._csv_file = path.open("a", newline="")
        self._csv = csv.writer(self._csv_file)
        from tensorboardX import SummaryWriter

        # purge_step drops events a killed run wrote after its last checkpoint.
        self.tb = SummaryWriter(str(self.dir / "tb"), purge_step=start if start > 0 else None)
        self.returns: list[float] = []
        self.successes: list[float] = []
        if start > 0:
            self._reload_history()

    def _truncate(self, path: Path, n: int) -> None:
        with path.open(newline="") as f:
            rows = list(csv.reader(f))
        header, body = rows[0], rows[1:]
        if header != self.columns:
            raise CheckpointError(f"{path} has columns {header}; expected {self.columns}")
        with path.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(header)
            w.writerows(r for r in body if int(r[0]) < n)

    def _reload_history(self) -> None:
        with (self.dir / "metrics.csv").open(newline="") as f:
            for r in csv.DictReader(f):
                self.returns.append(float(r["return"]))
                if r["success"] != "":
                    self.successes.append(float(r["success"]))

    def log(self, row: dict[str, Any], agent: SAC) -> None:
        """Append one interaction's row; checkpoint every ``checkpoint_every`` interactions."""
        i = row["interaction"]
        success = row["success"]
        values = [i, f"{row['return']:.6g}", row["length"],
                  "" if success is None else int(success)]
        values += [f"{v:.6g}" for v in row["strategy"]]
        values += [row["strategy_id"]]
        values += [f"{row[k]:.6g}" if k in row else "" for k in METRIC_COLUMNS]
        values += [f"{row['wall_time']:.3f}"]
        self._csv.writerow(values)
        self._csv_file.flush()
        self.returns.append(row["return"])
        self.tb.add_scalar("interaction/return", row["return"], i)
        if success is not None:
            self.successes.append(float(success))
            self.tb.add_scalar("interaction/success", float(success), i)
        for k in METRIC_COLUMNS:
            if k in row:
                self.tb.add_scalar(f"train/{k}", row[k], i)
        if (i + 1) % self.checkpoint_every == 0:
            self.checkpoint(agent)

    def checkpoint(self, agent: SAC) -> Path:
        """Write ``checkpoints/ckpt_<n>`` completely, then point ``latest.json`` at it."""
        self.tb.flush()
        root = self.dir / "checkpoints"
        n = agent.num_interactions
        ck = root / f"ckpt_{n}"
        if ck.exists():
            shutil.rmtree(ck)
        ck.mkdir(parents=True)
        agent.save(ck / "agent.msgpack")
        np.savez(ck / "buffer.npz", **agent.buffer.state_dict())
        lengths = np.array([len(a) for a in agent.action_log], np.int32)
        acts = np.zeros((len(lengths), agent.horizon, agent.act_dim), np.float32)
        for j, a in enumerate(agent.action_log):
            acts[j, : len(a)] = a
        np.savez(ck / "actions.npz", actions=acts, lengths=lengths)
        (ck / "run.json").write_text(json.dumps({"interactions": n,
                                                 "wall_time": agent.wall_time}))
        tmp = root / "latest.json.tmp"
        tmp.write_text(json.dumps({"checkpoint": ck.name, "interactions": n}))
        tmp.replace(root / "latest.json")
        for old in root.glob("ckpt_*"):
            if old != ck:
                shutil.rmtree(old, ignore_errors=True)
        return ck

    def finish(self, agent: SAC, config: dict[str, Any]) -> dict[str, Any]:
        """Final checkpoint and ``summary.json``."""
        if agent.num_interactions % self.checkpoint_every != 0:
            self.checkpoint(agent)
        summary = {
            "env": config["env"],
            "algo": config["algo"],
            "seed": config["seed"],
            "interactions": agent.num_interactions,
            "final_return": final_mean(self.returns) if self.returns else None,
            "final_success": final_mean(self.successes) if self.successes else None,
            "wall_time_s": round(agent.wall_time, 2),
            "versions": _versions(),
            "git_commit": _git_commit(),
        }
        (self.dir / "summary.json").write_text(json.dumps(summary, indent=2))
        self.close()
        return summary

    def close(self) -> None:
        self.tb.close()
        self._csv_file.close()


def load_checkpoint(run_dir: Path, agent: SAC) -> None:
    """Restore ``agent`` (state, buffer, action log) from the run folder's latest checkpoint.

    Raises CheckpointError naming the file when anything is missing, corrupt or mismatched.
    """
    root = Path(run_dir) / "checkpoints"
    pointer = root / "latest.json"
    if not pointer.is_file():
        raise CheckpointError(f"no checkpoint to resume in {root} (latest.json is missing)")
    try:
        ck = root / json.loads(pointer.read_text())["checkpoint"]
        meta = json.loads((ck / "run.json").read_text())
    except Exception:
        raise CheckpointError(f"{pointer} is corrupt or points at a missing checkpoint") from None
    from lili.agents import load_agent

    loaded = load_agent(ck / "agent.msgpack", agent.env)
    if loaded.algo != agent.algo:
        raise CheckpointError(f"{ck} holds a {loaded.algo!r} agent; this run is {agent.algo!r}")
    if loaded.config != agent.config:
        raise CheckpointError(f"{ck} was trained with another agent config than {run_dir}")
    agent.state = loaded.state
    agent.num_interactions = loaded.num_interactions
    try:
        with np.load(ck / "buffer.npz", allow_pickle=False) as d:
            agent.buffer.load_state_dict(dict(d))
        with np.load(ck / "actions.npz", allow_pickle=False) as d:
            acts, lengths = d["actions"], d["lengths"]
    except CheckpointError:
        raise
    except Exception as e:
        raise CheckpointError(f"{ck} has a corrupt buffer or action log: {e}") from None
    if len(lengths) != agent.num_interactions or agent.buffer.count != agent.num_interactions:
        raise CheckpointError(f"{ck} is inconsistent: its parts hold different interaction counts")
    agent.action_log = [acts[j, :n].copy() for j, n in enumerate(lengths)]
    agent.wall_time = float(meta.get("wall_time", 0.0))
    agent._pending = None
