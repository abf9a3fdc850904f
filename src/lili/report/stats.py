"""Statistics over run folders: final performance per seed, mean +- s.e. over seeds, gap closed,
and the interval estimates of Agarwal et al. 2021 ("Deep RL at the edge of the statistical
precipice"): the interquartile mean (IQM) across seeds and the probability of improvement
P(X > Y), each with a stratified bootstrap 95% confidence interval (SciPy's
``scipy.stats.bootstrap``, percentile method, a fixed seed: the same numbers every time)."""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from lili.report.files import Run
from lili.report.paper import paper_reference
from lili.report.style import algo_sort_key, env_sort_key

__all__ = ["final_performance", "mean_se", "summarize", "group_runs", "moving_average",
           "strategy_frequencies", "success_by_strategy", "strategy_names", "STRATEGY_WINDOW",
           "gap_closed", "gap_share", "held_share", "held_fraction", "iqm", "iqm_ci",
           "probability_of_improvement",
           "probability_of_improvement_ci", "BOOTSTRAP_RESAMPLES", "BOOTSTRAP_SEED",
           "CONFIDENCE"]

STRATEGY_WINDOW = 200
BOOTSTRAP_RESAMPLES = 2000
"""Bootstrap resamples per interval: the interval's bounds move by well under a hundredth of
the spread between seeds from one seed of the resampler to another, and a report stays fast."""
BOOTSTRAP_SEED = 0
"""The resampler's seed: the same runs give the same intervals, byte for byte."""
CONFIDENCE = 0.95


def final_performance(run: Run, metric: str = "return", frac: float = 0.1) -> float:
    """Mean of ``metric`` over the last ``frac`` of the run's interactions (at least one).

    This is :func:`lili.runs.final_mean` over the metric's non-empty cells, the number that
    ``summary.json`` holds. NaN when the metric has no value at all (e.g. ``success`` in an
    env that defines none). Raises ValueError for an unknown metric, a
    ``frac`` outside (0, 1] or a run without interactions.
    """
    if not 0.0 < frac <= 1.0:
        raise ValueError(f"frac={frac!r} is invalid; allowed: 0 < frac <= 1")
    if metric not in run.metrics:
        raise ValueError(
            f"{run.path}: no metric {metric!r}; available: {', '.join(run.metrics)}"
        )
    if run.n_interactions == 0:
        raise ValueError(f"{run.path}: no interactions logged yet")
    # Imported here: lili.runs pulls in the agents (JAX), which reading CSV files does not need.
    from lili.runs import final_mean

    values = run.metrics[metric]
    values = values[~np.isnan(values)]
    # The one definition of final performance, the one summary.json uses.
    return final_mean(values.tolist(), frac) if values.size else math.nan


