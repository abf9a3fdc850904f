"""Env steps per second: K Gymnasium envs stepped in Python against the JAX-native env
(``lili.envs.jax``), one jitted program that vmaps K runs, each interaction one ``lax.scan``.

    python benchmarks/jax_envs.py [--ks 1 8 64 512] [--env point-mass] [--steps 20000]
                                  [--repeats 3] [--name jax_envs]

Random actions, on whatever JAX's default device is (the committed numbers: the CPU). The K
runs are the Point Mass family of the paper's tables side by side (run k has the partner
``FAMILY[k % 11]``: the default one, the noisy ones sigma = 0.2 ... 1.0 and the history ones
N = 3 ... 11), in both paths; the other envs take their defaults. The Gymnasium path is
``gym.make`` (as training makes its env), ``reset`` / ``step`` of each of the K envs in turn,
at least ``--steps`` steps in all; the JAX path is :func:`lili.envs.jax.rollout_many` over
at least ten times as many, timed after its compile (the compile is reported apart). The best
of ``--repeats`` timings counts, because the machine is shared. Prints a table and writes
``benchmarks/results/<name>.json``.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time
from typing import Any

import gymnasium as gym
import jax
import numpy as np
from _results import check_result_name, write_result

from lili.envs import resolve_env_id
from lili.envs.jax import UniformPolicy, make, rollout_many, stack
from lili.experiments.presets import HISTORY, NOISE

FAMILY: list[dict[str, Any]] = ([{}] + [{"step_noise": s} for s in NOISE[1:]]
                                + [{"history": n} for n in HISTORY[1:]])


def env_kwargs(env_id: str, k: int) -> dict[str, Any]:
    """The kwargs of run ``k``: the Point Mass family, or the defaults of another env."""
    return FAMILY[k % len(FAMILY)] if env_id == "lili/PointMass-v0" else {}


def gymnasium_steps_per_s(env_id: str, k_runs: int, min_steps: int) -> float:
    """Steps per second of ``k_runs`` Gymnasium envs stepped one after another in Python."""
    envs = [gym.make(env_id, **env_kwargs(env_id, k)) for k in range(k_runs)]
    horizon = envs[0].unwrapped.horizon
    n_interactions = math.ceil(min_steps / (k_runs * horizon))
    rng = np.random.default_rng(0)
    shape = (k_runs, *envs[0].action_space.shape)
    for k, env in enumerate(envs):
        env.reset(seed=k)
    t0 = time.perf_counter()
    steps = 0
    for i in range(n_interactions):
        if i:
            for env in envs:
                env.reset()
        for _ in range(horizon):
            actions = rng.uniform(-1.0, 1.0, shape).astype(np.float32)
            for env, action in zip(envs, actions, strict=True):
                env.step(action)
            steps += k_runs
    return steps / (time.perf_counter() - t0)


def jax_steps_per_s(env_id: str, k_runs: int, min_steps: int,
                    repeats: int) -> tuple[float, float]:
    """(steps per second, compile seconds) of :func:`rollout_many` over ``k_runs`` runs."""
    pairs = [make(env_id, **env_kwargs(env_id, k)) for k in range(k_runs)]
    env, params = pairs[0][0], stack([p for _, p in pairs])
    horizon = int(params.horizon[0])
    n_interactions = math.ceil(min_steps / (k_runs * horizon))
    policy = UniformPolicy(env.action_shape)

    def run(seed: int) -> None:
        keys = jax.random.split(jax.random.PRNGKey(seed), k_runs)
        jax.block_until_ready(rollout_many(env, policy, keys, params, horizon, n_interactions))

    t0 = time.perf_counter()
    run(0)
    compile_s = time.perf_counter() - t0
    best = math.inf
    for seed in range(1, repeats + 1):
        t0 = time.perf_counter()
        run(seed)
        best = min(best, time.perf_counter() - t0)
    return k_runs * horizon * n_interactions / best, compile_s


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ks", type=int, nargs="+", default=[1, 8, 64, 512])
    p.add_argument("--env", default="point-mass")
    p.add_argument("--steps", type=int, default=20_000,
                   help="at least this many Gymnasium steps per K (JAX: ten times as many)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--name", default="jax_envs")
    args = p.parse_args()
    check_result_name(p, args.name)
    if any(k < 1 for k in args.ks) or args.steps < 1 or args.repeats < 1:
        p.error(f"--ks {args.ks}, --steps {args.steps}, --repeats {args.repeats}: "
                "allowed: integers >= 1")
    env_id = resolve_env_id(args.env)
    rows = []
    for k in args.ks:
        gym_rate = max(gymnasium_steps_per_s(env_id, k, args.steps) for _ in range(args.repeats))
        jax_rate, compile_s = jax_steps_per_s(env_id, k, 10 * args.steps, args.repeats)
        rows.append({"k": k, "gymnasium_steps_per_s": gym_rate, "jax_steps_per_s": jax_rate,
                     "jax_compile_s": compile_s, "speedup": jax_rate / gym_rate})
        print(f"K={k}: Gymnasium {gym_rate:,.0f} steps/s, JAX {jax_rate:,.0f} steps/s "
              f"(compile {compile_s:.1f} s)", flush=True)
    device = jax.devices()[0]
    lines = [f"{env_id}, random actions, {device.platform} ({device.device_kind}), "
             f"best of {args.repeats}",
             "",
             "| K runs | Gymnasium steps/s | JAX steps/s | JAX / Gymnasium | JAX compile |",
             "|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['k']} | {r['gymnasium_steps_per_s']:,.0f} | {r['jax_steps_per_s']:,.0f} "
              f"| {r['speedup']:,.0f}x | {r['jax_compile_s']:.1f} s |" for r in rows]
    write_result(args.name, "\n".join(lines), env=env_id, rows=rows, steps=args.steps,
                 repeats=args.repeats, device=f"{device.platform} ({device.device_kind})",
                 machine=platform.platform(), cpus=os.cpu_count(), jax=jax.__version__,
                 load_average=os.getloadavg())


if __name__ == "__main__":
    main()
