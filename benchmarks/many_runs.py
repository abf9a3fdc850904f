"""Many runs in one program against one run per process, end to end, on this machine's device.

    python benchmarks/many_runs.py [--algo lili] [--env lili/PointMass-v0] [--ks 1 2 4 8]
                                   [--interactions 20] [--processes] [--name many_runs]

For each K: K runs of ``--algo`` (seeds 0..K-1, the paper's sizes) train together through
``lili.many.train_many`` (the Gymnasium envs stepping in Python, one vmapped act per step, one
vmapped update block per interaction). Each run first plays its warm-up and one more interaction
(compiling everything, untimed); then ``--interactions`` more are timed. Reported: interactions
per second of all K runs together, env steps per second, updates per second, and the replay
buffer memory per run. With ``--processes`` the same K runs are also trained as K separate
processes at once (``lili.train.train``, one per process, timed the same way inside each) for
the ratio the issue asks about: K runs in one process against K processes on the same cores.
Prints a table and writes ``benchmarks/results/<name>.json``. Measure on an otherwise idle
machine: the numbers are wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import jax

import lili.envs  # noqa: F401
from lili.agents import make_agent
from lili.config import AgentConfig
from lili.many import group_nbytes, group_streams, train_many
from lili.train import Stream, train

RESULTS = Path(__file__).resolve().parent / "results"


def _agents(algo: str, env: str, k: int):
    return [make_agent(algo, env, AgentConfig(), seed) for seed in range(k)]


def timed_group(algo: str, env: str, k: int, n: int) -> dict:
    """Interactions per second of K runs trained together (module docstring)."""
    agents = _agents(algo, env, k)
    streams = group_streams(agents)
    warm = agents[0].config.warmup_interactions + 1
    train_many(agents, streams, warm)
    t = time.perf_counter()
    rows = train_many(agents, streams, n)
    wall = time.perf_counter() - t
    steps = sum(r["length"] for run in rows for r in run)
    updates = k * n * agents[0].core.n_updates
    return {"k": k, "wall_s": round(wall, 3), "interactions_per_s": round(k * n / wall, 2),
            "env_steps_per_s": round(steps / wall, 1), "updates_per_s": round(updates / wall, 1),
            "buffer_mib_per_run": round(group_nbytes(agents) / k / 2**20, 2)}


def timed_alone(algo: str, env: str, seed: int, n: int) -> float:
    """Seconds one run (in this process) takes for ``n`` interactions after its warm-up."""
    agent = make_agent(algo, env, AgentConfig(), seed)
    stream = Stream.for_agent(agent, agent.env)
    train(agent, stream, agent.config.warmup_interactions + 1)
    t = time.perf_counter()
    train(agent, stream, n)
    return time.perf_counter() - t


def timed_processes(algo: str, env: str, k: int, n: int) -> dict:
    """K runs as K processes at once: each times its own ``n`` interactions."""
    cmd = [sys.executable, __file__, "--worker", "--algo", algo, "--env", env,
           "--interactions", str(n)]
    procs = [subprocess.Popen([*cmd, "--seed", str(s)], stdout=subprocess.PIPE, text=True)
             for s in range(k)]
    walls = [float(p.communicate()[0].strip().splitlines()[-1]) for p in procs]
    return {"k": k, "wall_s": round(max(walls), 3),
            "interactions_per_s": round(k * n / max(walls), 2)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--algo", default="lili")
    p.add_argument("--env", default="lili/PointMass-v0")
    p.add_argument("--ks", type=int, nargs="+", default=[1, 2, 4, 8])
    p.add_argument("--interactions", type=int, default=20)
    p.add_argument("--processes", action="store_true", help="also K separate processes")
    p.add_argument("--name", default="many_runs")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.worker:
        print(timed_alone(args.algo, args.env, args.seed, args.interactions))
        return
    rows = []
    for k in args.ks:
        row = {"one_program": timed_group(args.algo, args.env, k, args.interactions)}
        if args.processes:
            row["k_processes"] = timed_processes(args.algo, args.env, k, args.interactions)
            row["ratio"] = round(row["one_program"]["interactions_per_s"]
                                 / row["k_processes"]["interactions_per_s"], 2)
        rows.append(row)
        one = row["one_program"]
        line = (f"K={k:5d}  one program: {one['interactions_per_s']:8.2f} interactions/s "
                f"{one['env_steps_per_s']:9.1f} steps/s {one['updates_per_s']:9.1f} updates/s "
                f"buffer {one['buffer_mib_per_run']} MiB/run")
        if args.processes:
            line += (f"  | {k} processes: {row['k_processes']['interactions_per_s']:8.2f} "
                     f"interactions/s  (one program / processes: {row['ratio']}x)")
        print(line, flush=True)
    out = {"algo": args.algo, "env": args.env, "interactions_timed": args.interactions,
           "device": jax.devices()[0].device_kind, "platform": platform.platform(),
           "cpus": os.cpu_count(), "jax": jax.__version__, "rows": rows}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{args.name}.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
