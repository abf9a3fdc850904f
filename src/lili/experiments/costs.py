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
from lili.runs import read_run_config

__all__ = ["COSTS", "WARM", "cost_key", "estimate_seconds", "measure"]

WARM = 30

# python benchmarks/costs.py --preset paper --timed 10 --jobs 2 (benchmarks/results/costs.md),
# 2026-12-01, two keys side by side on the 2-core machine. Check against full runs: Point Mass
# LILI 0.722 s here, 0.70-0.73 s per interaction of wall time in the 2000-interaction runs that
# ran two at a time (benchmarks/results/runs/s9/point-mass).
COSTS: dict[tuple[str, str, int], tuple[float, float]] = {
    ("lili/PointMass-v0", "sac", 1): (17.6, 0.4941),
    ("lili/PointMass-v0", "slac", 1): (64.0, 1.2963),
    ("lili/PointMass-v0", "lilac", 1): (35.3, 0.9376),
    ("lili/PointMass-v0", "lili-no-influence", 1): (26.0, 0.6585),
    ("lili/PointMass-v0", "lili", 1): (26.9, 0.7219),
    ("lili/PointMass-v0", "oracle", 1): (19.9, 0.5220),
    ("lili/PointMass-v0", "lili", 3): (34.0, 0.8607),
    ("lili/PointMass-v0", "lili", 5): (32.3, 1.0844),
    ("lili/PointMass-v0", "lili", 7): (34.7, 1.1694),
    ("lili/PointMass-v0", "lili", 9): (35.0, 1.4931),
    ("lili/PointMass-v0", "lili", 11): (39.5, 1.7192),
    ("lili/Driving2D-v0", "sac", 1): (14.6, 0.0941),
    ("lili/Driving2D-v0", "slac", 1): (54.9, 0.2813),
    ("lili/Driving2D-v0", "lilac", 1): (27.4, 0.2259),
    ("lili/Driving2D-v0", "lili-no-influence", 1): (20.4, 0.1507),
    ("lili/Driving2D-v0", "lili", 1): (23.4, 0.1588),
    ("lili/Driving2D-v0", "oracle", 1): (14.9, 0.0895),
    ("lili/DrivingSteer-v0", "sac", 1): (15.1, 0.1855),
    ("lili/DrivingSteer-v0", "slac", 1): (57.0, 0.5530),
    ("lili/DrivingSteer-v0", "lilac", 1): (32.2, 0.4136),
    ("lili/DrivingSteer-v0", "lili-no-influence", 1): (24.5, 0.2959),
    ("lili/DrivingSteer-v0", "lili", 1): (25.2, 0.3537),
    ("lili/DrivingSteer-v0", "oracle", 1): (16.0, 0.1859),
    ("lili/LunarLander-v0", "sac", 1): (20.1, 0.5863),
    ("lili/LunarLander-v0", "slac", 1): (77.9, 1.6456),
    ("lili/LunarLander-v0", "lilac", 1): (44.2, 1.2375),
    ("lili/LunarLander-v0", "lili-no-influence", 1): (29.4, 0.9335),
    ("lili/LunarLander-v0", "lili", 1): (33.5, 0.9115),
    ("lili/LunarLander-v0", "oracle", 1): (21.5, 0.6582),
    ("lili/AirHockey-v0", "random", 1): (9.0, 0.0054),
    ("lili/AirHockey-v0", "sac", 1): (18.2, 0.3088),
    ("lili/AirHockey-v0", "lili-no-influence", 1): (27.6, 0.4125),
    ("lili/AirHockey-v0", "lili", 1): (27.5, 0.4670),
    ("lili/AirHockey-v0", "oracle", 1): (18.4, 0.2904),
    # Influence suite (not in paper): the cpu_time_s of the committed 2000-interaction runs
    # (benchmarks/results/runs/s10/influence), two runs side by side; fixed part not split out.
    ("lili/InfluenceDrift-v0", "sac", 1): (20.0, 0.046),
    ("lili/InfluenceDrift-v0", "lili-no-influence", 1): (20.0, 0.064),
    ("lili/InfluenceDrift-v0", "lili", 1): (20.0, 0.067),
    ("lili/InfluenceDrift-v0", "oracle", 1): (20.0, 0.047),
    ("lili/InfluenceSwitch-v0", "sac", 1): (20.0, 0.047),
    ("lili/InfluenceSwitch-v0", "lili-no-influence", 1): (20.0, 0.066),
    ("lili/InfluenceSwitch-v0", "lili", 1): (20.0, 0.067),
    ("lili/InfluenceSwitch-v0", "oracle", 1): (20.0, 0.046),
    # Not measured yet: Switch's, whose horizon, sizes and updates per interaction Flee shares.
    ("lili/InfluenceFlee-v0", "sac", 1): (20.0, 0.047),
    ("lili/InfluenceFlee-v0", "lili-no-influence", 1): (20.0, 0.066),
    ("lili/InfluenceFlee-v0", "lili", 1): (20.0, 0.067),
    ("lili/InfluenceFlee-v0", "oracle", 1): (20.0, 0.046),
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
        history = int(read_run_config(path.parent)["agent"].get("history", 1))
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
