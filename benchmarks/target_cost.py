"""How much of a Point Mass run's return is where its target sat, and how much how it reached it.

    python benchmarks/target_cost.py RUN_GLOB [RUN_GLOB ...] [--last 200] [--history 800]
        [--name target_cost]

For every run of ``lili/PointMass-v0`` over its last ``--last`` interactions: the mean return,
the mean **reach cost** of the targets it met (the return the scripted greedy policy earns in
one interaction with that target: straight to it at full speed, then on it; targets near the
circle's top, next to the start, are cheap, those at its bottom dear) and the **shortfall**,
return minus reach cost (how much worse than greedy the run reached the targets it met; the
exploring agent's noise is part of it). The partner's choices change only where the target
sits, so of two runs that differ in return, the reach cost tells how much is the partner's
doing (where the ego kept, or let go, the target) and the shortfall how much is reaching.
The shortfall is also split between targets met often and seldom before, as
``target_spread.py`` splits the return (sectors met more often than the median target in the
``--history`` interactions before): is a run that reaches worse reaching worse everywhere, or
only where it seldom trained?
Prints a table and writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import numpy as np
from _results import records_args, write_result
from target_spread import partner_setting, sectors, spread

from lili.envs.influence.point_mass import SCRIPTED
from lili.envs.point_mass import CENTER, PointMassEnv
from lili.report.files import load_run


class ReachCost:
    """The greedy policy's return in one interaction with the target at a given angle, rolled
    out in the env itself (one home for its dynamics), memoised per angle."""

    def __init__(self) -> None:
        self.env = PointMassEnv()
        self.env.reset(seed=0)
        self.greedy = SCRIPTED["greedy"](0)
        self.cache: dict[float, float] = {}

    def __call__(self, theta: float) -> float:
        key = round(float(theta) % (2 * np.pi), 9)
        if key not in self.cache:
            self.env.partner.theta = key  # read by the next interaction's start
            obs, info = self.env.reset()
            total, done = 0.0, False
            while not done:
                obs, reward, terminated, truncated, info = self.env.step(self.greedy(obs, info))
                total += reward
                done = terminated or truncated
            self.cache[key] = total
        return self.cache[key]


def target_angles(run_metrics: dict[str, np.ndarray]) -> np.ndarray:
    """The target's angle round the circle's centre at every interaction (radians); the run's
    strategy columns are checked by :func:`target_spread.sectors`, which :func:`split` calls
    first."""
    return np.arctan2(run_metrics["strategy_1"] - CENTER[1], run_metrics["strategy_0"] - CENTER[0])


def split(run_metrics: dict[str, np.ndarray], last: int, history: int,
          cost: ReachCost) -> dict[str, float]:
    """The figures of one run (see the module docstring); ValueError when it is too short."""
    returns = run_metrics["return"]
    sector = sectors(run_metrics)
    # spread() checks the length and reads only the last `last` entries of what it splits.
    by_return = spread(returns, sector, last, history)
    reach = np.full(len(returns), np.nan)
    reach[-last:] = [cost(a) for a in target_angles(run_metrics)[-last:]]
    by_shortfall = spread(returns - reach, sector, last, history)
    return {"return": by_return["return"], "reach_cost": float(np.mean(reach[-last:])),
            "shortfall": by_shortfall["return"], "sectors": by_return["sectors"],
            "shortfall_often": by_shortfall["return_often"],
            "shortfall_seldom": by_shortfall["return_seldom"],
            "n_often": by_return["n_often"], "n_seldom": by_return["n_seldom"]}


def main() -> None:
    p, args, folders = records_args(__doc__, "target_cost", {"last": 200, "history": 800})
    cost, out, lines = ReachCost(), [], []
    for folder in folders:
        run = load_run(folder)
        if run.env != "lili/PointMass-v0":
            p.error(f"{folder}: env {run.env!r} is not lili/PointMass-v0")
        try:
            row = split(run.metrics, args.last, args.history, cost)
        except ValueError as e:
            p.error(f"{folder}: {e}")
        kwargs, setting = partner_setting(run.config)
        out.append({"run": folder, "algo": run.algo, "seed": run.seed, "env_kwargs": kwargs,
                    "interactions": len(run.metrics["return"]), **row})
        lines.append(f"| {folder} | {setting} | {row['return']:.3f} | {row['reach_cost']:.3f} | "
                     f"{row['shortfall']:.3f} | {row['sectors']} | "
                     f"{row['shortfall_often']:.3f} ({row['n_often']}) | "
                     f"{row['shortfall_seldom']:.3f} ({row['n_seldom']}) |")
    table = "\n".join([
        f"last {args.last} interactions; reach cost: the scripted greedy policy's return on the "
        "targets the run met; shortfall: return minus reach cost; often/seldom: the target's "
        f"sector met more / not more often than the median target in the {args.history} "
        "interactions before", "",
        "| run | partner | return | reach cost | shortfall | sectors visited | "
        "shortfall, often-met target (n) | shortfall, seldom-met target (n) |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
        *lines])
    write_result(args.name, table, last=args.last, history=args.history, runs=out)


if __name__ == "__main__":
    main()
