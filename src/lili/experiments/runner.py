"""How one run is executed: the ``lili train`` command line, its log and its environment.

This is the one place that calls into training (through the ``lili train`` command, one
process per run), so that both backends produce the same run folders and a change of the
training API is ported here only.
"""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
from pathlib import Path

import yaml

from lili.experiments.plan import RunSpec, run_status

__all__ = ["train_command", "log_path", "child_env", "write_agent_configs", "run_blocking",
           "rows_logged"]

# Asks XLA for no intra-op threading, since runs go side by side and threading these small
# matrices only adds contention. Measured (2 cores, Point Mass LILI): it does not give one
# thread; each run still keeps two Eigen threads busy (1.8 cores alone, 0.41 s/interaction;
# 0.73-0.76 s two side by side). Pinning each run to a core with taskset gained only ~10%,
# and the flags are kept rather than affinity because they leave the numbers of existing
# records unchanged.
XLA_FLAGS = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"


def _config_path(spec: RunSpec) -> Path:
    # One per algo: a preset's --set reaches only the algos that read the field.
    return spec.experiment / f"agent_config-{spec.algo}.yaml"


def write_agent_configs(specs: list[RunSpec]) -> None:
    """Write each experiment folder's ``agent_config-<algo>.yaml`` (the ``--config`` of its
    runs of that algo)."""
    written: dict[Path, dict] = {}
    for spec in specs:
        if not spec.config:
            continue
        path = _config_path(spec)
        if path in written:
            if written[path] != spec.config:
                raise ValueError(f"runs in {spec.experiment} need different agent configs")
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(yaml.safe_dump(spec.config, sort_keys=True))
        written[path] = spec.config


def train_command(spec: RunSpec, python: str = sys.executable) -> list[str]:
    """The ``lili train`` command of ``spec``; ``--resume`` when its folder holds a started run.

    The folder is looked at now, not when the run was planned, so that a retried Ray task
    resumes from the checkpoint its killed attempt left.
    """
    cmd = [python, "-m", "lili.cli", "train", spec.env, "--algo", spec.algo, "--seed",
           str(spec.seed), "--interactions", str(spec.interactions), "--out",
           str(spec.experiment), "--no-progress"]
    if spec.config:
        cmd += ["--config", str(_config_path(spec))]
    for key, value in spec.env_kwargs.items():
        cmd += ["--env-kwarg", f"{key}={value}"]
    if run_status(spec) == "resume":
        cmd.append("--resume")
    return cmd


def log_path(spec: RunSpec) -> Path:
    """Where the run's stdout and stderr go: ``<experiment>/logs/<env>-<algo>-seed_<k>.log``."""
    return spec.run_dir.parents[2] / "logs" / (
        f"{spec.run_dir.parents[1].name}-{spec.algo}-seed_{spec.seed}.log")


def child_env() -> dict[str, str]:
    """This process's environment with XLA's intra-op threading turned off (see XLA_FLAGS)."""
    return dict(os.environ, XLA_FLAGS=XLA_FLAGS)


def _die_with_parent() -> None:
    """In the child: get SIGKILL when the parent dies (Linux), so no orphan keeps training."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def start(spec: RunSpec) -> subprocess.Popen:
    """Start ``spec`` as a child process writing to :func:`log_path`."""
    log = log_path(spec)
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("a") as f:
        preexec = _die_with_parent if sys.platform.startswith("linux") else None
        return subprocess.Popen(train_command(spec), stdout=f, stderr=subprocess.STDOUT,
                                env=child_env(), preexec_fn=preexec)


def run_blocking(spec: RunSpec) -> int:
    """Run ``spec`` to the end (what a Ray task does); returns the exit code."""
    return start(spec).wait()


def rows_logged(spec: RunSpec) -> int:
    """Interactions the run has logged so far (rows of metrics.csv), read without parsing."""
    try:
        with (spec.run_dir / "metrics.csv").open("rb") as f:
            return max(0, sum(1 for _ in f) - 1)
    except OSError:
        return 0
