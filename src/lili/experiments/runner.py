"""How one run is executed: the ``lili train`` command line, its log and its environment.

This is the one place that calls into training (through the ``lili train`` command, one
process per job), so that both backends produce the same run folders and a change of the
training API is ported here only. A job is a tuple of runs that train in one program
(``lili train --seeds``, :mod:`lili.many`): :func:`group_runs` makes them, one run each by
default.
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

__all__ = ["Job", "group_runs", "groupable", "train_command", "log_path", "child_env",
           "write_agent_configs", "run_blocking", "rows_logged", "DEVICES"]

Job = tuple[RunSpec, ...]
"""Runs that train together in one process (one run, or seeds of one cell: :func:`group_runs`)."""

DEVICES = ("cpu", "gpu")
"""``lili reproduce --device`` values: the JAX platform the runs' processes use."""

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


def groupable(algo: str) -> bool:
    """Whether runs of ``algo`` can train in one program (:func:`lili.many.check_group_algo`:
    a SAC-family agent whose update is the shared block); read from the algo's class, so that
    no list of algos is kept here."""
    from lili.many import check_group_algo

    try:
        check_group_algo(algo)
    except ValueError:
        return False
    return True


def _cell(spec: RunSpec) -> tuple:
    """What runs of one job share: everything but the seed, and the state on disk (a job
    starts or resumes all of its runs)."""
    return (str(spec.experiment), spec.env, spec.algo, spec.interactions, spec.backend,
            yaml.safe_dump(spec.env_kwargs, sort_keys=True),
            yaml.safe_dump(spec.config, sort_keys=True), run_status(spec) == "resume")


def group_runs(specs: list[RunSpec], size: int = 1) -> list[Job]:
    """``specs`` as jobs of at most ``size`` runs each, in the order of each job's first run:
    runs of one cell (same experiment, env, algo, budget, backend, env options and agent config;
    new, or all started) whose algo is :func:`groupable` share a job; every other run is a job of
    its own."""
    if size < 1:
        raise ValueError(f"--group {size} is invalid; allowed: an integer >= 1")
    jobs: list[list[RunSpec]] = []
    open_jobs: dict[tuple, list[RunSpec]] = {}
    can: dict[str, bool] = {}
    for spec in specs:
        if size > 1 and can.setdefault(spec.algo, groupable(spec.algo)):
            key = _cell(spec)
            job = open_jobs.get(key)
            if job is not None and len(job) < size:
                job.append(spec)
                continue
            open_jobs[key] = job = [spec]
        else:
            job = [spec]
        jobs.append(job)
    return [tuple(job) for job in jobs]


def train_command(job: RunSpec | Job, python: str = sys.executable) -> list[str]:
    """The ``lili train`` command of ``job`` (one run, or runs of one cell trained together
    with ``--seeds``), with ``--backend jax`` for runs of the JAX-native path; ``--resume``
    when its folders hold started runs.

    The folders are looked at now, not when the runs were planned, so that a retried Ray task
    resumes from the checkpoint its killed attempt left.
    """
    job = _as_job(job)
    spec = job[0]
    seeds = (["--seed", str(spec.seed)] if len(job) == 1
             else ["--seeds", ",".join(str(s.seed) for s in job)])
    cmd = [python, "-m", "lili.cli", "train", spec.env, "--algo", spec.algo, *seeds,
           "--interactions", str(spec.interactions), "--out", str(spec.experiment),
           "--no-progress"]
    if spec.config:
        cmd += ["--config", str(_config_path(spec))]
    for key, value in spec.env_kwargs.items():
        cmd += ["--env-kwarg", f"{key}={value}"]
    if spec.backend != "gym":
        cmd += ["--backend", spec.backend]
    if run_status(spec) == "resume":
        cmd.append("--resume")
    return cmd


def _as_job(job: RunSpec | Job) -> Job:
    return (job,) if isinstance(job, RunSpec) else tuple(job)


def log_path(job: RunSpec | Job) -> Path:
    """Where the job's stdout and stderr go: ``<experiment>/logs/<env>-<algo>-seed_<k>.log``
    for one run, ``...-seeds_<k1>,<k2>,....log`` for runs trained together."""
    job = _as_job(job)
    spec = job[0]
    seeds = (f"seed_{spec.seed}" if len(job) == 1
             else "seeds_" + ",".join(str(s.seed) for s in job))
    return spec.run_dir.parents[2] / "logs" / (
        f"{spec.run_dir.parents[1].name}-{spec.algo}-{seeds}.log")


def child_env(device: str | None = None) -> dict[str, str]:
    """This process's environment with XLA's intra-op threading turned off (see XLA_FLAGS),
    on ``device`` (:data:`DEVICES`; None: JAX's own choice), and without XLA's preallocation
    of GPU memory, so that several runs' processes can share one GPU."""
    env = dict(os.environ, XLA_FLAGS=XLA_FLAGS, XLA_PYTHON_CLIENT_PREALLOCATE="false")
    if device is not None:
        env["JAX_PLATFORMS"] = {"cpu": "cpu", "gpu": "cuda"}[device]
    return env


def _die_with_parent() -> None:
    """In the child: get SIGKILL when the parent dies (Linux), so no orphan keeps training."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def start(job: RunSpec | Job, device: str | None = None) -> subprocess.Popen:
    """Start ``job`` as a child process writing to :func:`log_path`."""
    log = log_path(job)
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("a") as f:
        preexec = _die_with_parent if sys.platform.startswith("linux") else None
        return subprocess.Popen(train_command(job), stdout=f, stderr=subprocess.STDOUT,
                                env=child_env(device), preexec_fn=preexec)


def run_blocking(job: RunSpec | Job, device: str | None = None) -> int:
    """Run ``job`` to the end (what a Ray task does); returns the exit code. A retried job
    whose killed attempt left some runs started and others not runs them as two commands."""
    job = _as_job(job)
    code = 0
    for part in _by_state(job):
        code = start(part, device).wait() or code
    return code


def _by_state(job: Job) -> list[Job]:
    status = {s: run_status(s) for s in job}
    parts = (tuple(s for s in job if status[s] == "resume"),
             tuple(s for s in job if status[s] == "new"))
    return [part for part in parts if part]


def rows_logged(spec: RunSpec) -> int:
    """Interactions the run has logged so far (rows of metrics.csv), read without parsing."""
    try:
        with (spec.run_dir / "metrics.csv").open("rb") as f:
            return max(0, sum(1 for _ in f) - 1)
    except OSError:
        return 0
