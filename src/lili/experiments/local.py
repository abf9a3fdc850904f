"""Local backend: up to ``jobs`` ``lili train`` processes at a time on this machine."""

from __future__ import annotations

import subprocess

from lili.experiments.plan import RunSpec
from lili.experiments.runner import start

__all__ = ["LocalBackend"]


class LocalBackend:
    """Runs each :class:`RunSpec` as a child process; :meth:`poll` reports finished ones."""

    description = "local processes"

    def __init__(self, jobs: int) -> None:
        self.capacity = jobs
        self._running: dict[RunSpec, subprocess.Popen] = {}

    def submit(self, spec: RunSpec) -> None:
        """Start ``spec`` now."""
        self._running[spec] = start(spec)

    def poll(self) -> list[tuple[RunSpec, int]]:
        """(spec, exit code) of every run that ended since the last call."""
        ended = [(s, p.returncode) for s, p in self._running.items() if p.poll() is not None]
        for spec, _ in ended:
            del self._running[spec]
        return ended

    def close(self) -> None:
        """Stop the runs still going (they resume from their last checkpoint next time)."""
        for proc in self._running.values():
            proc.terminate()
        for proc in self._running.values():
            proc.wait()
        self._running.clear()
