"""Scripted blockers on air hockey: what blocking and influencing are worth, with no learning.

    python benchmarks/air_hockey_scripted.py [--interactions 600] [--seeds 0 1] [--last 400]
        [--env-kwarg aim_noise=0.02 ...]

Plays the blockers of ``lili.envs.air_hockey.scripted`` (random, middle, crossing, greedy and
influencer; the last three are told the striker's mode; and the predictor, told only the last
shot's mode and side) on ``lili/AirHockey-v0``, prints block
rate, reward per interaction and the striker's modes over the last ``--last`` interactions of
each seed (mean over seeds) and the value of influence (influencer minus greedy), and writes
``benchmarks/results/air_hockey_scripted{_<kwargs>}.{json,md}``. About 10 s per blocker and
seed on one core.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import yaml

from lili.envs.air_hockey import AirHockeyEnv
from lili.envs.air_hockey.scripted import BLOCKERS, blocker_env, make_blocker
from lili.envs.influence.scripted import play

RESULTS = Path(__file__).resolve().parent / "results"


def _row(runs: list, seconds: float) -> dict:
    """One blocker's numbers over its seeds' rollouts."""
    return {
        "block_rate": float(np.mean([r.success_rate() for r in runs])),
        "reward": float(np.mean([r.mean_return() for r in runs])),
        "reward_per_seed": [r.mean_return() for r in runs],
        "modes": np.mean([r.strategy_frequencies(3) for r in runs], 0).tolist(),
        "seconds": seconds,
    }


def scripted_table(interactions: int = 600, seeds: tuple[int, ...] = (0, 1), last: int = 400,
                   env_kwargs: dict | None = None, write: bool = True) -> dict:
    """Measure every scripted blocker; print the table; return (and write) the numbers."""
    env_kwargs = dict(env_kwargs or {})
    rows = {}
    for name in BLOCKERS:
        t0 = time.time()
        # The predictor is told only the last shot's mode and side (on a wrapped env): the
        # ceiling of a blocker reading the past.
        runs = [play(blocker_env(name, AirHockeyEnv(**env_kwargs)),
                     make_blocker(name, seed, env_kwargs.get("bank_shots", True)),
                     interactions, seed).last(last) for seed in seeds]
        rows[name] = _row(runs, time.time() - t0)
    value = rows["influencer"]["reward"] - rows["greedy"]["reward"]
    lines = [f"Air hockey, scripted blockers ({interactions} interactions, seeds "
             f"{', '.join(map(str, seeds))}, last {last} counted; "
             f"env kwargs {env_kwargs or 'default'})",
             "", "| blocker | told the mode | block rate | reward / interaction | "
             "striker left / middle / right |", "|---|---|---:|---:|---|"]
    for name, row in rows.items():
        modes = " / ".join(f"{100 * f:.0f}" for f in row["modes"])
        told = ("yes" if name in ("crossing", "greedy", "influencer")
                else "the last one and its side" if name == "predictor" else "no")
        lines.append(f"| {name} | {told} | {100 * row['block_rate']:.1f}% | "
                     f"{row['reward']:.3f} | {modes}% |")
    lines += ["", f"Value of influence (influencer - greedy): {value:+.3f} per interaction "
              f"({100 * value / rows['greedy']['reward']:+.1f}%)"]
    table = "\n".join(lines)
    print(table, flush=True)
    out = {"interactions": interactions, "seeds": list(seeds), "last": last,
           "env_kwargs": env_kwargs, "blockers": rows, "value_of_influence": value}
    if write:
        suffix = "".join(f"_{k}={v}" for k, v in sorted(env_kwargs.items()))
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / f"air_hockey_scripted{suffix}.json").write_text(json.dumps(out, indent=1))
        (RESULTS / f"air_hockey_scripted{suffix}.md").write_text(table + "\n")
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interactions", type=int, default=600)
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    p.add_argument("--last", type=int, default=400)
    p.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE")
    args = p.parse_args()
    if not 1 <= args.last <= args.interactions:
        p.error(f"--last {args.last} is invalid; allowed: 1 to --interactions "
                f"({args.interactions})")
    kwargs = {}
    for item in args.env_kwarg:
        if "=" not in item:
            p.error(f"--env-kwarg {item!r} is invalid; allowed: KEY=VALUE")
        key, value = item.split("=", 1)
        kwargs[key] = yaml.safe_load(value)
    scripted_table(args.interactions, tuple(args.seeds), args.last, kwargs)


if __name__ == "__main__":
    main()
