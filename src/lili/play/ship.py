"""Train the agent that ships with the package: ``python -m lili.play.ship``.

Writes ``agents/air_hockey.msgpack`` (the agent, under 5 MB) and ``agents/air_hockey.json``
(how it was trained: algo, interactions, seed, env options, config) beside this module, so that
``lili play air-hockey`` works right after ``pip install``. ``--out`` writes elsewhere (tests
rerun the script at a tiny budget that way).

``--from-run RUN`` ships the final agent of an air hockey run folder of ``lili train`` instead of
training again: ``lili train`` and this script run the same loop, so the agent file is the same
byte for byte for the same algo, budget, seed, env options and config (a test checks it), and
the run's config.yaml becomes the JSON's record of how it was trained.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import yaml

from lili.play.policy import SHIPPED_AGENT, train_and_save

__all__ = ["main", "MAX_BYTES"]

MAX_BYTES = 5 * 2**20


def main(argv: list[str] | None = None) -> int:
    """Train and save; exit code 2 with one message on bad input."""
    p = argparse.ArgumentParser(prog="python -m lili.play.ship",
                                description=__doc__.splitlines()[0])
    p.add_argument("--algo", default="lili", help="agent to train (default lili)")
    p.add_argument("--interactions", type=int, default=2000, help="budget (default 2000)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE",
                   help="air hockey option, e.g. aim_noise=0.05 (repeatable)")
    p.add_argument("--config", help="YAML file with AgentConfig fields to change")
    p.add_argument("--out", default=str(SHIPPED_AGENT),
                   help=f"agent file (default {SHIPPED_AGENT})")
    p.add_argument("--from-run", metavar="RUN",
                   help="ship the final agent of this air hockey run folder (no training)")
    args = p.parse_args(argv)
    if args.from_run:
        try:
            out, meta = copy_from_run(args.from_run, args.out)
        except ValueError as e:
            print(f"lili.play.ship: error: {e}", file=sys.stderr)
            return 2
        return _finish(Path(out), meta)
    try:
        if args.interactions < 1:
            raise ValueError(f"--interactions {args.interactions} is invalid; allowed: >= 1")
        env_kwargs = {}
        for item in args.env_kwarg:
            if "=" not in item:
                raise ValueError(f"--env-kwarg {item!r} is invalid; allowed: KEY=VALUE")
            key, value = item.split("=", 1)
            env_kwargs[key] = yaml.safe_load(value)
        config = None
        if args.config:
            from lili.config import load_config

            config = load_config(args.config).to_dict()
        start = time.time()
        out = train_and_save(args.algo, args.interactions, args.seed, args.out, env_kwargs,
                             config, progress=sys.stderr.isatty())
    except (ValueError, FileNotFoundError) as e:
        print(f"lili.play.ship: error: {e}", file=sys.stderr)
        return 2
    meta = {"algo": args.algo, "interactions": args.interactions, "seed": args.seed,
            "env_kwargs": env_kwargs, "config": config,
            "wall_time_s": round(time.time() - start, 1)}
    return _finish(Path(out), meta)


def copy_from_run(run: str | Path, out: str | Path) -> tuple[Path, dict[str, Any]]:
    """Copy the final agent of air hockey run folder ``run`` to ``out``; return the path and
    the record of how it was trained. ValueError naming the folder when it does not fit."""
    from lili.runs import latest_checkpoint, read_run_config

    cfg = read_run_config(run)  # CheckpointError is a ValueError too
    if cfg["env"] != "lili/AirHockey-v0":
        raise ValueError(f"{run} is a run of {cfg['env']!r}; allowed: a lili/AirHockey-v0 run")
    ck, done = latest_checkpoint(run)
    if done != int(cfg["interactions"]):
        raise ValueError(f"{run} is not finished ({done} of {cfg['interactions']} "
                         "interactions); allowed: a finished run")
    path = ck / "agent.msgpack"
    if path.stat().st_size > MAX_BYTES:
        raise ValueError(f"{path} is {path.stat().st_size / 2**20:.1f} MiB; the shipped agent "
                         "must stay under 5 MiB")
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(path, out)
    env_kwargs = cfg.get("env_kwargs") or {}
    meta = {"algo": cfg["algo"], "interactions": done, "seed": cfg["seed"],
            "env_kwargs": env_kwargs, "config": cfg["agent"],
            "trained_by": f"lili train lili/AirHockey-v0 --algo {cfg['algo']} --seed "
                          f"{cfg['seed']} --interactions {done}"
                          + "".join(f" --env-kwarg {k}={v}" for k, v in env_kwargs.items())
                          + _config_flag(cfg["agent"]),
            "from_run": str(run)}
    return Path(out), meta


def _config_flag(agent: dict[str, Any]) -> str:
    """`` --config FILE`` naming the fields of ``agent`` that differ from the defaults (the
    file itself is not kept; its content is the record's ``config``), or nothing."""
    from lili.config import AgentConfig

    default = AgentConfig().to_dict()
    changed = {k: v for k, v in agent.items() if k in default and default[k] != v}
    if not changed:
        return ""
    return " --config FILE  # FILE: " + ", ".join(f"{k}: {v}" for k, v in changed.items())


def _finish(out: Path, meta: dict[str, Any]) -> int:
    """Check the size, write the JSON record beside the agent, and say so."""
    size = out.stat().st_size
    if size > MAX_BYTES:
        print(f"lili.play.ship: error: {out} is {size / 2**20:.1f} MiB; the shipped agent must "
              "stay under 5 MiB", file=sys.stderr)
        return 2
    Path(out).with_suffix(".json").write_text(json.dumps(meta, indent=1) + "\n")
    print(f"wrote {out} ({size / 2**20:.2f} MiB) and {Path(out).with_suffix('.json').name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
