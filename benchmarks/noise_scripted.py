"""What the noisy partner leaves to reach: scripted Point Mass policies per step noise sigma.

    python benchmarks/noise_scripted.py [--interactions 1000] [--last 800] [--seeds 0 1]

For each sigma of the ``noise`` preset (Table 2: the partner's 0.2 rad step gets Gaussian noise
of sigma x 0.2 rad) plays, on ``PointMassEnv(step_noise=sigma)``:

- the influencer *told* the target (``lili.envs.influence.point_mass.influencer``): what noise
  costs an agent that sees the strategy (the Oracle's bound);
- the influencer told only what the *last interaction* predicts
  (:class:`~lili.envs.influence.point_mass.LastInteractionInfluencer`): the bound of an agent
  whose latent reads the last interaction, as LILI's does;
- the no-information policy (SAC's level).

Prints the mean return per interaction over the last ``--last`` interactions (mean over seeds)
beside LILI's committed runs (``results/runs/s9/noise``, final 10%, mean +- s.e.) and the
paper's, and writes ``benchmarks/results/noise_scripted.{json,md}``. About 20 s per sigma.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from lili.envs.influence.point_mass import LastInteractionInfluencer, influencer, no_information
from lili.envs.influence.scripted import play
from lili.envs.point_mass import PointMassEnv
from lili.report.paper import PAPER_TABLES
from lili.report.stats import mean_se

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
SIGMAS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)
POLICIES = {"influencer (told the target)": lambda: influencer,
            "influencer (last interaction)": LastInteractionInfluencer,
            "no information": lambda: no_information}


def lili_finals(sigma: float) -> list[float]:
    """Final returns of the committed LILI runs at ``sigma``, seeds 0-2 as the preset plans
    them (sigma 0: the Point Mass preset's runs, which the ``noise`` table reuses)."""
    runs = RESULTS / "runs" / "s9"
    folder = runs / "point-mass" if sigma == 0 else runs / "noise" / f"sigma_{sigma:g}"
    return [json.loads(p.read_text())["final_return"]
            for p in sorted(folder.glob("PointMass-v0/lili/seed_[012]/summary.json"))]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interactions", type=int, default=1000)
    p.add_argument("--last", type=int, default=800)
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    args = p.parse_args()
    if not 1 <= args.last <= args.interactions:
        p.error(f"--last {args.last} is invalid; allowed: 1 to --interactions")
    rows = []
    for sigma in SIGMAS:
        row = {"sigma": sigma}
        for name, make in POLICIES.items():
            row[name] = float(np.mean([
                play(PointMassEnv(step_noise=sigma), make(), args.interactions, seed)
                .last(args.last).mean_return() for seed in args.seeds]))
        finals = lili_finals(sigma)
        row["lili"] = finals
        row["paper"] = PAPER_TABLES["noise"]["rows"][sigma][0]
        rows.append(row)
        print(row, flush=True)
    lines = [f"Point Mass with the noisy partner: scripted bounds ({args.interactions} "
             f"interactions, last {args.last}, seeds {args.seeds}) beside LILI (final 10%)", "",
             "| sigma | " + " | ".join(POLICIES) + " | LILI (ours) | LILI (paper) |",
             "|---:|" + "---:|" * (len(POLICIES) + 2)]
    for row in rows:
        m, se = mean_se(row["lili"]) if row["lili"] else (float("nan"), float("nan"))
        paper = row["paper"]
        lines.append(f"| {row['sigma']:g} | " + " | ".join(f"{row[n]:.3f}" for n in POLICIES)
                     + f" | {m:.3f} ± {se:.3f} ({len(row['lili'])}) | "
                     + f"{paper:.4g} |")
    table = "\n".join(lines)
    print(table)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "noise_scripted.json").write_text(json.dumps(rows, indent=1))
    (RESULTS / "noise_scripted.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