def mean_se(values: Sequence[float]) -> tuple[float | None, float | None]:
    """Mean and standard error (std ddof=1 / sqrt n; 0 with one value); None, None if empty."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.size == 0:
        return None, None
    mean = float(arr.mean())
    se = float(arr.std(ddof=1) / math.sqrt(arr.size)) if arr.size > 1 else 0.0
    return mean, se


def group_runs(runs: Iterable[Run]) -> dict[str, dict[str, list[Run]]]:
    """env -> algo -> runs (with at least one interaction), envs and algos in display order."""
    groups: dict[str, dict[str, list[Run]]] = {}
    for run in runs:
        if run.n_interactions == 0:
            continue
        groups.setdefault(run.env, {}).setdefault(run.algo, []).append(run)
    return {
        env: {algo: sorted(by_algo[algo], key=lambda r: r.seed)
              for algo in sorted(by_algo, key=algo_sort_key)}
        for env, by_algo in sorted(groups.items(), key=lambda kv: env_sort_key(kv[0]))
    }


def summarize(runs: Iterable[Run], frac: float = 0.1) -> list[dict[str, Any]]:
    """One dict per (env, algo), envs sorted and algos in a fixed order.

    Keys: ``env``, ``algo``, ``n`` (seeds), ``seeds``, ``interactions_min`` /
    ``interactions_max`` (interactions logged), ``budget`` (largest configured budget or None),
    ``return_mean`` / ``return_se`` / ``returns`` (final return per seed, see
    :func:`final_performance`), ``success_mean`` / ``success_se`` / ``successes`` (None when the
    env defines no success), ``gap_closed`` = (R - R_sac) / (R_oracle - R_sac) on the mean final
    returns (None unless SAC and Oracle both ran on the env and differ), ``paper_return`` and
    ``paper_gap_closed`` (None when the paper gives no number) and ``paper_text`` (None or the
    paper's qualitative statement), ``wall_time_mean`` (seconds per run, None without a
    ``wall_time`` column), ``paper_success`` (None or the paper's success rate) and
    ``strategy_freq`` (see :func:`strategy_frequencies`; None without strategy ids),
    ``length_mean`` / ``length_se`` (final steps per interaction; None without a ``length``
    column), ``return_iqm`` / ``return_iqm_ci`` and ``success_iqm`` / ``success_iqm_ci``
    (:func:`iqm_ci`: the IQM over seeds and its bootstrap 95% interval ``[low, high]``, None
    where there is no value or a single seed).
    s.e. = std(ddof=1) / sqrt(n), 0 with one seed. Runs with no
    interaction logged yet are left out.
    """
    rows: list[dict[str, Any]] = []
    for env, by_algo in group_runs(runs).items():
        paper = paper_reference(env) or {}
        paper_returns = paper.get("return", {})
        env_rows = []
        for algo, group in by_algo.items():
            returns = [final_performance(r, "return", frac) for r in group]
            successes = [final_performance(r, "success", frac) for r in group if r.has_success]
            successes = [s for s in successes if not math.isnan(s)]
            r_mean, r_se = mean_se(returns)
            s_mean, s_se = mean_se(successes)
            budgets = [r.budget for r in group if r.budget is not None]
            walls = [float(r.metrics["wall_time"][-1]) for r in group
                     if r.has_metric("wall_time")]
            freq = strategy_frequencies(group)
            l_mean, l_se = mean_se([final_performance(r, "length", frac) for r in group
                                    if r.has_metric("length")])
            env_rows.append({
                "env": env,
                "algo": algo,
                "n": len(group),
                "seeds": [r.seed for r in group],
                "interactions_min": min(r.n_interactions for r in group),
                "interactions_max": max(r.n_interactions for r in group),
                "budget": max(budgets) if budgets else None,
                "return_mean": r_mean,
                "return_se": r_se,
                "returns": returns,
                "success_mean": s_mean,
                "success_se": s_se,
                "successes": successes if successes else None,
                "gap_closed": None,
                "paper_return": paper_returns.get(algo),
                "paper_gap_closed": gap_closed(paper_returns, algo),
                "paper_text": paper.get("success_text", {}).get(algo),
                "wall_time_mean": float(np.mean(walls)) if walls else None,
                "paper_success": paper.get("success", {}).get(algo),
                "strategy_freq": None if freq is None else freq.tolist(),
                "length_mean": l_mean,
                "length_se": l_se,
                **_iqm_fields("return", returns),
                **_iqm_fields("success", successes),
            })
        means = {row["algo"]: row["return_mean"] for row in env_rows}
        for row in env_rows:
            row["gap_closed"] = gap_closed(means, row["algo"])
        rows.extend(env_rows)
    return rows


def _iqm_fields(metric: str, values: Sequence[float]) -> dict[str, Any]:
    """``<metric>_iqm`` and ``<metric>_iqm_ci`` ([low, high] or None) of :func:`summarize`."""
    if not len(values) or any(math.isnan(v) for v in values):
        return {f"{metric}_iqm": None, f"{metric}_iqm_ci": None}
    point, low, high = iqm_ci(values)
    return {f"{metric}_iqm": point,
            f"{metric}_iqm_ci": None if low is None else [low, high]}


def gap_share(value: float | None, start: float | None, end: float | None) -> float | None:
    """The share of the gap from ``start`` to ``end`` that ``value`` closes:
    (value - start) / (end - start); None when any is None or the two ends tie."""
    if value is None or start is None or end is None or end == start:
        return None
    return float((value - start) / (end - start))


def gap_closed(returns: dict[str, float], algo: str) -> float | None:
    """(R_algo - R_SAC) / (R_Oracle - R_SAC), or None without both baselines or when they tie."""
    return gap_share(returns.get(algo), returns.get("sac"), returns.get("oracle"))


def held_share(run: Run, held: Sequence[int], frac: float = 0.1) -> float | None:
    """The share of the run's last ``frac`` of interactions (:func:`lili.runs.final_window`,
    the window of :func:`final_performance`) in which the partner's strategy id is one of
    ``held``: the influence suite's behavioural evidence of influence, with ``held`` the ids
    the scripted influencer holds the partner at (:data:`lili.envs.influence.HELD`). Counted
    over the interactions that logged an id; None when none in the window did."""
    from lili.runs import final_window  # as in final_performance: no JAX to read a CSV

    ids = run.metrics.get("strategy_id")
    if ids is None or run.n_interactions == 0:
        return None
    return held_fraction(ids[-final_window(run.n_interactions, frac):], held)


def held_fraction(ids: Sequence[float], held: Sequence[int]) -> float | None:
    """The share of strategy ids ``ids`` that are one of ``held``, counted over the ids that
    are logged (not NaN, not the -1 of an interaction without one); None when none is."""
    ids = np.asarray(ids, dtype=np.float64)
    ids = ids[~np.isnan(ids) & (ids >= 0)]
    return float(np.isin(ids, held).mean()) if ids.size else None


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """Trailing moving average; the window is shortened at the start; NaNs are skipped."""
    if window < 1:
        raise ValueError(f"window={window!r} is invalid; allowed: an integer >= 1")
    values = np.asarray(values, dtype=np.float64)
    valid = ~np.isnan(values)
    csum = np.concatenate([[0.0], np.cumsum(np.where(valid, values, 0.0))])
    ccount = np.concatenate([[0], np.cumsum(valid)])
    idx = np.arange(values.size)
    lo = np.maximum(0, idx - window + 1)
    total = csum[idx + 1] - csum[lo]
    count = ccount[idx + 1] - ccount[lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def strategy_frequencies(runs: Iterable[Run], last: int = STRATEGY_WINDOW) -> np.ndarray | None:
    """How often the partner played each discrete strategy over the last ``last`` interactions.

    Pools the runs given (e.g. the seeds of one algo); returns fractions indexed by
    ``strategy_id`` (length = largest id seen + 1), or None when no run logs an id >= 0.
    """
    counts: list[np.ndarray] = []
    for run in runs:
        ids = run.metrics.get("strategy_id")
        if ids is None:
            continue
        ids = ids[-last:]
        ids = ids[~np.isnan(ids) & (ids >= 0)].astype(int)
        if ids.size:
            counts.append(np.bincount(ids))
    if not counts:
        return None
    total = np.zeros(max(len(c) for c in counts))
    for c in counts:
        total[: len(c)] += c
    return total / total.sum()


def success_by_strategy(run: Run, window: int) -> np.ndarray:
    """Successes and interactions per (window, strategy): shape (windows, strategies, 2).

    Window k holds interactions ``k * window`` to ``(k + 1) * window - 1`` (the last may be
    shorter); strategies are indexed by ``strategy_id``. In air hockey this is blocks per
    striker mode over training: it shows a mode the blocker never learns to block even when
    that mode is fired at it.
    """
    if isinstance(window, bool) or not isinstance(window, int) or window < 1:
        raise ValueError(f"window={window!r} is invalid; allowed: an integer >= 1")
    ids, success = run.metrics.get("strategy_id"), run.metrics.get("success")
    if ids is None or success is None or not np.any(ids >= 0) \
            or np.all(np.isnan(success)):
        raise ValueError(f"{run.path}: no strategy_id and success columns to count; allowed: "
                         "a run of an env with discrete strategies and a success flag")
    n_windows = -(-run.n_interactions // window)
    out = np.zeros((n_windows, int(np.nanmax(ids)) + 1, 2))
    for k in range(n_windows):
        part = slice(k * window, (k + 1) * window)
        for sid, ok in zip(ids[part], success[part], strict=True):
            if sid >= 0 and not np.isnan(ok):
                out[k, int(sid)] += (ok, 1)
    return out


def strategy_names(env: str, n: int) -> list[str]:
    """Names of strategies 0..n-1: the env's own (its class's ``strategy_names``), else the
    paper's where known, else ``id k``."""
    names = _env_strategy_names(env) or (paper_reference(env) or {}).get("strategy_names", [])
    return [names[k] if k < len(names) else f"id {k}" for k in range(n)]


