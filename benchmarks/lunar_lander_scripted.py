"""Scripted landers on Lunar Lander: how each reading of the reward ranks them.

    python benchmarks/lunar_lander_scripted.py [--interactions 50] [--seeds 0 1]

Plays four scripted policies (:func:`lili.envs.lunar_lander.pad_controller` to this
interaction's pad, to the centre of the ground, to the other pad, and a drop with the engines
off) under both readings of the appendix's reward (``reward="potential"``, the literal one, and
``reward="difference"``, the potential's change from step to step as Gymnasium pays its
shaping) and both endings (``end_on_contact``), prints mean return and success per policy, and
writes ``benchmarks/results/lunar_lander_scripted.{json,md}``. About 40 s on one core.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from lili.envs.influence.scripted import play
from lili.envs.lunar_lander import REWARDS, LunarLanderEnv, pad_controller

RESULTS = Path(__file__).resolve().parent / "results"

POLICIES = {
    "pad": lambda obs, info: pad_controller(obs, info["strategy"]),
    "centre": lambda obs, info: pad_controller(obs, np.array([0.0, 0.0])),
    "wrong pad": lambda obs, info: pad_controller(
        obs, np.array([-info["strategy"][0], info["strategy"][1]])),
    "drop (engines off)": lambda obs, info: np.array([-1.0, 0.0], np.float32),
}


def ranking_table(interactions: int = 50, seeds: tuple[int, ...] = (0, 1)) -> dict:
    """Mean return and success of every scripted policy under the four reward/ending pairs."""
    rows = {}
    for reward in REWARDS:
        for end_on_contact in (True, False):
            key = f"reward={reward}, end_on_contact={end_on_contact}"
            rows[key] = {}
            for name, policy in POLICIES.items():
                runs = [play(LunarLanderEnv(reward=reward, end_on_contact=end_on_contact),
                             policy, interactions, seed) for seed in seeds]
                rows[key][name] = {"return": float(np.mean([r.mean_return() for r in runs])),
                                   "success": float(np.mean([r.success_rate() for r in runs]))}
            order = sorted(rows[key], key=lambda n: -rows[key][n]["return"])
            rows[key]["ranking"] = order
    names = list(POLICIES)
    lines = [f"Lunar Lander, scripted policies ({interactions} interactions x seeds "
             f"{', '.join(map(str, seeds))}): mean return per interaction (success)", "",
             "| reading | " + " | ".join(names) + " | pad first, drop last |",
             "|---|" + "---:|" * len(names) + "---|"]
    for key, row in rows.items():
        ok = row["ranking"][0] == "pad" and row["ranking"][-1] == names[-1]
        cells = [f"{row[n]['return']:+.2f} ({100 * row[n]['success']:.0f}%)" for n in names]
        lines.append(f"| {key} | " + " | ".join(cells) + f" | {'yes' if ok else 'no'} |")
    table = "\n".join(lines)
    print(table, flush=True)
    RESULTS.mkdir(exist_ok=True)
    out = {"interactions": interactions, "seeds": list(seeds), "readings": rows}
    (RESULTS / "lunar_lander_scripted.json").write_text(json.dumps(out, indent=1))
    (RESULTS / "lunar_lander_scripted.md").write_text(table + "\n")
    return out


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interactions", type=int, default=50)
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    args = p.parse_args()
    if args.interactions < 1:
        p.error(f"--interactions {args.interactions} is invalid; allowed: an integer >= 1")
    ranking_table(args.interactions, tuple(args.seeds))
