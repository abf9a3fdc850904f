"""Environment speed: env steps per second for every registered env, random actions, one core.

    python benchmarks/envs.py [--steps 5000] [--repeats 3] [--envs lili/PointMass-v0 ...]

Each env runs ``--steps`` steps of uniform random actions (resetting at the end of every
interaction, so the partner update is included); the best of ``--repeats`` timings counts,
because these machines are shared. Prints a table beside the issues' floors (DrivingSteer
>= 300 steps/s, AirHockey >= 2000 steps/s) and writes ``benchmarks/results/envs.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

from lili.envs import ENV_ALIASES

RESULTS = Path(__file__).resolve().parent / "results"
FLOORS = {"lili/DrivingSteer-v0": 300.0, "lili/AirHockey-v0": 2000.0}


def steps_per_second(env_id: str, steps: int, seed: int = 0) -> tuple[float, float]:
    """(env steps per second, mean interaction length) over ``steps`` random-action steps."""
    env = gym.make(env_id)
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    env.action_space.seed(seed)
    ends = 0
    t0 = time.perf_counter()
    for _ in range(steps):
        a = rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32)
        _, _, terminated, truncated, _ = env.step(a)
        if terminated or truncated:
            ends += 1
            env.reset()
    elapsed = time.perf_counter() - t0
    env.close()
    return steps / elapsed, steps / max(ends, 1)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=5000)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--envs", nargs="+", default=sorted(set(ENV_ALIASES.values())))
    args = p.parse_args()
    rows = []
    for env_id in args.envs:
        timings = [steps_per_second(env_id, args.steps, seed) for seed in range(args.repeats)]
        best = max(t[0] for t in timings)
        floor = FLOORS.get(env_id)
        rows.append({"env": env_id, "steps_per_s": best, "mean_length": timings[0][1],
                     "floor": floor, "ok": None if floor is None else best >= floor})
    lines = [f"| env | steps/s (best of {args.repeats}) | mean interaction length | floor |",
             "|---|---:|---:|---|"]
    for r in rows:
        floor = "—"
        if r["floor"] is not None:
            floor = f">= {r['floor']:.0f} ({'ok' if r['ok'] else 'MISSED'})"
        lines.append(
            f"| {r['env']} | {r['steps_per_s']:,.0f} | {r['mean_length']:.1f} | {floor} |")
    print("\n".join(lines))
    RESULTS.mkdir(exist_ok=True)
    payload = {"rows": rows, "steps": args.steps, "repeats": args.repeats,
               "machine": platform.platform(), "python": platform.python_version()}
    (RESULTS / "envs.json").write_text(json.dumps(payload, indent=1))


if __name__ == "__main__":
    main()
