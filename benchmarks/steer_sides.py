"""Which side each Driving (steering) run ends its interactions on, read from its records.

    python benchmarks/steer_sides.py RUN_GLOB [RUN_GLOB ...] [--last 100] [--name steer_sides]

The opponent swerves, in interaction i + 1, to the side the ego ended interaction i on (its
final lateral position: left of the middle lane's centre line or not; ``history`` 1), so the
partner strategy that ``metrics.csv`` logs for i + 1 is the ego's end side in i: the records
hold every interaction's end side though no run logs it. Over each run's last ``--last``
interactions this prints the share ending on the left, how often the end side differs from the
one before (a policy that passes on the other side each time and stays there switches every
interaction; one that keeps one side never does), the success rate, the mean length (a
collision or lane violation ends an interaction early), and the policy's entropy and SAC
temperature alpha as logged. It also resets the env with several seeds and says whether the
first observation of an interaction ever differs: where it never does, a policy that cannot
see the past meets the same start every time, and only its sampling noise can vary its side.
Writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from _results import records_args, write_result

import lili  # noqa: F401  (registers the envs)
from lili.report.files import load_run

ENV = "lili/DrivingSteer-v0"


def end_sides(strategy_id: np.ndarray) -> np.ndarray:
    """The ego's end side (0 left, 1 right) of interactions 0 .. n-2: the opponent's target of
    the interaction after each."""
    return np.asarray(strategy_id[1:], dtype=int)


def side_figures(strategy_id: np.ndarray, last: int) -> dict[str, float]:
    """Left share and switch rate of the end sides over the last ``last`` interactions that
    have a successor; ValueError when the run is shorter."""
    sides = end_sides(strategy_id)
    if len(sides) < last + 1:
        raise ValueError(f"the run has {len(strategy_id)} interactions; --last {last} needs "
                         f"{last + 2}")
    recent = sides[-last:]
    switched = sides[1:][-last:] != sides[:-1][-last:]
    return {"left_share": float(np.mean(recent == 0)), "switch_rate": float(np.mean(switched))}


def distinct_starts(seeds: range = range(8)) -> int:
    """How many different first observations the env gives over ``seeds`` resets."""
    env = gym.make(ENV)
    starts = {env.reset(seed=s)[0].tobytes() for s in seeds}
    env.close()
    return len(starts)


def _tail_mean(values: np.ndarray, last: int) -> float:
    tail = np.asarray(values[-last:], dtype=float)
    tail = tail[~np.isnan(tail)]
    return float(tail.mean()) if len(tail) else float("nan")


def main() -> None:
    p, args, folders = records_args(__doc__, "steer_sides", {"last": 100})
    out, lines = [], []
    for folder in folders:
        run = load_run(folder)
        history = (run.config.get("env_kwargs") or {}).get("history", 1)
        if run.env != ENV or history != 1:
            p.error(f"{folder}: a run of {run.env} (history {history}); allowed: {ENV} with "
                    f"history 1")
        m = run.metrics
        try:
            row = side_figures(m["strategy_id"], args.last)
        except ValueError as e:
            p.error(f"{folder}: {e}")
        row.update({"success": _tail_mean(m["success"], args.last),
                    "length": _tail_mean(m["length"], args.last),
                    "entropy": _tail_mean(m["entropy"], args.last),
                    "alpha": _tail_mean(m["alpha"], args.last)})
        out.append({"run": folder, "algo": run.algo, "seed": run.seed, **row})
        lines.append(f"| {folder} | {run.algo} | {row['left_share']:.2f} | "
                     f"{row['switch_rate']:.2f} | {row['success']:.2f} | {row['length']:.1f} | "
                     f"{row['entropy']:.2f} | {row['alpha']:.4f} |")
    starts = distinct_starts()
    table = "\n".join([
        f"last {args.last} interactions; end side = the opponent's target of the next "
        f"interaction; the env's first observation over 8 seeded resets: {starts} distinct", "",
        "| run | algo | ends left | end side switches | success | length | entropy | alpha |",
        "|---|---|---:|---:|---:|---:|---:|---:|", *lines])
    write_result(args.name, table, last=args.last, distinct_starts=starts, runs=out)


if __name__ == "__main__":
    main()
