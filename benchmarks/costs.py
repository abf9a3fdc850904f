"""CPU cost of one run of every (env, algo) the paper's presets train: the figures behind
``lili reproduce --dry-run`` and its ETA (:mod:`lili.experiments.costs`).

    python benchmarks/costs.py [--preset paper] [--timed 30] [--jobs 2]

For every distinct cost key of the preset's runs (env, algo, and the encoder's history, the one
config field that changes the work per interaction; noise levels do not), one child process with
one XLA thread, as ``lili reproduce`` starts runs, builds the first planned run of that key (its
own env kwargs and agent config, so the benchmark cannot drift from the presets) the way
``lili train`` does, plays the warm-up and 10 learning interactions (imports, env, JAX compiles,
SLAC's pretraining: the fixed part), then ``--timed`` more. It reports the CPU-seconds of the
whole process (``time.process_time``, every thread), so the figures do not depend on what else
runs on the machine; a run of ``n`` interactions is estimated to cost
``fixed + per_interaction * (n - 30)`` CPU-seconds. ``--jobs 2`` (the default) measures two
keys side by side, as ``lili reproduce --jobs 2`` runs them: on this 2-core machine a process
costs about 1.5x the CPU-seconds when another one runs beside it (Point Mass LILI: 0.45 s per
interaction alone, 0.69 beside another run), so measure under the load you will run at.
Prints a table, writes ``benchmarks/results/costs.{json,md}`` and the lines of
:data:`lili.experiments.costs.COSTS`.
About 25 CPU-minutes for ``paper`` (34 keys).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
WARM = 30  # interactions before the timed part: the default warm-up (20) and 10 learning ones


def measure_one(run: dict, timed: int) -> dict[str, float]:
    """In this process: CPU-seconds of the fixed part and per learning interaction of ``run``
    (a planned run's ``env``, ``algo``, ``env_kwargs`` and ``config``)."""
    from lili.agents import make_agent
    from lili.config import AgentConfig
    from lili.envs.spec import load_env_class
    from lili.train import Stream, train

    env = load_env_class(run["env"])(**run["env_kwargs"])
    agent = make_agent(run["algo"], env, AgentConfig.from_dict(run["config"]), 0)
    stream = Stream.for_agent(agent, agent.env)
    train(agent, stream, WARM)
    fixed = time.process_time()
    train(agent, stream, timed)
    per = (time.process_time() - fixed) / timed
    return {"fixed_s": round(fixed, 2), "per_interaction_s": round(per, 4)}


def cost_keys(preset: str) -> dict[tuple[str, str, int], dict]:
    """The distinct (env, algo, history) of the preset's runs, in plan order, each with the
    first planned run that has it (as :func:`measure_one` takes it)."""
    from lili.experiments.costs import cost_key
    from lili.experiments.plan import plan
    from lili.experiments.presets import get_preset

    keys: dict[tuple[str, str, int], dict] = {}
    for spec in plan(get_preset(preset), "/nonexistent-costs-plan"):
        keys.setdefault(cost_key(spec), {"env": spec.env, "algo": spec.algo,
                                         "env_kwargs": spec.env_kwargs, "config": spec.config})
    return keys


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--timed", type=int, default=30, help="timed interactions per key")
    ap.add_argument("--jobs", type=int, default=2, help="keys measured side by side")
    ap.add_argument("--only", metavar="RUN_JSON",
                    help="measure one planned run in this process and print its JSON (internal)")
    args = ap.parse_args()
    if args.timed < 1:
        ap.error(f"--timed {args.timed} is invalid; allowed: an integer >= 1")
    if args.jobs < 1:
        ap.error(f"--jobs {args.jobs} is invalid; allowed: an integer >= 1")
    if args.only:
        print(json.dumps(measure_one(json.loads(args.only), args.timed)))
        return

    from lili.experiments.runner import child_env

    keys = cost_keys(args.preset)

    def run(key: tuple[str, str, int]) -> dict:
        env_id, algo, history = key
        out = subprocess.run([sys.executable, __file__, "--only", json.dumps(keys[key]),
                              "--timed", str(args.timed)], env=child_env(), text=True,
                             capture_output=True, cwd=os.getcwd())
        if out.returncode != 0:
            raise RuntimeError(f"{env_id} {algo} history {history} failed:\n"
                               f"{out.stderr[-2000:]}")
        return {"env": env_id, "algo": algo, "history": history,
                **json.loads(out.stdout.strip().splitlines()[-1])}

    rows = []
    with ThreadPoolExecutor(args.jobs) as pool:
        for n, row in enumerate(pool.map(run, keys), 1):
            rows.append(row)
            print(f"[{n}/{len(keys)}] {row['env']} {row['algo']} h={row['history']}: fixed "
                  f"{row['fixed_s']:.1f} s, {row['per_interaction_s']:.3f} s/interaction",
                  flush=True)

    lines = [f"CPU cost per run, one XLA thread (`python benchmarks/costs.py --preset "
             f"{args.preset} --timed {args.timed} --jobs {args.jobs}`); a run of n "
             f"interactions costs about fixed + per interaction x (n - {WARM}) CPU-seconds", "",
             "| env | algo | history | fixed (s) | per interaction (s) | 1000 int. (min) "
             "| 2000 int. (min) |", "|---|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        k1, k2 = (r["fixed_s"] + r["per_interaction_s"] * (n - WARM) for n in (1000, 2000))
        lines.append(f"| {r['env']} | {r['algo']} | {r['history']} | {r['fixed_s']:.1f} | "
                     f"{r['per_interaction_s']:.3f} | {k1 / 60:.1f} | {k2 / 60:.1f} |")
    table = "\n".join(lines)
    print(table)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "costs.json").write_text(json.dumps(
        {"preset": args.preset, "timed": args.timed, "jobs": args.jobs, "warm": WARM,
         "rows": rows}, indent=2))
    (RESULTS / "costs.md").write_text(table + "\n")
    print("\nlili.experiments.costs.COSTS entries:")
    for r in rows:
        print(f'    ("{r["env"]}", "{r["algo"]}", {r["history"]}): '
              f'({r["fixed_s"]:.1f}, {r["per_interaction_s"]:.4f}),')


if __name__ == "__main__":
    main()
