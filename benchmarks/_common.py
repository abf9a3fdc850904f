"""Shared driver of the learning benchmarks: train a grid of (algo, seed) runs, then report.

Runs are ``lili train`` processes (so the benchmark measures exactly what users run), ``--jobs``
at a time; finished runs are skipped and interrupted ones resumed, so a benchmark can be stopped
and restarted.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ALGOS = ["sac", "oracle", "lili", "lili-no-influence"]


def parse_args(description: str, algos: list[str], interactions: int, seeds: int = 3):
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--algos", nargs="+", default=algos)
    p.add_argument("--seeds", type=int, default=seeds)
    p.add_argument("--interactions", type=int, default=interactions)
    p.add_argument("--jobs", type=int, default=2, help="runs in parallel (default 2 = cores)")
    p.add_argument("--out", default=None, help="experiment folder")
    p.add_argument("--config", default=None, help="AgentConfig YAML for every run")
    return p.parse_args()


def run_grid(env: str, algos: list[str], seeds: int, interactions: int, out: Path, jobs: int,
             config: str | None = None, env_kwargs: tuple[str, ...] = ()) -> None:
    """Train every (algo, seed) with ``lili train`` (skip finished runs, resume killed ones)."""
    lili = str(Path(sys.executable).parent / "lili")
    from lili.envs import resolve_env_id

    env_dir = resolve_env_id(env).split("/")[-1]
    queue = []
    for seed in range(seeds):
        for algo in algos:
            run = out / env_dir / algo / f"seed_{seed}"
            if (run / "summary.json").exists():
                done = json.loads((run / "summary.json").read_text())
                if done["interactions"] >= interactions:
                    continue
            cmd = [lili, "train", env, "--algo", algo, "--seed", str(seed), "--interactions",
                   str(interactions), "--out", str(out), "--no-progress"]
            if config:
                cmd += ["--config", config]
            for kv in env_kwargs:
                cmd += ["--env-kwarg", kv]
            if (run / "metrics.csv").exists():
                cmd.append("--resume")
            queue.append((algo, seed, cmd))
    running: list[tuple[str, int, subprocess.Popen, float]] = []
    while queue or running:
        while queue and len(running) < jobs:
            algo, seed, cmd = queue.pop(0)
            log = (out / "logs")
            log.mkdir(parents=True, exist_ok=True)
            f = open(log / f"{env_dir}_{algo}_{seed}.log", "w")
            print(f"start {algo} seed {seed}", flush=True)
            # One XLA thread per run: with --jobs runs side by side, intra-op threading of
            # these small matrices only adds contention.
            env = dict(os.environ, XLA_FLAGS="--xla_cpu_multi_thread_eigen=false "
                       "intra_op_parallelism_threads=1")
            proc = subprocess.Popen(cmd, stdout=f, stderr=f, env=env)
            running.append((algo, seed, proc, time.time()))
        for item in list(running):
            algo, seed, proc, t0 = item
            if proc.poll() is not None:
                running.remove(item)
                status = "ok" if proc.returncode == 0 else f"FAILED ({proc.returncode})"
                print(f"done  {algo} seed {seed}: {status} in {time.time() - t0:.0f} s",
                      flush=True)
        time.sleep(1)


def report(out: Path, name: str) -> dict:
    """Write the report of every run under ``out`` and a JSON of the summary; print the table."""
    from lili.report import markdown_table, write_report

    summary = write_report([out], out / "report")
    table = markdown_table(summary)
    print(table)
    results = ROOT / "benchmarks" / "results"
    results.mkdir(exist_ok=True)
    (results / f"{name}.json").write_text(json.dumps(summary, indent=1, default=str))
    (results / f"{name}.md").write_text(table + "\n")
    for png in (out / "report").glob("*.png"):
        shutil.copy(png, results / f"{name}_{png.name}")
    return summary


def benchmark(env: str, name: str, doc: str, interactions: int,
              algos: list[str] | None = None) -> dict:
    """Command-line entry of a learning benchmark: parse flags, train the grid, report."""
    args = parse_args(doc.splitlines()[0], algos or ALGOS, interactions=interactions)
    out = Path(args.out) if args.out else ROOT / "runs" / f"bench_{name}"
    run_grid(env, args.algos, args.seeds, args.interactions, out, args.jobs, args.config)
    return report(out, name)
