"""The influence suite: scripted no-information, greedy and influencing policies per env, and
(with ``--algos``) learned agents beside them with the gap each closes from SAC to the
influencer, and (with ``--ablate``) LILI variants, one changed option each.

    python benchmarks/influence.py                          # scripted policies only (~30 s)
    python benchmarks/influence.py --algos sac lili-no-influence lili oracle   # + learned
    python benchmarks/influence.py --algos sac lili-no-influence lili \
        --ablate gamma=0.999 --ablate updates_per_step=4     # + one LILI row per variant

Scripted rows: the mean return per interaction over the last ``--last`` of ``--scripted``
interactions (Point Mass and Drift: 3000 and 2000, because Point Mass's greedy target
random-walks slowly and Drift's partner returns at random; Flee: 300 and 240, whole cycles),
seeds 0-1, beside the value derived in each env's docstring. Learned rows are the runs of the
``influence`` preset of ``lili reproduce`` (or, for a variant of ``lili.contrib``, of its
``contrib`` preset, on the suite's envs; 2000 interactions, 3 seeds by default; finished
runs are skipped, killed ones resumed; ``--jobs`` at a time) under ``--out``; an ablation
``FIELD=VALUE[,FIELD=VALUE]`` is the preset's LILI runs (or ``--ablate-algos``') with those
agent-config fields (``lili reproduce influence --algos lili --set ...``) under
``--out``/ablate/<variant>. Each seed scores the mean return over the last 10% of its
interactions (mean +- s.e. over seeds).
Gap closed = (R - R_SAC) / (R_influencer - R_SAC); "held" = the share of those interactions
in which the partner was at a strategy the scripted influencer holds it at
(:data:`lili.envs.influence.HELD`), the behavioural evidence of influence; "vs no influence" =
R - R_LILI(no influence) in units of their combined standard errors. Writes
``benchmarks/results/<--name>.{json,md}``; with ``--merge`` the learned rows already in that
JSON that this invocation does not recompute are kept (so ablations can be added one command
at a time).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import gymnasium as gym
import numpy as np
from _results import RESULTS, check_result_name

from lili.agents.registry import CONTRIB_ALGOS
from lili.cli import parse_overrides
from lili.envs.influence import HELD, SUITE, make_scripted, play
from lili.experiments import reproduce
from lili.experiments.presets import INFLUENCE_ENVS, get_preset
from lili.report import find_runs
from lili.report.stats import final_performance, gap_share, held_share, mean_se
from lili.report.style import algo_label

ROOT = Path(__file__).resolve().parent.parent
# Point Mass's greedy target takes a slow random walk round the circle, and Drift's partner
# returns at random about every 20 interactions: average them out. Flee's scripted policies
# cycle through 6 and 8 slots: count a whole number of both.
SCRIPTED_BUDGET = {"lili/PointMass-v0": (3000, 2000), "lili/InfluenceDrift-v0": (3000, 2000),
                   "lili/InfluenceFlee-v0": (300, 240)}


def scripted_returns(env_id: str, interactions: int, last: int, seeds=(0, 1)) -> dict:
    """Mean return over the last ``last`` interactions, per scripted policy (mean over seeds)."""
    interactions, last = SCRIPTED_BUDGET.get(env_id, (interactions, last))
    out = {}
    for name in SUITE[env_id][0]:
        per_seed = [play(gym.make(env_id), make_scripted(env_id, name, s), interactions, s)
                    .last(last).mean_return() for s in seeds]
        out[name] = {"mean": float(np.mean(per_seed)), "per_seed": per_seed,
                     "known": SUITE[env_id][1].get(name), "interactions": interactions,
                     "last": last}
    return out


def _score(runs: list, env_id: str) -> dict:
    """Final return and held share per seed of ``runs`` (one algo on one env)."""
    runs = sorted(runs, key=lambda r: r.seed)
    finals = [final_performance(r) for r in runs]
    held = [held_share(r, HELD[env_id]) for r in runs]
    mean, se = mean_se(finals)
    return {"mean": mean, "se": se, "per_seed": finals, "held": float(np.mean(held)),
            "held_per_seed": held,
            "seeds": [r.seed for r in runs],
            "interactions": min(r.n_interactions for r in runs)}


def learned_returns(algos: list[str], envs: list[str], seeds: int | None,
                    interactions: int | None, jobs: int, out: Path,
                    overrides: dict | None = None) -> dict:
    """Run ``algos`` on ``envs`` (with agent-config ``overrides``) into ``out`` and score them:
    {env: {algo: score}}. The ``influence`` preset's algos run there; the variants of
    :mod:`lili.contrib` through the ``contrib`` preset (on the envs it has)."""
    scores: dict = {}
    for preset, mine in (("influence", [a for a in algos if a not in CONTRIB_ALGOS]),
                         ("contrib", [a for a in algos if a in CONTRIB_ALGOS])):
        have = {g.env for g in get_preset(preset).groups}
        where = [e for e in envs if e in INFLUENCE_ENVS and e in have]
        if mine and where:
            for env_id, rows in _learned(preset, mine, where, seeds, interactions, jobs, out,
                                         overrides).items():
                scores.setdefault(env_id, {}).update(rows)
    return scores


def _learned(preset: str, algos: list[str], envs: list[str], seeds: int | None,
             interactions: int | None, jobs: int, out: Path, overrides: dict | None) -> dict:
    reproduce(preset, out, seeds=seeds, interactions=interactions, jobs=jobs,
              algos=tuple(algos), envs=tuple(envs), overrides=overrides, say=lambda line: None)
    n = interactions or get_preset(preset).interactions
    runs = find_runs([out / get_preset(preset).groups[0].folder], upto=n)
    scores: dict = {}
    for env_id in envs:
        for algo in algos:
            mine = [r for r in runs if r.env == env_id and r.algo == algo]
            if mine:
                scores.setdefault(env_id, {})[algo] = _score(mine, env_id)
    return scores


def table(env_id: str, scripted: dict, learned: dict) -> list[str]:
    lines = [f"### {env_id}", "", "| policy | return / interaction | derived | gap closed | "
             "held | vs no influence |", "|---|---:|---:|---:|---:|---:|"]
    sac = learned.get("sac", {}).get("mean")
    top = scripted["influencer"]["mean"]
    base = learned.get("lili-no-influence")
    for name, row in scripted.items():
        known = "" if row["known"] is None else f"{row['known']:.3f}"
        lines.append(f"| scripted: {name.replace('-', ' ')} | {row['mean']:.3f} | {known} "
                     "| | | |")
    for algo, row in learned.items():
        share = gap_share(row["mean"], sac, top)
        gap = "" if share is None else f"{share:.2f}"
        versus = ""
        if base is not None and "no-influence" not in algo and "no influence" not in algo \
                and algo != "sac":
            se = float(np.hypot(row["se"], base["se"]))
            diff = row["mean"] - base["mean"]
            versus = f"{diff:+.3f} ({diff / se:+.1f} s.e.)" if se > 0 else f"{diff:+.3f}"
        lines.append(f"| {algo_label(algo)} ({len(row['per_seed'])} seeds, "
                     f"{row['interactions']} int.) | {row['mean']:.3f} ± {row['se']:.3f} | "
                     f"| {gap} | {_held(row)} | {versus} |")
    return lines + [""]


def _held(row: dict) -> str:
    """The held share, with each seed's where the row has them (not rows of older reports)."""
    text = f"{100 * row['held']:.0f}%"
    seeds = row.get("held_per_seed")
    if seeds and len(seeds) > 1:
        text += " (" + " / ".join(f"{100 * h:.0f}" for h in seeds) + ")"
    return text