def _values(values: Sequence[float], name: str = "values") -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64).ravel()
    if arr.size == 0 or np.any(np.isnan(arr)):
        raise ValueError(f"{name}={list(values)!r} is invalid; allowed: one or more numbers, "
                         "no NaN")
    return arr


def _iqm(x: np.ndarray, axis: int = -1) -> np.ndarray:
    from scipy.stats import trim_mean

    return trim_mean(x, 0.25, axis=axis)


def iqm(values: Sequence[float]) -> float:
    """Interquartile mean: the mean of the middle half, ``scipy.stats.trim_mean(values, 0.25)``
    as rliable computes it (``floor(n / 4)`` values cut from each end, so with 3 seeds it is
    the mean and with 4-7 seeds the lowest and highest one are left out). Robust to one seed
    that diverged, unlike the mean, and less noisy than the median. ValueError when empty or
    NaN."""
    return float(_iqm(_values(values)))


def _bootstrap(samples: tuple[np.ndarray, ...], statistic, n_resamples: int,
               seed: int) -> tuple[float | None, float | None]:
    """Percentile bootstrap ``CONFIDENCE`` interval of ``statistic(*samples, axis)``, each sample
    resampled on its own (stratified by sample: seeds of one algo are never mixed with another's).
    (None, None) when a sample has a single value: one seed has no spread to resample."""
    if any(s.size < 2 for s in samples):
        return None, None
    from scipy.stats import bootstrap

    result = bootstrap(samples, statistic, n_resamples=n_resamples, vectorized=True,
                       method="percentile", confidence_level=CONFIDENCE,
                       rng=np.random.default_rng(seed))
    low, high = result.confidence_interval
    return float(low), float(high)


