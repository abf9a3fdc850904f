"""Progress of a sweep: one overall bar (runs done / total, ETA from per-run estimates) above
one bar per running run (its metrics.csv rows). Plain lines when not on a terminal."""

from __future__ import annotations

import sys
import time

from lili.experiments.costs import estimate_seconds
from lili.experiments.plan import RunSpec
from lili.experiments.runner import rows_logged

__all__ = ["SweepProgress"]


class SweepProgress:
    """Tracks runs; ``live`` draws rich bars, otherwise start/end lines are printed."""

    def __init__(self, total: list[RunSpec], done: int, live: bool | None = None) -> None:
        self.live = sys.stdout.isatty() if live is None else live
        self.total = len(total) + done
        self.done = done
        self._left = {s: estimate_seconds(s, rows_logged(s)) for s in total}
        self._start: dict[RunSpec, float] = {}
        self._tasks: dict[RunSpec, int] = {}
        self._t0 = time.time()
        self._spent = 0.0
        self._estimated_done = 0.0
        if self.live:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
            )

            self._bars = Progress(TextColumn("{task.description}"), BarColumn(),
                                  MofNCompleteColumn(), TextColumn("{task.fields[eta]}"),
                                  TimeElapsedColumn())
            self._overall = self._bars.add_task("runs", total=self.total, completed=done,
                                                eta=self._eta())
            self._bars.start()

    def _eta(self, capacity: int = 1) -> str:
        left = sum(self._left.values())
        # Scale the estimates by how the finished runs compared with theirs.
        if self._estimated_done > 0:
            left *= self._spent / self._estimated_done
        return f"ETA {left / max(capacity, 1) / 60:.0f} min"

    def started(self, spec: RunSpec) -> None:
        self._start[spec] = time.time()
        if self.live:
            self._tasks[spec] = self._bars.add_task(spec.name, total=spec.interactions,
                                                    completed=rows_logged(spec), eta="")
        else:
            print(f"start {spec.name}", flush=True)

    def ended(self, spec: RunSpec, code: int, capacity: int) -> None:
        took = time.time() - self._start.pop(spec, time.time())
        self._spent += took
        self._estimated_done += self._left.pop(spec, 0.0)
        self.done += 1
        status = "ok" if code == 0 else f"FAILED (exit {code})"
        if self.live:
            self._bars.remove_task(self._tasks.pop(spec))
            self._bars.update(self._overall, completed=self.done, eta=self._eta(capacity))
            self._bars.console.print(f"done {spec.name}: {status} in {took:.0f} s")
        else:
            print(f"done  {spec.name}: {status} in {took:.0f} s ({self.done}/{self.total})",
                  flush=True)

    def refresh(self, capacity: int) -> None:
        if not self.live:
            return
        for spec, task in self._tasks.items():
            self._bars.update(task, completed=rows_logged(spec))
        self._bars.update(self._overall, eta=self._eta(capacity))

    def stop(self) -> None:
        if self.live:
            self._bars.stop()
