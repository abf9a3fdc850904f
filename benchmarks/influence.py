"""The influence suite: scripted no-information, greedy and influencing policies per env, and
(with ``--algos``) learned agents beside them with the gap each closes from SAC to the
influencer.

    python benchmarks/influence.py                          # scripted policies only (~30 s)
    python benchmarks/influence.py --algos sac lili-no-influence lili oracle \\
        --interactions 600 --seeds 3                        # + learned agents (lili train)

Scripted rows: the mean return per interaction over the last ``--last`` of ``--scripted``
interactions (Point Mass: 3000 and 2000, because its greedy target random-walks slowly),
seeds 0-1, beside the value derived in each env's docstring. Learned rows: ``lili train``
runs (one per algo and seed, one at a time, skipped when finished, resumed when
interrupted) under ``runs/bench_influence/``, scored as the mean return over the last 10% of
interactions of each seed, mean +- s.e. over seeds. Gap closed = (R - R_SAC) / (R_influencer -
R_SAC). Writes ``benchmarks/results/influence.{json,md}``.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

from lili.envs.influence import POLICIES, SUITE, make_scripted, play

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
# Point Mass's greedy target takes a slow random walk round the circle: average it out.
SCRIPTED_BUDGET = {"lili/PointMass-v0": (3000, 2000)}
LABELS = {"no-information": "scripted: no information", "greedy": "scripted: greedy",
          "influencer": "scripted: influencer", "sac": "SAC", "oracle": "Oracle",
          "lili": "LILI", "lili-no-influence": "LILI (no influence)"}


def scripted_returns(env_id: str, interactions: int, last: int, seeds=(0, 1)) -> dict:
    """Mean return over the last ``last`` interactions, per scripted policy (mean over seeds)."""
    interactions, last = SCRIPTED_BUDGET.get(env_id, (interactions, last))
    out = {}
    for name in POLICIES:
        per_seed = [play(gym.make(env_id), make_scripted(env_id, name, s), interactions, s)
                    .last(last).mean_return() for s in seeds]
        out[name] = {"mean": float(np.mean(per_seed)), "per_seed": per_seed,
                     "known": SUITE[env_id][1][name], "interactions": interactions,
                     "last": last}
    return out


def train_run(env_id: str, algo: str, seed: int, interactions: int, out: Path) -> Path:
    """The one adapter to the agents: a ``lili train`` run (skipped if done, else resumed)."""
    run = out / env_id.split("/")[-1] / algo / f"seed_{seed}"
    summary = run / "summary.json"
    if summary.exists() and json.loads(summary.read_text())["interactions"] >= interactions:
        return run
    cmd = [str(Path(sys.executable).parent / "lili"), "train", env_id, "--algo", algo,
           "--seed", str(seed), "--interactions", str(interactions), "--out", str(out),
           "--no-progress"] + (["--resume"] if (run / "metrics.csv").exists() else [])
    print(f"train {algo} seed {seed} on {env_id}", flush=True)
    subprocess.run(cmd, check=True)
    return run


def learned_returns(env_id: str, algos: list[str], seeds: int, interactions: int,
                    out: Path) -> dict:
    """Train every (algo, seed) and score the runs' ``metrics.csv``."""
    results = {}
    for algo in algos:
        finals = []
        for seed in range(seeds):
            path = train_run(env_id, algo, seed, interactions, out) / "metrics.csv"
            with path.open() as f:
                returns = [float(row["return"]) for row in csv.DictReader(f)]
            tail = max(1, len(returns) // 10)
            finals.append(float(np.mean(returns[-tail:])))
        se = float(np.std(finals, ddof=1) / np.sqrt(len(finals))) if len(finals) > 1 else 0.0
        results[algo] = {"mean": float(np.mean(finals)), "se": se, "per_seed": finals,
                         "interactions": interactions}
    return results


def table(env_id: str, scripted: dict, learned: dict) -> list[str]:
    lines = [f"### {env_id}", "", "| policy | return / interaction | derived | gap closed |",
             "|---|---:|---:|---:|"]
    sac = learned.get("sac", {}).get("mean")
    top = scripted["influencer"]["mean"]
    for name, row in scripted.items():
        lines.append(f"| {LABELS[name]} | {row['mean']:.3f} | {row['known']:.3f} | |")
    for algo, row in learned.items():
        gap = "" if sac is None or top == sac else f"{(row['mean'] - sac) / (top - sac):.2f}"
        lines.append(f"| {LABELS.get(algo, algo)} ({len(row['per_seed'])} seeds, "
                     f"{row['interactions']} int.) | {row['mean']:.3f} ± {row['se']:.3f} | "
                     f"| {gap} |")
    return lines + [""]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--envs", nargs="+", default=list(SUITE), choices=list(SUITE))
    p.add_argument("--scripted", type=int, default=300, help="interactions per scripted run")
    p.add_argument("--last", type=int, default=200, help="scripted interactions counted")
    p.add_argument("--algos", nargs="*", default=[], help="learned agents (lili train)")
    p.add_argument("--interactions", type=int, default=600, help="per learned run")
    p.add_argument("--seeds", type=int, default=3, help="seeds per learned agent")
    p.add_argument("--out", default=str(ROOT / "runs" / "bench_influence"))
    p.add_argument("--name", default="influence", help="results file stem")
    args = p.parse_args()
    if not 1 <= args.last <= args.scripted:
        p.error(f"--last {args.last} is invalid; allowed: 1 to --scripted ({args.scripted})")
    for flag in ("interactions", "seeds"):
        if getattr(args, flag) < 1:
            p.error(f"--{flag} {getattr(args, flag)} is invalid; allowed: an integer >= 1")
    from lili.agents import ALGOS

    bad = [a for a in args.algos if a not in ALGOS]
    if bad:
        p.error(f"--algos {' '.join(bad)} is invalid; allowed: {', '.join(ALGOS)}")
    report, lines = {}, []
    for env_id in args.envs:
        scripted = scripted_returns(env_id, args.scripted, args.last)
        learned = (learned_returns(env_id, args.algos, args.seeds, args.interactions,
                                   Path(args.out)) if args.algos else {})
        report[env_id] = {"scripted": scripted, "learned": learned}
        lines += table(env_id, scripted, learned)
        print("\n".join(table(env_id, scripted, learned)), flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.name}.json").write_text(json.dumps(report, indent=1))
    (RESULTS / f"{args.name}.md").write_text("\n".join(lines))


if __name__ == "__main__":
    main()
