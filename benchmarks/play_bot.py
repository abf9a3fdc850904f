"""Trained blockers against the human-like bot striker: blocks out of 40, beside the paper.

    python benchmarks/play_bot.py LABEL=RUN_GLOB [LABEL=scripted:NAME ...] [--shots 40]
        [--sessions 3] [--aim-noise 0.05] [--lapse 0.1] [--name play_bot]

Each ``RUN_GLOB`` names air hockey run folders (one per training seed); every run plays
``--sessions`` sessions of ``--shots`` shots against :class:`lili.play.striker.BotStriker` (the
paper's protocol: the striker aims away from where the blocker blocked it last, with aim noise
and lapses) through the same game session as the page. Prints blocks per 40 shots (mean +- s.e.
over runs, each run's mean over sessions) and blocks by the shot's mode beside the paper's
expert-human study (SAC 18/40, LILI (no influence) 29/40), and writes
``benchmarks/results/<--name>.json``.

``LABEL=scripted:NAME`` plays a scripted blocker of ``lili.envs.air_hockey.scripted`` instead
(:class:`lili.play.policy.ScriptedBlocker`); ``scripted:greedy`` is told each shot's mode and
so gives the ceiling of a blocker that sees what the learned ones see, where only the bot's
aim noise makes it miss.
"""

from __future__ import annotations

import argparse
import glob

import numpy as np
from _results import check_result_name, write_result

from lili.play.bot import PAPER_HUMAN, run_bot
from lili.play.policy import Blocker, ScriptedBlocker, agent_file_for_run, make_play_env
from lili.play.striker import MODE_NAMES, BotConfig

SCRIPTED = "scripted:"


def score_run(run: str, shots: int, sessions: int, config: BotConfig) -> dict:
    if run.startswith(SCRIPTED):
        env_kwargs: dict = {}
        blocker = ScriptedBlocker(run.removeprefix(SCRIPTED))
    else:
        path, cfg = agent_file_for_run(run)
        env_kwargs = dict(cfg.get("env_kwargs") or {})
        blocker = Blocker.load(path, make_play_env(env_kwargs))
    blocks, by_mode = [], np.zeros((len(MODE_NAMES), 2))
    for s in range(sessions):
        res = run_bot(blocker, env_kwargs, shots, config, seed=s)
        blocks.append(res["blocks"] * 40 / res["shots"])
        for j, name in enumerate(MODE_NAMES):
            by_mode[j] += res["by_mode"][name]  # [blocks, shots]
    return {"run": run, "algo": blocker.algo, "env_kwargs": env_kwargs,
            "blocks_per_40": float(np.mean(blocks)), "sessions": blocks,
            "by_mode": {n: by_mode[j].tolist() for j, n in enumerate(MODE_NAMES)}}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("groups", nargs="+", metavar="LABEL=RUN_GLOB")
    p.add_argument("--shots", type=int, default=40)
    p.add_argument("--sessions", type=int, default=3)
    p.add_argument("--aim-noise", type=float, default=BotConfig.aim_noise)
    p.add_argument("--lapse", type=float, default=BotConfig.lapse)
    p.add_argument("--name", default="play_bot", help="results file name (without .json)")
    args = p.parse_args()
    check_result_name(p, args.name)
    config = BotConfig(aim_noise=args.aim_noise, lapse=args.lapse)
    rows, out = [], []
    for group in args.groups:
        if "=" not in group:
            p.error(f"{group!r} is invalid; allowed: LABEL=RUN_GLOB")
        label, pattern = group.split("=", 1)
        runs = [pattern] if pattern.startswith(SCRIPTED) else sorted(glob.glob(pattern))
        if not runs:
            p.error(f"{pattern!r} matches no run folder")
        scores = [score_run(r, args.shots, args.sessions, config) for r in runs]
        values = np.array([s["blocks_per_40"] for s in scores])
        se = values.std(ddof=1) / np.sqrt(len(values)) if len(values) > 1 else 0.0
        modes = {n: np.sum([s["by_mode"][n] for s in scores], 0) for n in MODE_NAMES}
        algo = scores[0]["algo"]
        paper = f"{PAPER_HUMAN[algo]}/40" if algo in PAPER_HUMAN else "—"
        rows.append(f"| {label} | {len(runs)} | {values.mean():.1f} ± {se:.1f} | "
                    + " | ".join(f"{modes[n][0] / max(modes[n][1], 1):.0%}" for n in MODE_NAMES)
                    + f" | {paper} |")
        out.append({"label": label, "runs": scores, "mean": float(values.mean()),
                    "se": float(se)})
    table = "\n".join([f"bot: aim noise {config.aim_noise} rad, lapse {config.lapse}; "
                       f"{args.sessions} sessions of {args.shots} shots per run", "",
                       "| blocker | runs | blocks / 40 (mean ± s.e.) | "
                       + " | ".join(f"{n} blocked" for n in MODE_NAMES)
                       + " | paper (expert human) |",
                       "|---|---:|---:|" + "---:|" * len(MODE_NAMES) + "---|", *rows])
    write_result(args.name, table, groups=out)


if __name__ == "__main__":
    main()
