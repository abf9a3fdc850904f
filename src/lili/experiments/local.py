"""Local backend: up to ``jobs`` ``lili train`` processes at a time on this machine, each
training one job (:data:`lili.experiments.runner.Job`: one run, or seeds trained together)."""

from __future__ import annotations

import subprocess

from lili.experiments.runner import Job, start

__all__ = ["LocalBackend"]


class LocalBackend:
    """Runs each job as a child process; :meth:`poll` reports finished ones."""

    description = "local processes"

    def __init__(self, jobs: int, device: str | None = None) -> None:
        self.capacity = jobs
        self.device = device
        self._running: dict[Job, subprocess.Popen] = {}

    def submit(self, job: Job) -> None:
        """Start ``job`` now."""
        self._running[job] = start(job, self.device)

    def poll(self) -> list[tuple[Job, int]]:
        """(job, exit code) of every job that ended since the last call."""
        ended = [(j, p.returncode) for j, p in self._running.items() if p.poll() is not None]
        for job, _ in ended:
            del self._running[job]
        return ended

    def close(self) -> None:
        """Stop the runs still going (they resume from their last checkpoint next time)."""
        for proc in self._running.values():
            proc.terminate()
        for proc in self._running.values():
            proc.wait()
        self._running.clear()
