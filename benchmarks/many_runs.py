"""Many runs in one program, end to end, on this machine's device: the Gymnasium path and the
JAX-native path.

    python benchmarks/many_runs.py [--path gym|jax|both] [--algo lili] [--env point-mass]
                                   [--ks 1 2 4 8] [--interactions 20] [--config small.yaml]
                                   [--env-kwarg step_noise=0.2] [--budget 2000] [--processes]
                                   [--memory-fraction 0.5] [--name many_runs] [--out-dir DIR]

For each path and each K, K runs of ``--algo`` (seeds 0..K-1; the paper's sizes unless
``--config`` changes them) train together:

- ``gym``: :func:`lili.many.train_many` (K Gymnasium envs stepping in Python, one act program
  per step, one update-block program per interaction, each mapped over the runs by
  :func:`lili.agents.multiseed.over_seeds`: ``vmap`` on an accelerator, ``lax.map`` on a CPU);
- ``jax``: :class:`lili.jax_train.JaxRuns` (the JAX twin of the env; one jitted program per
  interaction, mapped over the runs by the same ``over_seeds``: acting and env steps as a scan,
  the buffer write, the update block, the next latent).

Each run first plays its warm-up and one more interaction (compiling everything; timed apart as
``first_s``), then ``--interactions`` more are timed (one value for every K, or one per K).
Reported: interactions per second of all K runs together, env steps and updates per second, the
replay buffer per run and, where the device reports it, the device memory in use per run. With
``--budget N``, each JAX row also extrapolates the wall time of K runs of N interactions:
``first_s`` plus the timed seconds per interaction times the rest (labelled extrapolated; the
buffers fill as the runs go on, which costs the block nothing: it samples a fixed batch). With
``--processes`` the Gymnasium path is also run as K separate processes (``lili.train.train``)
for the ratio the issue asks about. Prints a table and writes ``<out-dir>/<name>.json`` (default
``benchmarks/results``) with the device (``jax.devices()``) and the platform. Measure on an
otherwise idle machine: the numbers are wall time.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import jax

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import RESULTS, check_result_name  # noqa: E402


def _config(path: str | None):
    from lili.config import AgentConfig, load_config

    return load_config(path) if path else AgentConfig()


def _kwargs(pairs: list[str]) -> dict:
    from lili.cli import _parse_kwargs

    return _parse_kwargs(pairs)


def _device_memory() -> dict:
    """The device's memory counters where it reports them (GPUs do; the CPU does not)."""
    try:
        stats = jax.devices()[0].memory_stats() or {}
    except Exception:
        stats = {}
    return {k: stats[k] for k in ("peak_bytes_in_use", "bytes_in_use", "bytes_limit")
            if k in stats}


def _row(path: str, k: int, n: int, wall: float, first: float, steps: int, n_updates: int,
         buffer_each: int) -> dict:
    mem = _device_memory()
    row = {"path": path, "k": k, "interactions_timed": n, "first_s": round(first, 2),
           "wall_s": round(wall, 3), "s_per_interaction": round(wall / n, 4),
           "interactions_per_s": round(k * n / wall, 2),
           "env_steps_per_s": round(steps / wall, 1),
           "updates_per_s": round(k * n * n_updates / wall, 1),
           "buffer_mib_per_run": round(buffer_each / 2**20, 2)}
    if "bytes_in_use" in mem:  # the K runs' live arrays, measured while they are alive
        row["device_in_use_mib_per_run"] = round(mem["bytes_in_use"] / k / 2**20, 2)
    if "peak_bytes_in_use" in mem:  # the process's peak so far (a larger K before counts)
        row["device_peak_mib"] = round(mem["peak_bytes_in_use"] / 2**20, 1)
    return row


