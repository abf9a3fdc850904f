"""Train the agent that ships with the package: ``python -m lili.play.ship``.

Writes ``agents/air_hockey.msgpack`` (the agent, under 5 MB) and ``agents/air_hockey.json``
(how it was trained: algo, interactions, seed, env options, config) beside this module, so that
``lili play air-hockey`` works right after ``pip install``. ``--out`` writes elsewhere (tests
rerun the script at a tiny budget that way).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

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
    args = p.parse_args(argv)
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
    size = out.stat().st_size
    if size > MAX_BYTES:
        print(f"lili.play.ship: error: {out} is {size / 2**20:.1f} MiB; the shipped agent must "
              "stay under 5 MiB", file=sys.stderr)
        return 2
    meta = {"algo": args.algo, "interactions": args.interactions, "seed": args.seed,
            "env_kwargs": env_kwargs, "config": config,
            "wall_time_s": round(time.time() - start, 1)}
    Path(out).with_suffix(".json").write_text(json.dumps(meta, indent=1) + "\n")
    print(f"wrote {out} ({size / 2**20:.2f} MiB) and {Path(out).with_suffix('.json').name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
