"""Figures: learning curves with s.e. bands, the Point Mass target heatmap, strategy bars."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lili.report.files import Run
from lili.report.paper import paper_reference
from lili.report.stats import (
    STRATEGY_WINDOW,
    group_runs,
    iqm_ci,
    moving_average,
    strategy_frequencies,
    strategy_names,
)
from lili.report.style import DPI, algo_color, algo_label, algo_sort_key, env_key, env_title

if TYPE_CHECKING:  # matplotlib is imported lazily (_pyplot): reports that draw nothing skip it
    from matplotlib.figure import Figure

__all__ = ["plot_learning_curves", "plot_strategy_heatmap", "heatmap_figure",
           "plot_strategy_frequencies"]

# Point Mass geometry (lili.envs.point_mass), repeated here so that reporting needs no env import.
PM_CENTER = (0.0, -0.05)
PM_RADIUS = 0.1
PM_BOUND = 0.15


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _seed_band(group: list[Run], metric: str, window: int):
    """x, mean over seeds, s.e. over seeds and seed count per x of the smoothed metric."""
    xs = np.unique(np.concatenate([r.metrics["interaction"] for r in group]))
    table = np.full((len(group), xs.size), np.nan)
    for i, run in enumerate(group):
        cols = np.searchsorted(xs, run.metrics["interaction"])
        table[i, cols] = moving_average(run.metrics[metric], window)
    count = np.sum(~np.isnan(table), axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.nansum(table, axis=0) / np.maximum(count, 1)
        dev = np.where(np.isnan(table), 0.0, table - mean) ** 2
        sd = np.sqrt(dev.sum(axis=0) / np.maximum(count - 1, 1))
        se = np.where(count > 1, sd / np.sqrt(np.maximum(count, 1)), 0.0)
    mean = np.where(count > 0, mean, np.nan)
    return xs, mean, se, count


def _grid(n: int, max_cols: int = 3) -> tuple[int, int]:
    cols = min(n, max_cols)
    return math.ceil(n / cols), cols


def plot_learning_curves(
    runs: Iterable[Run], out_png: str | Path, metric: str = "return", window: int = 50
) -> Path:
    """Learning curves: one subplot per env, one line per algo (mean over seeds ± s.e.).

    Each seed's ``metric`` is smoothed by a trailing moving average over ``window``
    interactions before averaging over seeds. Envs where ``metric`` is empty for every run are
    skipped. The paper's numbers are dashed horizontal lines (return on Point Mass); where the
    paper gives only a description it is printed in the subplot. Raises ValueError when no run
    has the metric. Returns the path written.
    """
    groups = {
        env: {algo: [r for r in group if r.has_metric(metric)] for algo, group in by_algo.items()}
        for env, by_algo in group_runs(runs).items()
    }
    groups = {
        env: {algo: g for algo, g in by_algo.items() if g}
        for env, by_algo in groups.items()
        if any(by_algo.values())
    }
    if not groups:
        raise ValueError(f"no run with metric {metric!r} to plot")
    plt = _pyplot()
    from matplotlib.lines import Line2D

    nrows, ncols = _grid(len(groups))
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.6 * ncols, 4.0 * nrows), squeeze=False)
    ylabel = {"return": "return per interaction", "success": "success rate"}.get(metric, metric)
    for ax, (env, by_algo) in zip(axes.flat, groups.items(), strict=False):
        handles = []
        for algo, group in by_algo.items():
            xs, mean, se, _ = _seed_band(group, metric, window)
            color = algo_color(algo)
            n = len(group)
            label = f"{algo_label(algo)} ({n} seed{'s' * (n > 1)})"
            (line,) = ax.plot(xs, mean, color=color, lw=1.6, label=label)
            ax.fill_between(xs, mean - se, mean + se, color=color, alpha=0.2, lw=0)
            handles.append(line)
        ref = paper_reference(env) or {}
        if metric in ref and isinstance(ref[metric], dict):
            for algo, value in sorted(ref[metric].items(), key=lambda kv: algo_sort_key(kv[0])):
                ax.axhline(value, color=algo_color(algo), ls="--", lw=1.1, alpha=0.85)
                handles.append(Line2D([], [], color=algo_color(algo), ls="--", lw=1.1,
                                      label=f"paper {algo_label(algo)} ({value:g})"))
        title = env_title(env)
        if metric == "success" and "text" in ref:
            title += "\n" + textwrap.fill(f"paper: {ref['text']}", width=50)
        if metric == "success":
            ax.set_ylim(-0.03, 1.03)
        ax.set_title(title, fontsize=11)
        ax.set_xlabel("interaction")
        ax.set_ylabel(f"{ylabel} (moving avg. {window})")
        ax.grid(True, alpha=0.3)
        ax.legend(handles=handles, fontsize=8, loc="best", framealpha=0.85)
    for ax in list(axes.flat)[len(groups):]:
        ax.set_visible(False)
    fig.suptitle(f"Learning curves: {ylabel} (mean over seeds ± s.e.)", fontsize=12)
    fig.tight_layout()
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png


def plot_strategy_heatmap(runs: Iterable[Run], out_png: str | Path, last: int = 500) -> Path:
    """Where the Point Mass target ends up (see :func:`heatmap_figure`). Returns the path."""
    plt = _pyplot()
    fig = heatmap_figure(runs, last)
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png


def heatmap_figure(runs: Iterable[Run], last: int = 500) -> Figure:
    """Where the Point Mass target ends up: a 2-D histogram of (strategy_0, strategy_1).

    One panel per (Point Mass env, algo), pooling the last ``last`` interactions of every
    seed; colour = fraction of those interactions in the cell (square-root scale, shared by
    all panels). The circle the target moves on and the ego's start (0, 0) are drawn. Raises
    ValueError when no Point Mass run with strategy columns is given. Returns the matplotlib
    figure (the caller closes it).
    """
    if last < 1:
        raise ValueError(f"last={last!r} is invalid; allowed: an integer >= 1")
    panels: list[tuple[str, str, np.ndarray, int, int]] = []
    for env, by_algo in group_runs(runs).items():
        if "pointmass" not in env_key(env):
            continue
        for algo, group in by_algo.items():
            points, used = [], 0
            for run in group:
                strat = run.strategy
                if strat is None or strat.shape[1] < 2:
                    continue
                xy = strat[-last:, :2]
                used = max(used, len(xy))
                points.append(xy[~np.isnan(xy).any(axis=1)])
            if points:
                panels.append((env, algo, np.concatenate(points), len(points), used))
    if not panels:
        raise ValueError("no Point Mass run with strategy_0/strategy_1 columns to plot")
    plt = _pyplot()
    from matplotlib.colors import PowerNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle

    edges = np.linspace(-PM_BOUND, PM_BOUND, 41)
    hists = []
    for _, _, xy, _, _ in panels:
        h, _, _ = np.histogram2d(xy[:, 0], xy[:, 1], bins=[edges, edges])
        hists.append(h / max(len(xy), 1))
    vmax = max(float(h.max()) for h in hists) or 1.0
    norm = PowerNorm(gamma=0.5, vmin=0.0, vmax=vmax)
    cmap = plt.get_cmap("magma_r").with_extremes(bad="white")
    ncols = 2 if len(panels) == 4 else min(len(panels), 3)
    nrows = math.ceil(len(panels) / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.7 * ncols + 1.0, 3.9 * nrows + 0.5),
                             squeeze=False, layout="constrained")
    multi_env = len({env for env, *_ in panels}) > 1
    mesh = None
    for ax, (env, algo, _xy, n_seeds, used), h in zip(axes.flat, panels, hists, strict=False):
        mesh = ax.pcolormesh(edges, edges, np.ma.masked_equal(h.T, 0.0), cmap=cmap, norm=norm)
        ax.add_patch(Circle(PM_CENTER, PM_RADIUS, fill=False, ec="0.35", lw=1.0, ls="--"))
        ax.plot([0.0], [0.0], marker="*", ms=13, color="#1f9bde", mec="black", mew=0.6, ls="")
        ax.set_xlim(-PM_BOUND, PM_BOUND)
        ax.set_ylim(-PM_BOUND, PM_BOUND)
        ax.set_aspect("equal")
        title = f"{algo_label(algo)}\n{n_seeds} seed{'s' * (n_seeds > 1)}, last {used} interactions"
        if multi_env:
            title = f"{env}: {title}"
        ax.set_title(title, fontsize=10, color=algo_color(algo))
        ax.set_xlabel("target x")
        ax.set_ylabel("target y")
        ax.tick_params(labelsize=8)
        ax.grid(True, alpha=0.2)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    legend = [
        Line2D([], [], marker="*", ms=11, color="#1f9bde", mec="black", ls="", label="ego start"),
        Line2D([], [], color="0.35", ls="--", label="circle the target moves on"),
    ]
    fig.legend(handles=legend, loc="outside lower center", ncol=2, fontsize=9, frameon=False)
    # Wrapped to the figure's width: a single panel is narrower than the one-line title.
    width_in = fig.get_size_inches()[0]
    fig.suptitle(textwrap.fill("Point Mass: target position (partner's strategy) at the end of "
                               "training", width=int(width_in * 8.5)), fontsize=12)
    cbar = fig.colorbar(mesh, ax=axes.ravel().tolist(), shrink=0.8, pad=0.02)
    cbar.set_ticks(np.unique(np.round(np.linspace(0.0, 1.0, 6) ** 2 * vmax, 3)))
    cbar.set_label("fraction of interactions (sqrt scale)", fontsize=9)
    return fig


def plot_strategy_frequencies(runs: Iterable[Run], out_png: str | Path,
                              last: int = STRATEGY_WINDOW) -> Path:
    """Bars of how often the partner played each strategy at the end, per env and algo.

    Like the paper's air hockey figure (how often the striker fired left, middle, right over
    the final 200 interactions): one subplot per env with discrete strategy ids, one group of
    bars per strategy, one bar per algo (seeds pooled), with a whisker for the bootstrap 95%
    interval of the IQM of the per-seed shares (:func:`lili.report.stats.iqm_ci`; none with
    one seed). Raises ValueError when no run logs a strategy id. Returns the path written.
    """
    panels = []
    by_env = group_runs(runs)
    for env, by_algo in by_env.items():
        freqs = {algo: f for algo, group in by_algo.items()
                 if (f := strategy_frequencies(group, last)) is not None}
        if freqs:
            panels.append((env, freqs, {a: len(by_algo[a]) for a in freqs}))
    if not panels:
        raise ValueError("no run with a strategy_id column to plot")
    plt = _pyplot()
    nrows, ncols = _grid(len(panels))
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.6 * ncols, 3.8 * nrows), squeeze=False)
    for ax, (env, freqs, seeds) in zip(axes.flat, panels, strict=False):
        k = max(len(f) for f in freqs.values())
        width = 0.8 / len(freqs)
        for j, (algo, f) in enumerate(freqs.items()):
            f = np.pad(f, (0, k - len(f)))
            xs = np.arange(k) + (j - (len(freqs) - 1) / 2) * width
            n = seeds[algo]
            ax.bar(xs, f, width, color=algo_color(algo),
                   label=f"{algo_label(algo)} ({n} seed{'s' * (n > 1)})")
            per_seed = [p for r in by_env[env][algo]
                        if (p := strategy_frequencies([r], last)) is not None]
            for x, i in zip(xs, range(k), strict=True):
                _, low, high = iqm_ci([p[i] if i < len(p) else 0.0 for p in per_seed])
                if low is not None:
                    ax.plot([x, x], [low, high], color="0.15", lw=1.0)
        ax.axhline(1.0 / k, color="0.4", ls=":", lw=1.0, label="uniform")
        ax.set_xticks(np.arange(k), strategy_names(env, k))
        ax.set_ylim(0, 1)
        ax.set_ylabel(f"fraction of the last {last} interactions")
        ax.set_title(env_title(env), fontsize=11)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=8, framealpha=0.85)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle("Partner's strategy at the end of training", fontsize=12)
    fig.tight_layout()
    out_png = Path(out_png)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png