def iqm_ci(values: Sequence[float], n_resamples: int = BOOTSTRAP_RESAMPLES,
           seed: int = BOOTSTRAP_SEED) -> tuple[float, float | None, float | None]:
    """(IQM, low, high): :func:`iqm` and its bootstrap 95% confidence interval over the seeds
    (percentile method, ``n_resamples`` resamples from a generator seeded with ``seed``, so the
    same values always give the same interval). With few seeds (3-7) the interval is wide and
    coarse, as it should be; low = high = None with one seed."""
    arr = _values(values)
    low, high = _bootstrap((arr,), _iqm, n_resamples, seed)
    return float(_iqm(arr)), low, high


def _p_improvement(x: np.ndarray, y: np.ndarray, axis: int = -1) -> np.ndarray:
    x = np.moveaxis(x, axis, -1)[..., :, None]
    y = np.moveaxis(y, axis, -1)[..., None, :]
    return np.mean((x > y) + 0.5 * (x == y), axis=(-2, -1))


def probability_of_improvement(x: Sequence[float], y: Sequence[float]) -> float:
    """P(X > Y): over every pair of a seed of X and a seed of Y, the share where X's value is
    higher, ties counting 1/2 (the Mann-Whitney U statistic over n_x n_y; Agarwal et al. 2021).
    1.0 when every seed of X beats every seed of Y, 0.5 for identical sets, 0.0 reversed."""
    return float(_p_improvement(_values(x, "x"), _values(y, "y")))


def probability_of_improvement_ci(x: Sequence[float], y: Sequence[float],
                                  n_resamples: int = BOOTSTRAP_RESAMPLES,
                                  seed: int = BOOTSTRAP_SEED
                                  ) -> tuple[float, float | None, float | None]:
    """(P(X > Y), low, high): :func:`probability_of_improvement` and its stratified bootstrap
    95% interval (X's seeds and Y's seeds resampled separately; fixed ``seed``). None bounds
    when X or Y has one seed."""
    xa, ya = _values(x, "x"), _values(y, "y")
    low, high = _bootstrap((xa, ya), _p_improvement, n_resamples, seed)
    return float(_p_improvement(xa, ya)), low, high


def _env_strategy_names(env: str) -> tuple[str, ...]:
    """``strategy_names`` of the env's class (a registered id's entry point, or a
    ``module:Class`` spec); empty when it defines none or cannot be imported here (a report
    may be written where the env of a run is not installed)."""
    try:
        import gymnasium as gym
        from gymnasium.envs.registration import load_env_creator

        from lili.envs.spec import load_env_class

        factory = load_env_class(env)
        if isinstance(factory, functools.partial) and factory.func is gym.make:
            entry = gym.registry[factory.args[0]].entry_point
            factory = load_env_creator(entry) if isinstance(entry, str) else entry
        names = getattr(factory, "strategy_names", ())
    except Exception:  # noqa: BLE001 - any import failure means: no names from the env
        return ()
    if not isinstance(names, (tuple, list)):
        return ()
    return tuple(str(name) for name in names)
