"""What the noisy and the history-dependent partners leave to reach: scripted Point Mass bounds.

    python benchmarks/partner_scripted.py --table noise|history [--interactions 1000]
        [--last 800] [--seeds 0 1]

For each row of the paper's Table 2 (``noise``: the partner's 0.2 rad step gets Gaussian noise
of sigma x 0.2 rad) or Table 3 (``history``: the partner turns by the majority of the ego's
last N ends) plays, on ``PointMassEnv(step_noise=sigma)`` or ``PointMassEnv(history=N)``:

- the influencer *told* the target (``lili.envs.influence.point_mass.influencer``): what the
  partner costs an agent that sees the strategy (the Oracle's bound);
- the influencer told only what the last interaction predicts
  (:class:`~lili.envs.influence.point_mass.LastInteractionInfluencer`): the bound of an agent
  whose latent reads the last interaction, as LILI's does; in the history table also the one
  that reads the last N interactions, as LILI's encoder there does;
- the no-information policy (SAC's level); in the history table also the greedy policy, which
  ends on a random side.

Prints the mean return per interaction over the last ``--last`` interactions (mean over seeds)
beside LILI's committed runs (``results/runs/s9/<table>``, final 10%, mean +- s.e.) and the
paper's, and writes ``benchmarks/results/partner_scripted_<table>.{json,md}``. For the history
table it also reads from LILI's records how it holds the target: how often, per 100 of its
last 200 interactions, the target turned back (the told influencer, holding it at the top,
turns it back every interaction). About 20 s per row.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
from _results import RESULTS

from lili.envs.influence.point_mass import (
    GreedyCoin,
    LastInteractionInfluencer,
    influencer,
    no_information,
)
from lili.envs.influence.scripted import play
from lili.envs.point_mass import CENTER, PointMassEnv
from lili.report.files import load_run
from lili.report.paper import PAPER_TABLES
from lili.report.stats import mean_se
from lili.report.tables import fmt_mean_se

RUNS = RESULTS / "runs" / "s9"
TURN_WINDOW = 200

# table -> policy name -> factory(row value, seed) -> policy
POLICIES: dict[str, dict[str, Callable]] = {
    "noise": {
        "influencer (told the target)": lambda v, seed: influencer,
        "influencer (last interaction)": lambda v, seed: LastInteractionInfluencer(),
        "no information": lambda v, seed: no_information,
    },
    "history": {
        "influencer (told the target)": lambda v, seed: influencer,
        "influencer (last N interactions)": lambda v, seed: LastInteractionInfluencer(history=v),
        "influencer (last interaction)": lambda v, seed: LastInteractionInfluencer(),
        "greedy (random side)": lambda v, seed: GreedyCoin(seed),
        "no information": lambda v, seed: no_information,
    },
}


def lili_folders(table: str, value: float) -> list[Path]:
    """The committed LILI runs of a row, seeds 0-2 as the preset plans them (the first row,
    sigma 0 or N = 1, is the Point Mass preset's runs, which both tables reuse)."""
    first = value == 0 if table == "noise" else value == 1
    name = f"sigma_{value:g}" if table == "noise" else f"n_{value:g}"
    folder = RUNS / "point-mass" if first else RUNS / table / name
    return sorted(p.parent for p in folder.glob("PointMass-v0/lili/seed_[012]/summary.json"))


def turns_back(x: np.ndarray, y: np.ndarray) -> float:
    """Per 100 interactions, how often a target at angles ``arctan2(y, x)`` (one per
    interaction, round the circle's centre) reversed its direction."""
    step = np.angle(np.exp(1j * np.diff(np.arctan2(y, x))))
    return float(100 * np.mean(np.sign(step[1:]) != np.sign(step[:-1])))


def run_turns_back(folder: Path, last: int = TURN_WINDOW) -> float:
    """:func:`turns_back` over the run's last ``last`` interactions, from its records (the
    target relative to the circle's centre, which ``strategy_0/1`` hold)."""
    metrics = load_run(folder).metrics
    target = np.stack([metrics["strategy_0"], metrics["strategy_1"]], -1)[-(last + 2):]
    rel = target - CENTER
    return turns_back(rel[:, 0], rel[:, 1])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--table", choices=sorted(POLICIES), required=True)
    p.add_argument("--interactions", type=int, default=1000)
    p.add_argument("--last", type=int, default=800)
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    args = p.parse_args()
    if not 1 <= args.last <= args.interactions:
        p.error(f"--last {args.last} is invalid; allowed: 1 to --interactions")
    policies, paper = POLICIES[args.table], PAPER_TABLES[args.table]
    rows = []
    for value, (paper_mean, _) in paper["rows"].items():
        env_kwargs = {paper["parameter"]: value}  # the env kwarg the table varies
        row: dict = {paper["parameter"]: value}
        for name, make in policies.items():
            row[name] = float(np.mean([
                play(PointMassEnv(**env_kwargs), make(value, seed), args.interactions, seed)
                .last(args.last).mean_return() for seed in args.seeds]))
        folders = lili_folders(args.table, value)
        row["lili"] = [json.loads((f / "summary.json").read_text())["final_return"]
                       for f in folders]
        if args.table == "history":
            row["lili_turns_back"] = [run_turns_back(f) for f in folders]
        row["paper"] = paper_mean
        rows.append(row)
        print(row, flush=True)
    extra = ["LILI: target turns back / 100"] if args.table == "history" else []
    lines = [f"{paper['title']}: scripted bounds ({args.interactions} interactions, last "
             f"{args.last}, seeds {args.seeds}) beside LILI (final 10%)", "",
             f"| {paper['parameter']} | " + " | ".join([*policies, "LILI (ours)", *extra,
                                                       "LILI (paper)"]) + " |",
             "|---:|" + "---:|" * (len(policies) + 2 + len(extra))]
    for row in rows:
        m, se = mean_se(row["lili"])
        n = len(row["lili"])
        cells = [f"{row[name]:.3f}" for name in policies]
        cells.append("—" if m is None else f"{fmt_mean_se(m, se, '.3f', n=n)} ({n})")
        if extra:
            cells.append(" / ".join(f"{t:.0f}" for t in row["lili_turns_back"]))
        cells.append(f"{row['paper']:.4g}")
        lines.append(f"| {row[paper['parameter']]:g} | " + " | ".join(cells) + " |")
    table = "\n".join(lines)
    print(table)
    RESULTS.mkdir(exist_ok=True)
    stem = f"partner_scripted_{args.table}"
    (RESULTS / f"{stem}.json").write_text(json.dumps(rows, indent=1))
    (RESULTS / f"{stem}.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
