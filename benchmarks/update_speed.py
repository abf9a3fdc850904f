"""Update cost: this library's agents against Stable-Baselines3's SAC, side by side in one run.

    pip install -e '.[bench]'          # stable-baselines3 + torch (optional)
    python benchmarks/update_speed.py [--updates 500] [--repeats 5] [--algos sac lili ...]

Both sides do full SAC updates (twin critic, actor, temperature, target update) with the same
sizes: batch 256, 2x256 networks, on Point Mass transitions. SB3 is timed through
``model.train(gradient_steps=N)``; ours through the fused block (``agent.train_block``, one
``lax.scan`` of N updates with sampling inside). Every agent's update is timed too (Oracle,
LILI, LILI (no influence), LILAC, SLAC at its default sizes) and shown as a multiple of SAC's.
The ratio uses the best of ``--repeats`` timings of each, measured alternately in this process.
Prints a table and writes ``benchmarks/results/update_speed.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import gymnasium as gym
import jax
import numpy as np

import lili.envs  # noqa: F401
from lili.agents import make_agent
from lili.config import AgentConfig
from lili.train import Stream, train

RESULTS = Path(__file__).resolve().parent / "results"
AGENTS = ("sac", "oracle", "lili", "lili-no-influence", "lilac", "slac")


def ours(algo: str, n_updates: int):
    """A function that runs one block of ``n_updates`` updates of ``algo``."""
    env = gym.make("lili/PointMass-v0")
    cfg = AgentConfig(warmup_interactions=40, updates_per_step=n_updates / 50)
    agent = make_agent(algo, env, cfg, seed=0)
    stream = Stream.for_agent(agent, agent.env)
    train(agent, stream, 40)  # fills the buffer, fits the normaliser and compiles the block
    keys = iter(jax.random.split(jax.random.PRNGKey(1), 10_000))

    def run():
        agent.train_block(stream.buffer, next(keys))  # returns floats: the block is done

    run()
    return run


def sb3(n_updates: int):
    """The same for Stable-Baselines3's SAC, or None when it is not installed."""
    try:
        import torch
        from stable_baselines3 import SAC as SB3SAC
    except ImportError:
        return None
    env = gym.make("lili/PointMass-v0")
    model = SB3SAC("MlpPolicy", env, batch_size=256, learning_starts=2000, buffer_size=100_000,
                   policy_kwargs={"net_arch": [256, 256]}, seed=0, device="cpu", verbose=0)
    model.learn(total_timesteps=2000)  # fills the replay buffer (no updates before 2000 steps)

    def run():
        model.train(gradient_steps=n_updates, batch_size=256)

    run()
    return run, torch.__version__, torch.get_num_threads()


def best_ms(fn, n_updates: int, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1000 * min(times) / n_updates


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--updates", type=int, default=500)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--algos", nargs="+", default=list(AGENTS), choices=AGENTS)
    args = p.parse_args()
    n = args.updates
    runners = {algo: ours(algo, n) for algo in args.algos}
    sb = sb3(n)
    if sb is not None:
        runners["sb3-sac"] = sb[0]
    ms = {k: [] for k in runners}
    for _ in range(args.repeats):  # interleaved so that machine noise hits every row alike
        for k, fn in runners.items():
            ms[k].append(best_ms(fn, n, 1))
    best = {k: min(v) for k, v in ms.items()}
    rows = [(k, best[k]) for k in runners]
    print(f"{'agent':<20}{'ms / update':>12}{'x SAC':>8}{'vs SB3 SAC':>12}")
    for k, v in rows:
        ratio = f"{best['sb3-sac'] / v:.2f}x" if "sb3-sac" in best else "n/a"
        vs_sac = f"{v / best['sac']:.2f}" if "sac" in best else "n/a"
        print(f"{k:<20}{v:>12.2f}{vs_sac:>8}{ratio:>12}")
    if sb is None:
        print("(stable-baselines3 not installed: pip install -e '.[bench]' for the comparison)")
    out = {"ms_per_update": best, "all_ms": ms, "updates_per_timing": n,
           "batch": 256, "hidden": [256, 256], "jax": jax.__version__,
           "torch": sb[1] if sb else None, "torch_threads": sb[2] if sb else None,
           "machine": platform.machine(), "cpus": __import__("os").cpu_count()}
    if "sb3-sac" in best and "sac" in best:
        out["speedup_sac_vs_sb3"] = best["sb3-sac"] / best["sac"]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "update_speed.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