def merged(path: Path, learned: dict) -> dict:
    """``learned`` over the learned rows of an earlier report at ``path`` (new rows win)."""
    if not path.exists():
        return learned
    try:
        old = json.loads(path.read_text())
        out = {env: dict(entry["learned"]) for env, entry in old.items()}
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise SystemExit(f"--merge: {path} is not a report of this script ({e})") from None
    for env_id, rows in learned.items():
        out.setdefault(env_id, {}).update(rows)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--envs", nargs="+", default=list(SUITE), choices=list(SUITE))
    p.add_argument("--scripted", type=int, default=300, help="interactions per scripted run")
    p.add_argument("--last", type=int, default=200, help="scripted interactions counted")
    p.add_argument("--algos", nargs="*", default=[], help="learned agents (the influence preset)")
    p.add_argument("--ablate", action="append", default=[], metavar="FIELD=VALUE[,...]",
                   help="a LILI variant with these agent-config fields (repeatable)")
    p.add_argument("--ablate-algos", nargs="+", default=["lili"],
                   help="the agents each --ablate variant trains (default lili)")
    p.add_argument("--interactions", type=int, help="per learned run (default: the preset's)")
    p.add_argument("--seeds", type=int, help="seeds per learned agent (default: the preset's)")
    p.add_argument("--jobs", type=int, default=2, help="runs at a time")
    p.add_argument("--out", default=str(ROOT / "runs" / "bench_influence"))
    p.add_argument("--name", default="influence", help="results file stem")
    p.add_argument("--merge", action="store_true",
                   help="keep the learned rows of results/<--name>.json not recomputed now")
    args = p.parse_args()
    check_result_name(p, args.name)
    if not 1 <= args.last <= args.scripted:
        p.error(f"--last {args.last} is invalid; allowed: 1 to --scripted ({args.scripted})")
    allowed = (*get_preset("influence").algos, *CONTRIB_ALGOS)
    bad = [a for a in args.algos + args.ablate_algos if a not in allowed]
    if bad:
        p.error(f"--algos {' '.join(bad)} is invalid; allowed: {', '.join(allowed)}")
    try:
        variants = {v: parse_overrides(v.split(","), "--ablate") for v in args.ablate}
    except ValueError as e:
        p.error(str(e))
    out = Path(args.out)
    learned: dict = {}
    if args.algos:
        learned = learned_returns(args.algos, args.envs, args.seeds, args.interactions, args.jobs,
                                  out)
    for text, fields in variants.items():
        scores = learned_returns(args.ablate_algos, args.envs, args.seeds, args.interactions,
                                 args.jobs, out / "ablate" / text.replace(",", "_"), fields)
        for env_id, by_algo in scores.items():
            for algo, score in by_algo.items():
                learned.setdefault(env_id, {})[f"{algo_label(algo)} ({text})"] = score
    if args.merge:
        learned = merged(RESULTS / f"{args.name}.json", learned)
    report, lines = {}, []
    for env_id in args.envs:
        scripted = scripted_returns(env_id, args.scripted, args.last)
        mine = learned.get(env_id, {})
        report[env_id] = {"scripted": scripted, "learned": mine}
        lines += table(env_id, scripted, mine)
        print("\n".join(table(env_id, scripted, mine)), flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.name}.json").write_text(json.dumps(report, indent=1))
    (RESULTS / f"{args.name}.md").write_text("\n".join(lines))


if __name__ == "__main__":
    main()
