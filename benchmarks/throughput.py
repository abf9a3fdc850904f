"""Loop speed: end-to-end training throughput against Stable-Baselines3, side by side in one run.

    pip install -e '.[bench]'          # stable-baselines3 + torch
    python benchmarks/throughput.py [--interactions 60] [--threads 1 2]

For each XLA thread count (one worker process each, since XLA reads its flags at start-up) and
for SAC and LILI on Point Mass at the paper's sizes (batch 256, 2x256 actor and critic, one
update per env step, H = 50):

- **end to end**: env steps per second of ``train`` (acting, env, buffer, the fused update
  block, logging of nothing) after warm-up and compilation;
- **update block**: the block alone on the same buffer, in ms per update;
- **loop efficiency**: update-block time / wall time per env step (the share of the loop spent
  in the updates; the rest is acting, the env and the buffer);
- **SB3**: Stable-Baselines3's ``SAC.learn()`` on the same env and sizes (``train_freq=1``,
  ``gradient_steps=1``, ``learning_starts`` past), with torch on the same number of threads.

Prints a table and writes ``benchmarks/results/throughput.json``. Targets (issue 10): loop
efficiency >= 90% and end-to-end SAC >= 3x SB3's ``learn()``. Measure on an otherwise idle
machine.
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

RESULTS = Path(__file__).resolve().parent / "results"
H = 50


def _ours(algo: str, interactions: int) -> dict[str, float]:
    import gymnasium as gym
    import jax
    import jax.numpy as jnp

    import lili  # noqa: F401
    from lili.agents import make_agent
    from lili.config import AgentConfig
    from lili.train import Stream, train

    agent = make_agent(algo, gym.make("lili/PointMass-v0"), AgentConfig(), seed=0)
    stream = Stream.for_agent(agent, agent.env)
    train(agent, stream, agent.config.warmup_interactions + 3)  # warm-up and compilation
    spent = [0.0]
    block = agent.train_block

    def timed(buffer, key):
        t = time.perf_counter()
        out = block(buffer, key)  # returns floats: the block has finished
        spent[0] += time.perf_counter() - t
        return out

    agent.train_block = timed
    t0 = time.perf_counter()
    train(agent, stream, interactions)
    wall = time.perf_counter() - t0
    # The block alone, repeated on the same buffer.
    core, buf = agent.core, stream.buffer
    count = jnp.int32(buf.count)
    state, key = agent.state, jax.random.PRNGKey(1)
    best = float("inf")
    for r in range(5):
        t = time.perf_counter()
        state, m = core.jit_block(state, buf.arrays, count, jax.random.fold_in(key, r))
        jax.block_until_ready(m)
        best = min(best, time.perf_counter() - t)
    steps = interactions * H
    return {"steps_per_s": steps / wall, "wall_s": wall, "block_s": spent[0],
            "ms_per_update_in_loop": 1e3 * spent[0] / (interactions * core.n_updates),
            "ms_per_update_alone": 1e3 * best / core.n_updates,
            "loop_efficiency": spent[0] / wall}


def _sb3(interactions: int, threads: int) -> dict[str, float]:
    import gymnasium as gym
    import torch
    from stable_baselines3 import SAC

    import lili  # noqa: F401

    torch.set_num_threads(threads)
    env = gym.make("lili/PointMass-v0")
    model = SAC("MlpPolicy", env, batch_size=256, learning_starts=20 * H, train_freq=1,
                gradient_steps=1, policy_kwargs={"net_arch": [256, 256]}, seed=0, verbose=0)
    model.learn(total_timesteps=23 * H)  # past learning_starts, as our warm-up
    t0 = time.perf_counter()
    model.learn(total_timesteps=interactions * H, reset_num_timesteps=False)
    wall = time.perf_counter() - t0
    return {"steps_per_s": interactions * H / wall, "wall_s": wall}


def worker(threads: int, interactions: int) -> dict:
    out = {"threads": threads}
    for algo in ("sac", "lili"):
        out[algo] = _ours(algo, interactions)
    try:
        out["sb3"] = _sb3(interactions, threads)
    except ImportError as e:
        out["sb3"] = {"error": f"not installed ({e}); pip install -e '.[bench]'"}
    return out


def _env(threads: int) -> dict[str, str]:
    """The worker's environment: one XLA thread, or XLA's default (a thread pool over every
    core, which is 2 on the machines this was measured on)."""
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    if threads == 1:
        env["XLA_FLAGS"] = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
    env["OMP_NUM_THREADS"] = str(threads)
    return env


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interactions", type=int, default=60, help="timed interactions per agent")
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2],
                   help="1 = one XLA thread; more = XLA's default thread pool (all cores)")
    p.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.interactions < 1 or any(t < 1 for t in args.threads):
        p.error("--interactions and --threads must be integers >= 1")
    if args.worker:
        print(json.dumps(worker(args.worker, args.interactions)))
        return
    rows = []
    for threads in args.threads:
        res = subprocess.run([sys.executable, __file__, "--worker", str(threads),
                              "--interactions", str(args.interactions)],
                             capture_output=True, text=True, env=_env(threads))
        if res.returncode != 0:
            sys.exit(f"the worker with {threads} thread(s) failed:\n{res.stderr[-3000:]}")
        rows.append(json.loads(res.stdout.strip().splitlines()[-1]))
    lines = ["| XLA threads | agent | env steps/s (end to end) | ms / update in the loop | "
             "ms / update, block alone | loop efficiency | x SB3 learn() |",
             "|---:|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        sb3 = r["sb3"].get("steps_per_s")
        for algo in ("sac", "lili"):
            o = r[algo]
            ratio = f"{o['steps_per_s'] / sb3:.2f}x" if sb3 else "—"
            lines.append(f"| {r['threads']} | {algo.upper()} | {o['steps_per_s']:.0f} | "
                         f"{o['ms_per_update_in_loop']:.2f} | {o['ms_per_update_alone']:.2f} | "
                         f"{o['loop_efficiency']:.1%} | {ratio} |")
        lines.append(f"| {r['threads']} | SB3 SAC learn() | "
                     f"{sb3:.0f} | — | — | — | 1.00x |" if sb3 else
                     f"| {r['threads']} | SB3 SAC | {r['sb3']['error']} | | | | |")
    table = "\n".join(lines)
    print(table)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "throughput.json").write_text(json.dumps(
        {"interactions": args.interactions, "machine": platform.processor() or platform.machine(),
         "cpus": os.cpu_count(), "rows": rows, "table": table}, indent=1))


if __name__ == "__main__":
    main()