def timed_gym(algo: str, env: str, k: int, n: int, config, env_kwargs: dict) -> dict:
    """K runs through :func:`lili.many.train_many` (module docstring)."""
    from lili.agents import make_agent
    from lili.envs.core import resolve_env_id
    from lili.envs.spec import make_env
    from lili.many import group_nbytes, group_streams, train_many

    env_id = resolve_env_id(env)
    t = time.perf_counter()
    agents = [make_agent(algo, make_env(env_id, env_kwargs), config, s) for s in range(k)]
    streams = group_streams(agents)
    train_many(agents, streams, agents[0].config.warmup_interactions + 1)
    first = time.perf_counter() - t
    t = time.perf_counter()
    rows = train_many(agents, streams, n)
    wall = time.perf_counter() - t
    steps = sum(r["length"] for run in rows for r in run)
    return _row("gym", k, n, wall, first, steps, agents[0].core.n_updates,
                group_nbytes(agents) // k)


def timed_jax(algo: str, env: str, k: int, n: int, config, env_kwargs: dict,
              budget: int | None, fraction: float = 0.5) -> dict:
    """K runs through :class:`lili.jax_train.JaxRuns` (module docstring)."""
    from lili.buffer import buffer_nbytes
    from lili.jax_train import JaxRuns

    t = time.perf_counter()
    runs = JaxRuns(algo, env, list(range(k)), config, env_kwargs, fraction=fraction)
    warm = runs.config.warmup_interactions + 1
    runs.train(warm, keep_rows=False)
    first = time.perf_counter() - t
    t = time.perf_counter()
    rows = runs.train(n)
    wall = time.perf_counter() - t
    steps = sum(r["length"] for run in rows for r in run)
    core = runs.core
    row = _row("jax", k, n, wall, first, steps, core.n_updates,
               buffer_nbytes(runs.config.buffer_capacity, core.horizon, core.obs_dim,
                             core.act_dim))
    if budget:
        row["budget_interactions"] = budget
        row["extrapolated_budget_s"] = round(first + (budget - warm) * wall / n, 1)
    return row


def timed_alone(algo: str, env: str, seed: int, n: int) -> float:
    """Seconds one run (in this process) takes for ``n`` interactions after its warm-up."""
    from lili.agents import make_agent
    from lili.config import AgentConfig
    from lili.train import Stream, train

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
    return {"path": "k_processes", "k": k, "wall_s": round(max(walls), 3),
            "interactions_per_s": round(k * n / max(walls), 2)}


def _line(r: dict) -> str:
    if "error" in r:
        return f"{r['path']:>11s} K={r['k']:5d}  failed: {r['error']}"
    if r["path"] == "k_processes":
        return f"{'processes':>11s} K={r['k']:5d}  {r['interactions_per_s']:9.2f} interactions/s"
    line = (f"{r['path']:>11s} K={r['k']:5d}  {r['interactions_per_s']:9.2f} interactions/s "
            f"{r['env_steps_per_s']:11.1f} steps/s {r['updates_per_s']:10.1f} updates/s  "
            f"buffer {r['buffer_mib_per_run']} MiB/run  first {r['first_s']} s")
    if "device_in_use_mib_per_run" in r:
        line += f"  device {r['device_in_use_mib_per_run']} MiB/run"
    if "extrapolated_budget_s" in r:
        line += (f"  {r['budget_interactions']} interactions: {r['extrapolated_budget_s']} s "
                 "(extrapolated)")
    return line


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--path", choices=("gym", "jax", "both"), default="both")
    p.add_argument("--algo", default="lili")
    p.add_argument("--env", default="lili/PointMass-v0")
    p.add_argument("--ks", type=int, nargs="+", default=[1, 2, 4, 8])
    p.add_argument("--interactions", type=int, nargs="+", default=[20],
                   help="timed interactions: one value, or one per K")
    p.add_argument("--config", help="YAML file with AgentConfig fields to change")
    p.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--budget", type=int, help="extrapolate K runs of this many interactions "
                                              "(JAX path)")
    p.add_argument("--processes", action="store_true", help="also K separate processes (gym)")
    p.add_argument("--memory-fraction", type=float, default=0.5,
                   help="JAX path: the share of the device's free memory the K replay buffers "
                        "may take (default 0.5)")
    p.add_argument("--name", default="many_runs")
    p.add_argument("--out-dir", default=str(RESULTS))
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.worker:
        print(timed_alone(args.algo, args.env, args.seed, args.interactions[0]))
        return
    check_result_name(p, args.name)
    if len(args.interactions) not in (1, len(args.ks)):
        p.error(f"--interactions takes one value or one per K ({len(args.ks)}); got "
                f"{len(args.interactions)}")
    ns = args.interactions * len(args.ks) if len(args.interactions) == 1 else args.interactions
    config, env_kwargs = _config(args.config), _kwargs(args.env_kwarg)
    paths = ("gym", "jax") if args.path == "both" else (args.path,)
    rows: list[dict] = []
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    result = out_dir / f"{args.name}.json"
    head = {"algo": args.algo, "env": args.env, "env_kwargs": env_kwargs,
            "config": config.to_dict(), "budget": args.budget,
            "devices": [str(d) for d in jax.devices()], "device": jax.devices()[0].device_kind,
            "backend": jax.default_backend(), "platform": platform.platform(),
            "machine": platform.machine(), "cpus": os.cpu_count(), "jax": jax.__version__,
            "python": platform.python_version(), "load_average_at_start": os.getloadavg()}
    for which in paths:
        for k, n in zip(args.ks, ns, strict=True):
            try:
                if which == "gym":
                    row = timed_gym(args.algo, args.env, k, n, config, env_kwargs)
                else:
                    row = timed_jax(args.algo, args.env, k, n, config, env_kwargs, args.budget,
                                    args.memory_fraction)
            except Exception as e:  # e.g. out of device memory at the largest K: keep the rest
                row = {"path": which, "k": k, "error": f"{type(e).__name__}: {str(e)[:300]}"}
            rows.append(row)
            print(_line(row), flush=True)
            # Written after every row: a run stopped by a time limit keeps what it measured.
            head["load_average_now"] = os.getloadavg()
            result.write_text(json.dumps({**head, "rows": rows}, indent=2) + "\n")
            gc.collect()
            if which == "gym" and args.processes and "error" not in row:
                proc = timed_processes(args.algo, args.env, k, n)
                proc["ratio"] = round(row["interactions_per_s"] / proc["interactions_per_s"], 2)
                rows.append(proc)
                print(_line(proc) + f"  (one program / processes: {proc['ratio']}x)", flush=True)
    result.write_text(json.dumps({**head, "rows": rows}, indent=2) + "\n")
    print(f"wrote {result}")


if __name__ == "__main__":
    main()
