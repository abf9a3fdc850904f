"""A trained agent's training return beside the same agent played with and without exploration.

    python benchmarks/greedy_eval.py RUN_GLOB [RUN_GLOB ...] [--interactions 500]
        [--seed 11] [--name greedy_eval]

A claim reads the mean return over the last 10% of a run's training interactions, which the
policy's exploration noise and its learning within that window both shape. For every run
folder with a checkpoint (``lili train`` keeps them; committed records do not), this prints
that training measure and what the newest checkpoint scores over ``--interactions``
consecutive interactions of a fresh env sequence (env seed ``--seed``), no learning, the
latent updated between interactions as in training (:func:`lili.evaluate.evaluate`): once
sampling its actions as in training ("sampled"), once playing the policy's mean
("deterministic"). Sampled minus training is what the last window's learning and its env
draws add; deterministic minus sampled is what exploration costs. Where the env is one of the
influence suite's, "held" gives the share of interactions in which the partner was at a
strategy the scripted influencer holds it at (:data:`lili.envs.influence.HELD`) in each of
the three. Prints a table and writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

from _results import records_args, write_result

from lili.envs.influence import HELD
from lili.evaluate import evaluate
from lili.report.files import load_run
from lili.report.stats import final_performance, held_fraction, held_share
from lili.runs import load_trained

MODES = {"sampled": False, "deterministic": True}


def _cell(ret: float, held: float | None) -> str:
    return f"{ret:.3f}" + ("" if held is None else f" ({100 * held:.0f}%)")


def main() -> None:
    p, args, folders = records_args(__doc__, "greedy_eval", {"interactions": 500},
                                    more=lambda q: q.add_argument("--seed", type=int, default=11))
    if args.seed < 0:
        p.error(f"--seed {args.seed} is invalid; allowed: an integer >= 0")
    loaded = []
    for folder in folders:  # every run checked before any plays: a bad one costs no time
        try:
            run = load_run(folder)
            agent, env, _, at = load_trained(folder)
        except ValueError as e:
            p.error(f"run {folder}: {e}; allowed: a run folder of lili train with its checkpoints")
        loaded.append((folder, run, at, env, agent))
    out, lines = [], []
    for folder, run, at, env, agent in loaded:
        held = HELD.get(run.env)
        row = {"run": folder, "env": run.env, "algo": run.algo, "seed": run.seed,
               "checkpoint": at, "training": final_performance(run),
               "training_held": held_share(run, held) if held else None}
        for mode, deterministic in MODES.items():
            res = evaluate(agent, env, args.interactions, seed=args.seed,
                           deterministic=deterministic)
            row[mode] = res["mean_return"]
            row[f"{mode}_held"] = held_fraction(res["strategy_ids"], held) if held else None
        env.close()
        out.append(row)
        lines.append(f"| {folder} | {at} | {_cell(row['training'], row['training_held'])} | "
                     + " | ".join(_cell(row[m], row[f"{m}_held"]) for m in MODES) + " |")
    table = "\n".join([
        f"Mean return per interaction (held share where the env has one): training = its last "
        f"10%, sampled / deterministic = the checkpoint over {args.interactions} interactions "
        f"(env seed {args.seed})", "",
        "| run | checkpoint | training | sampled | deterministic |", "|---|---:|---:|---:|---:|",
        *lines])
    write_result(args.name, table, runs=out, interactions=args.interactions, seed=args.seed)


if __name__ == "__main__":
    main()
