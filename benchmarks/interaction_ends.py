"""How interactions end over training, from run folders (no training, no checkpoints).

    python benchmarks/interaction_ends.py RUN_GLOB [RUN_GLOB ...] [--window 500]
        [--name interaction_ends]

For every run and consecutive window of ``--window`` interactions: the share that succeeded,
the share that failed before the horizon (in Lunar Lander a crash, a landing off the pad or
flying off), and the share played to the horizon without success (a lander that hovers). The
horizon is :func:`lili.envs.core.env_horizon` of the env the run's config names. Tells an agent
that cannot land from one that will not. Prints a table and writes
``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import numpy as np
from _results import records_args, window_table, write_result

from lili.envs.core import env_horizon
from lili.envs.spec import make_env
from lili.report.files import load_run


def ends(success: np.ndarray, length: np.ndarray, horizon: int,
         window: int) -> list[list[float]]:
    """Per window of ``window`` interactions: [succeeded, failed early, played to the horizon]
    as shares of the window (its last window may be shorter)."""
    out = []
    for start in range(0, len(success), window):
        ok, n = success[start:start + window] == 1, length[start:start + window]
        full = (n >= horizon) & ~ok
        out.append([float(ok.mean()), float((~ok & ~full).mean()), float(full.mean())])
    return out


def main() -> None:
    p, args, folders = records_args(__doc__, "interaction_ends", {"window": 500})
    out, rows = [], []
    for folder in folders:
        run = load_run(folder)
        if not run.has_success:
            p.error(f"run {folder} has no success column; allowed: runs of an env with success")
        try:
            env = make_env(run.env, run.config.get("env_kwargs"))
        except ValueError as e:
            p.error(f"run {folder}: {e}")
        horizon = env_horizon(env)
        env.close()
        shares = ends(run.metrics["success"], run.metrics["length"], horizon, args.window)
        rows.append((folder, [" / ".join(f"{100 * s:3.0f}" for s in w) for w in shares]))
        out.append({"run": folder, "env": run.env, "algo": run.algo, "seed": run.seed,
                    "horizon": horizon, "window": args.window, "shares": shares})
    table = window_table("% of interactions that succeeded / failed early / reached the horizon "
                         "without success", args.window, rows)
    write_result(args.name, table, runs=out)


if __name__ == "__main__":
    main()
