"""Per-run CPU cost estimates, for ``--dry-run`` and the ETA.

:data:`COSTS` holds, per cost key (env, algo, encoder history), the CPU-seconds of a run's fixed
part (process start, imports, JAX compiles, the warm-up and SLAC's pretraining, up to interaction
:data:`WARM`) and of each interaction after it, measured by ``benchmarks/costs.py`` with one XLA
thread per process as ``lili reproduce`` runs them (``time.process_time``: the figures do not
depend on what else shared the machine). Noise levels and other env kwargs do not change the
work per interaction; the history does (the encoder reads N interactions). A run's wall time
is its CPU time when it has a core to itself, so ``--jobs J`` on J free cores takes about the
CPU time over J.

``python -m lili.experiments.costs RUNS_DIR`` prints the CPU-seconds per interaction of every
finished run under a folder (``cpu_time_s`` of ``summary.json``; runs from before it was
recorded show their wall time, marked), to check the table against full runs.
"""

from __future__ import annotations

import json
import statistics
import sys
from collections import defaultdict
from pathlib import Path

from lili.experiments.plan import RunSpec

__all__ = ["COSTS", "WARM", "cost_key", "estimate_seconds", "measure"]

WARM = 30

# benchmarks/costs.py --preset paper --timed 30 (see benchmarks/results/costs.md).
COSTS: dict[tuple[str, str, int], tuple[float, float]] = {
}


def cost_key(spec: RunSpec) -> tuple[str, str, int]:
    """(env, algo, encoder history) of a run: what its cost per interaction depends on."""
    return spec.env, spec.algo, int(spec.config.get("history", 1))


def estimate_seconds(spec: RunSpec, done: int = 0) -> float:
    """Estimated CPU-seconds of ``spec`` from interaction ``done`` on (start-up included).

    A key without a measurement borrows the nearest measured history of the same env and algo,
    else the env's slowest measured algo, else 1 s per interaction, so that the estimate errs
    on the long side.
    """
    env, algo, history = cost_key(spec)
    cost = COSTS.get((env, algo, history))
    if cost is None:
        same = [(abs(h - history), c) for (e, a, h), c in COSTS.items() if (e, a) == (env, algo)]
        same_env = [c for (e, _, _), c in COSTS.items() if e == env]
        cost = (min(same)[1] if same else max(same_env, key=lambda c: c[1]) if same_env
                else (30.0, 1.0))
    fixed, per = cost
    # A resumed run starts again (imports, compiles, replay) and pays the fixed part again.
    return fixed + per * max(0, spec.interactions - max(done, WARM))


def measure(root: str | Path) -> dict[tuple[str, str, int], tuple[float, bool]]:
    """Median over seeds of the CPU-seconds per interaction of every finished run under
    ``root``, keyed like :data:`COSTS`; the flag is True where only wall time was recorded."""
    rates: dict[tuple[str, str, int], list[tuple[float, bool]]] = defaultdict(list)
    for path in sorted(Path(root).rglob("summary.json")):
        s = json.loads(path.read_text())
        if not s.get("interactions"):
            continue
        try:
            import yaml

            history = int(yaml.safe_load((path.parent / "config.yaml").read_text())
                          ["agent"].get("history", 1))
        except Exception:
            history = 1
        cpu = s.get("cpu_time_s")
        seconds, wall = (cpu, False) if cpu is not None else (s["wall_time_s"], True)
        rates[(s["env"], s["algo"], history)].append((seconds / s["interactions"], wall))
    return {k: (statistics.median(r for r, _ in v), any(w for _, w in v))
            for k, v in sorted(rates.items())}


if __name__ == "__main__":
    for (env, algo, history), (rate, wall) in measure(
            sys.argv[1] if len(sys.argv) > 1 else ".").items():
        print(f"{env} {algo} history={history}: {rate:.3f} s/interaction"
              + (" (wall time; no cpu_time_s)" if wall else ""))
