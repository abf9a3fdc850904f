"""Command line: ``lili train | eval | report | check-env | play``.

Every bad input ends with one line ``lili: error: ...`` naming the value and what is allowed,
exit code 2, and nothing overwritten.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import yaml

__all__ = ["main"]


class UsageError(ValueError):
    """A bad command-line value."""


def _parse_kwargs(items: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise UsageError(f"--env-kwarg {item!r} is invalid; allowed: KEY=VALUE")
        k, v = item.split("=", 1)
        out[k] = yaml.safe_load(v)
    return out


def _make_env(env_id: str, kwargs: dict[str, Any], render_mode: str | None = None):
    import gymnasium as gym

    import lili.envs  # noqa: F401 - registers the ids (``lili eval`` reaches here first)

    try:
        if render_mode is not None:
            kwargs = {**kwargs, "render_mode": render_mode}
        return gym.make(env_id, **kwargs)
    except TypeError as e:
        raise UsageError(f"env {env_id} does not accept these kwargs {kwargs}: {e}") from None


def cmd_train(args: argparse.Namespace) -> int:
    from lili.agents import ALGOS, make_agent
    from lili.config import AgentConfig, load_config
    from lili.envs import resolve_env_id
    from lili.runs import RunLogger, load_checkpoint, run_dir_for
    from lili.train import train

    env_id = resolve_env_id(args.env)
    if args.algo not in ALGOS:
        raise UsageError(f"unknown algo {args.algo!r}; allowed: {', '.join(ALGOS)}")
    if args.interactions < 1:
        raise UsageError(f"--interactions {args.interactions} is invalid; allowed: an integer >= 1")
    if args.seed < 0:
        raise UsageError(f"--seed {args.seed} is invalid; allowed: an integer >= 0")
    config = load_config(args.config) if args.config else AgentConfig()
    env_kwargs = _parse_kwargs(args.env_kwarg)
    run_dir = run_dir_for(args.out, env_id, args.algo, args.seed)
    resolved = {"env": env_id, "env_kwargs": env_kwargs, "algo": args.algo, "seed": args.seed,
                "interactions": args.interactions, "agent": config.to_dict()}

    exists = (run_dir / "metrics.csv").exists()
    if exists and not args.resume:
        raise UsageError(f"run folder {run_dir} already holds a run; pass --resume to continue "
                         "it or choose another --out")
    if args.resume and not exists:
        raise UsageError(f"--resume: there is no run to resume in {run_dir}")
    if args.resume:
        old = yaml.safe_load((run_dir / "config.yaml").read_text())
        for key in ("env", "env_kwargs", "algo", "seed", "agent"):
            if old.get(key) != resolved[key]:
                raise UsageError(f"--resume: {key} differs from the run in {run_dir} "
                                 f"({old.get(key)!r} there, {resolved[key]!r} now)")

    env = _make_env(env_id, env_kwargs)
    agent = make_agent(args.algo, env, config, args.seed)
    start = 0
    if args.resume and (run_dir / "checkpoints" / "latest.json").exists():
        load_checkpoint(run_dir, agent)
        start = agent.num_interactions
    remaining = args.interactions - start
    if remaining < 0:
        raise UsageError(f"--interactions {args.interactions} is below the {start} the run has "
                         "already done")
    strategy_dim = int(env.unwrapped.strategy_space.shape[0])
    logger = RunLogger(run_dir, resolved, strategy_dim, config.checkpoint_every, start)
    print(f"training {args.algo} on {env_id} (seed {args.seed}) -> {run_dir}"
          + (f" (resumed at interaction {start})" if start else ""))
    try:
        train(agent, remaining, progress=not args.no_progress, logger=logger)
    except KeyboardInterrupt:
        logger.close()
        print(f"interrupted; resume with the same command and --resume (from interaction "
              f"{agent.num_interactions // config.checkpoint_every * config.checkpoint_every})")
        return 130
    summary = logger.finish(agent, resolved)
    line = f"final return (last 10%): {summary['final_return']:.3f}"
    if summary["final_success"] is not None:
        line += f", success {summary['final_success']:.2f}"
    print(line + f"; wall time {summary['wall_time_s']:.0f} s")
    return 0


def cmd_eval(args: argparse.Namespace) -> int:
    from lili.agents import CheckpointError, load_agent
    from lili.evaluate import evaluate

    run_dir = Path(args.run)
    cfg_path = run_dir / "config.yaml"
    if not cfg_path.is_file():
        raise UsageError(f"{run_dir} is not a run folder (config.yaml is missing)")
    cfg = yaml.safe_load(cfg_path.read_text())
    ptr = run_dir / "checkpoints" / "latest.json"
    if not ptr.is_file():
        raise CheckpointError(f"{run_dir} has no checkpoint to evaluate")
    ck = run_dir / "checkpoints" / json.loads(ptr.read_text())["checkpoint"]
    if args.interactions < 1:
        raise UsageError(f"--interactions {args.interactions} is invalid; allowed: an integer >= 1")
    env = _make_env(cfg["env"], cfg.get("env_kwargs", {}),
                    "rgb_array" if args.video else None)
    agent = load_agent(ck / "agent.msgpack", env)
    frames: list | None = [] if args.video else None
    res = evaluate(agent, None, args.interactions, seed=args.seed, frames=frames)
    msg = f"{cfg['algo']} on {cfg['env']}: mean return {res['mean_return']:.3f} over " \
          f"{args.interactions} interactions"
    if res["success_rate"] is not None:
        msg += f", success rate {res['success_rate']:.2f}"
    print(msg)
    if args.video and frames:
        from lili.video import write_video

        print(f"video: {write_video(frames, args.video)}")
    out = run_dir / "eval.json"
    out.write_text(json.dumps({k: v for k, v in res.items()}, indent=1))
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from lili.report import markdown_table, write_report

    if args.upto is not None and args.upto < 1:
        raise UsageError(f"--upto {args.upto} is invalid; allowed: an integer >= 1")
    out = Path(args.out) if args.out else Path(args.runs[0]) / "report"
    summary = write_report(args.runs, out, upto=args.upto)
    print(markdown_table(summary))
    print(f"figures and tables in {out}")
    return 0


def cmd_check_env(args: argparse.Namespace) -> int:
    from lili.envs.checker import check_env, load_env_class

    factory = load_env_class(args.env)
    check_env(factory, n_interactions=args.interactions, seed=args.seed)
    print(f"{args.env}: passes Gymnasium's checker and the repeated-interaction contract")
    return 0


def cmd_play(args: argparse.Namespace) -> int:
    from lili.play.command import run_play

    return run_play(args)


def build_parser() -> argparse.ArgumentParser:
    from lili.agents import ALGOS

    p = argparse.ArgumentParser(prog="lili", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    t = sub.add_parser("train", help="train an agent and write a run folder")
    t.add_argument("env", help="registered id (lili/PointMass-v0) or alias (point-mass)")
    t.add_argument("--algo", default="lili", help=f"one of {', '.join(ALGOS)} (default lili)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--interactions", type=int, default=2000, help="budget (default 2000)")
    t.add_argument("--out", default="runs/default", help="experiment folder (default runs/default)")
    t.add_argument("--config", help="YAML file with AgentConfig fields to change")
    t.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE",
                   help="env option, e.g. step_noise=0.2 or history=3 (repeatable)")
    t.add_argument("--resume", action="store_true", help="continue the run in the folder")
    t.add_argument("--no-progress", action="store_true", help="no progress bar")
    t.set_defaults(func=cmd_train)

    e = sub.add_parser("eval", help="evaluate a run's latest checkpoint without learning")
    e.add_argument("run", help="run folder")
    e.add_argument("--interactions", type=int, default=100)
    e.add_argument("--seed", type=int, default=12345, help="seed of the env sequence")
    e.add_argument("--video", help="write the interactions to this animated .gif")
    e.set_defaults(func=cmd_eval)

    r = sub.add_parser("report", help="curves, tables and heatmaps from run folders")
    r.add_argument("runs", nargs="+", help="run folders or folders containing them")
    r.add_argument("--out", help="output folder (default RUN/report)")
    r.add_argument("--upto", type=int, metavar="N",
                   help="compare at one budget: use only each run's first N interactions")
    r.set_defaults(func=cmd_report)

    c = sub.add_parser("check-env", help="check an env against the repeated-interaction contract")
    c.add_argument("env", help="MODULE:CLASS, or a registered id")
    c.add_argument("--interactions", type=int, default=6)
    c.add_argument("--seed", type=int, default=0)
    c.set_defaults(func=cmd_check_env)

    from lili.play.command import add_arguments as play_arguments

    p_play = sub.add_parser("play", help="play against a trained agent in a browser (or a bot)")
    play_arguments(p_play)
    p_play.set_defaults(func=cmd_play)
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``lili`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (ValueError, FileNotFoundError) as e:  # UsageError, CheckpointError, EnvContractError
        print(f"lili: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
