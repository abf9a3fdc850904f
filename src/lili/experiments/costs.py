"""Per-run cost estimates, from measured wall times, for ``--dry-run`` and the ETA.

:data:`SECONDS_PER_INTERACTION` holds, per (env, algo), the median over seeds of
``wall_time_s / interactions`` of the committed records (``benchmarks/results/runs/*``, full
budgets, two runs sharing the 2-core machine most of the time, so this is a wall time per run at
``--jobs 2``, which is also about the CPU time of one core). Where no record exists the entry
says how it was measured instead. ``python -m lili.experiments.costs RUNS_DIR`` prints the same
medians from any folder of finished runs, to refresh the table.
"""

from __future__ import annotations

import json
import statistics
import sys
from collections import defaultdict
from pathlib import Path

from lili.experiments.plan import RunSpec

__all__ = ["SECONDS_PER_INTERACTION", "STARTUP_SECONDS", "estimate_seconds", "measure"]

# Start-up of one `lili train` process (imports, env, JAX compiles), measured: a 6-interaction
# Point Mass LILI run took 25 CPU-seconds, almost none of it training.
STARTUP_SECONDS = 25.0

SECONDS_PER_INTERACTION: dict[tuple[str, str], float] = {
    # Committed records (median of 3 seeds).
    ("lili/PointMass-v0", "sac"): 0.639,
    ("lili/PointMass-v0", "slac"): 0.794,
    ("lili/PointMass-v0", "lilac"): 0.593,
    ("lili/PointMass-v0", "lili-no-influence"): 0.630,
    ("lili/PointMass-v0", "lili"): 1.745,
    ("lili/PointMass-v0", "oracle"): 0.629,
    ("lili/Driving2D-v0", "sac"): 0.239,
    ("lili/Driving2D-v0", "slac"): 0.303,
    ("lili/Driving2D-v0", "lilac"): 0.293,
    ("lili/Driving2D-v0", "lili-no-influence"): 0.343,
    ("lili/Driving2D-v0", "lili"): 0.369,
    ("lili/Driving2D-v0", "oracle"): 0.234,
    ("lili/DrivingSteer-v0", "sac"): 0.289,
    ("lili/DrivingSteer-v0", "lili"): 0.395,
    ("lili/DrivingSteer-v0", "oracle"): 0.320,
    ("lili/LunarLander-v0", "sac"): 0.326,
    ("lili/LunarLander-v0", "lili"): 0.490,
    ("lili/LunarLander-v0", "oracle"): 0.333,
    # No records: 60-interaction runs measured the rate over interactions 30-59 (with 3-7
    # processes on the 2 cores): Driving (steering) SAC 0.266, SLAC 1.051, LILAC 0.714, LILI
    # (no influence) 0.459 s. Scaled by SAC's record / SAC's short rate (0.289 / 0.266); Lunar
    # Lander's SLAC, LILAC, LILI (no influence) = its SAC record x the same algo / SAC ratio.
    ("lili/DrivingSteer-v0", "slac"): 1.14,
    ("lili/DrivingSteer-v0", "lilac"): 0.78,
    ("lili/DrivingSteer-v0", "lili-no-influence"): 0.50,
    ("lili/LunarLander-v0", "slac"): 1.29,
    ("lili/LunarLander-v0", "lilac"): 0.87,
    ("lili/LunarLander-v0", "lili-no-influence"): 0.56,
    # Air hockey: its records were lost; benchmarks/README.md's table gives the measured wall
    # time per 1000-interaction run (Random 14 s, SAC 6 min, LILI (no influence) 9 min, LILI
    # 10 min). The Oracle is SAC with a longer observation: SAC's figure.
    ("lili/AirHockey-v0", "random"): 0.014,
    ("lili/AirHockey-v0", "sac"): 0.36,
    ("lili/AirHockey-v0", "lili-no-influence"): 0.54,
    ("lili/AirHockey-v0", "lili"): 0.60,
    ("lili/AirHockey-v0", "oracle"): 0.36,
}


def estimate_seconds(spec: RunSpec, done: int = 0) -> float:
    """Estimated seconds of ``spec`` from interaction ``done`` on (start-up included).

    An (env, algo) without a measurement gets the env's slowest measured algo (or 1 s per
    interaction for an env never measured), so that the estimate errs on the long side.
    """
    rate = SECONDS_PER_INTERACTION.get((spec.env, spec.algo))
    if rate is None:
        same_env = [v for (env, _), v in SECONDS_PER_INTERACTION.items() if env == spec.env]
        rate = max(same_env) if same_env else 1.0
    return STARTUP_SECONDS + rate * max(0, spec.interactions - done)


def measure(root: str | Path) -> dict[tuple[str, str], float]:
    """Median over seeds of wall_time_s / interactions of every finished run under ``root``."""
    rates: dict[tuple[str, str], list[float]] = defaultdict(list)
    for path in sorted(Path(root).rglob("summary.json")):
        s = json.loads(path.read_text())
        if s.get("interactions"):
            rates[(s["env"], s["algo"])].append(s["wall_time_s"] / s["interactions"])
    return {k: statistics.median(v) for k, v in sorted(rates.items())}


if __name__ == "__main__":
    for (env, algo), rate in measure(sys.argv[1] if len(sys.argv) > 1 else ".").items():
        print(f'    ("{env}", "{algo}"): {rate:.3f},')
