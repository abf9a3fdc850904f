"""What a training run costs beyond its update block, on this CPU (issue 33, item 5).

    python benchmarks/run_cost.py [--algo lili] [--env lili/PointMass-v0] [--interactions 40]

For each condition (one or two processes side by side; XLA's default intra-op threading or the
flags ``lili reproduce`` gives its runs, :data:`lili.experiments.runner.XLA_FLAGS`) every
process trains one run exactly as ``lili train`` does (a real run folder: metrics.csv,
TensorBoard, checkpoints) and times, inside that same process, each part of an interaction
after the warm-up: the update block, acting, the env's steps and the rest of the rollout, the
next acting state (the encoder), the logger, and what is left. So run cost and block cost are
measured in the same conditions, and the table says what else costs more than 10% of a run.
Prints a table and writes ``benchmarks/results/run_cost.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _results import RESULTS, check_result_name

PARTS = ("block", "act", "env", "next_state", "logger")


class _Timer:
    """Wall and CPU seconds spent in wrapped calls, per part."""

    def __init__(self) -> None:
        self.wall = dict.fromkeys(PARTS, 0.0)
        self.cpu = dict.fromkeys(PARTS, 0.0)
        self.on = False

    def wrap(self, part: str, fn):
        def timed(*args, **kwargs):
            if not self.on:
                return fn(*args, **kwargs)
            w, c = time.perf_counter(), time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                self.wall[part] += time.perf_counter() - w
                self.cpu[part] += time.process_time() - c
        return timed


def child(algo: str, env_id: str, n: int, seed: int) -> dict:
    """Train one run (warm-up, then ``n`` timed interactions) and time its parts."""
    import gymnasium as gym
    import numpy as np

    import lili.envs  # noqa: F401
    import lili.train as lt
    from lili.agents import make_agent
    from lili.config import AgentConfig
    from lili.runs import RunLogger
    from lili.train import Stream, train

    timer = _Timer()
    env = gym.make(env_id)
    cfg = AgentConfig()
    agent = make_agent(algo, env, cfg, seed=seed)
    stream = Stream.for_agent(agent, agent.env)
    agent.train_block = timer.wrap("block", agent.train_block)
    agent.act = timer.wrap("act", agent.act)
    agent.next_state = timer.wrap("next_state", agent.next_state)
    # rollout's env steps go through lili.train.env_step; the rest of rollout is Python glue.
    lt.env_step = timer.wrap("env", lt.env_step)
    with tempfile.TemporaryDirectory() as tmp:
        strategy_dim = int(np.prod(env.unwrapped.strategy_space.shape))
        logger = RunLogger(Path(tmp), {"algo": algo, "env": env_id, "seed": seed},
                           strategy_dim, cfg.checkpoint_every)
        logger.log = timer.wrap("logger", logger.log)
        t = time.perf_counter()
        train(agent, stream, cfg.warmup_interactions + 2, logger=logger)
        first = time.perf_counter() - t
        timer.on = True
        w, c = time.perf_counter(), time.process_time()
        train(agent, stream, n, logger=logger)
        wall, cpu = time.perf_counter() - w, time.process_time() - c
    return {"first_s": first, "wall_per_interaction": wall / n, "cpu_per_interaction": cpu / n,
            "parts_wall": {k: v / n for k, v in timer.wall.items()},
            "parts_cpu": {k: v / n for k, v in timer.cpu.items()}}


def condition(args, procs: int, flags: bool) -> list[dict]:
    """``procs`` child processes side by side; their results."""
    from lili.experiments.runner import XLA_FLAGS

    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    env["JAX_PLATFORMS"] = "cpu"
    if flags:
        env["XLA_FLAGS"] = XLA_FLAGS
    cmd = [sys.executable, __file__, "--child", "--algo", args.algo, "--env", args.env,
           "--interactions", str(args.interactions)]
    children = [subprocess.Popen(cmd + ["--seed", str(k)], env=env, stdout=subprocess.PIPE,
                                 text=True) for k in range(procs)]
    out = []
    for p in children:
        stdout, _ = p.communicate()
        if p.returncode != 0:
            for other in children:  # the others' timings would be of another condition
                other.kill()
                other.wait()
            raise SystemExit(f"a child failed (exit {p.returncode})")
        out.append(json.loads(stdout.strip().splitlines()[-1]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--algo", default="lili")
    ap.add_argument("--env", default="lili/PointMass-v0")
    ap.add_argument("--interactions", type=int, default=40, help="timed, after the warm-up")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--name", default="run_cost")
    args = ap.parse_args()
    # Checked here, before any child starts (these import no agent and no JAX).
    from lili.agents.registry import ALGOS
    from lili.envs.core import resolve_env_id
    from lili.limits import MAX_INTERACTIONS, check_count

    if args.algo not in ALGOS:
        ap.error(f"--algo {args.algo!r} is invalid; allowed: {', '.join(ALGOS)}")
    try:
        args.env = resolve_env_id(args.env)
        check_count(args.interactions, "--interactions", MAX_INTERACTIONS)
    except ValueError as e:
        ap.error(str(e))
    check_result_name(ap, args.name)
    if args.child:
        print(json.dumps(child(args.algo, args.env, args.interactions, args.seed)))
        return
    load = os.getloadavg()
    rows = []
    for flags in (False, True):
        for procs in (1, 2):
            res = condition(args, procs, flags)
            mean = {k: sum(r[k] for r in res) / procs
                    for k in ("wall_per_interaction", "cpu_per_interaction", "first_s")}
            parts = {p: sum(r["parts_wall"][p] for r in res) / procs for p in PARTS}
            rows.append({"procs": procs, "xla_flags": flags, **mean, "parts_wall": parts,
                         "runs": res})
            print(f"done: procs {procs}, flags {flags}: {mean['wall_per_interaction']:.3f} s",
                  flush=True)
    head = ("| XLA flags | processes | s/interaction (wall) | CPU-s/interaction | "
            "interactions/s (all) | " + " | ".join(PARTS) + " | other |")
    lines = [head, "|" + "---|" * (6 + len(PARTS))]
    for r in rows:
        w = r["wall_per_interaction"]
        other = w - sum(r["parts_wall"].values())
        shares = " | ".join(f"{r['parts_wall'][p]:.3f} ({100 * r['parts_wall'][p] / w:.0f}%)"
                            for p in PARTS)
        lines.append(f"| {'runner' if r['xla_flags'] else 'default'} | {r['procs']} | {w:.3f} | "
                     f"{r['cpu_per_interaction']:.3f} | {r['procs'] / w:.2f} | {shares} | "
                     f"{other:.3f} ({100 * other / w:.0f}%) |")
    table = "\n".join(lines)
    print(table)
    import jax

    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.name}.json").write_text(json.dumps({
        "algo": args.algo, "env": args.env, "interactions": args.interactions,
        "cpu_count": os.cpu_count(), "loadavg_before": load, "loadavg_after": os.getloadavg(),
        "jax": jax.__version__, "rows": rows, "table": table}, indent=1))


if __name__ == "__main__":
    main()
