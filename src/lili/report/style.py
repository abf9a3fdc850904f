"""Names, colours and display order of envs and algos, the same in every table and figure."""

from __future__ import annotations

import re
import zlib

from lili.agents.registry import ALGOS

__all__ = ["ALGO_ORDER", "ALGO_LABELS", "ALGO_COLORS", "DPI", "algo_label", "algo_color",
           "algo_sort_key", "env_key", "env_title", "env_sort_key"]

ALGO_ORDER = ALGOS  # the registry's order (lili.agents.registry.TABLE)
ALGO_LABELS = {
    "random": "Random",
    "sac": "SAC",
    "slac": "SLAC",
    "lili-no-influence": "LILI (no influence)",
    "lili": "LILI",
    "lilac": "LILAC",
    "oracle-last": "Oracle (last interaction)",
    "oracle": "Oracle",
    "lili-categorical": "LILI (categorical)",
    "lili-quantised": "LILI (quantised)",
    "lili-bottleneck": "LILI (bottleneck)",
    "lili-posterior": "LILI (posterior target)",
    "lili-prediction-critic": "LILI (prediction critic)",
    "lili-set-encoder": "LILI (set encoder)",
    "lili-critic-ln": "LILI (critic LayerNorm)",
    "slac-obs-critic": "SLAC (critic reads the observation)",
    "slac-frame-actor": "SLAC (actor reads one frame)",
    "slac-mean-critic": "SLAC (critic reads the filter's means)",
    "slac-frame-critic": "SLAC (critic reads one frame)",
}
ALGO_COLORS = {
    "random": "#7f7f7f",
    "sac": "#1f77b4",
    "slac": "#9467bd",
    "lili-no-influence": "#ff7f0e",
    "lili": "#d62728",
    "lilac": "#8c564b",
    "oracle-last": "#98df8a",
    "oracle": "#2ca02c",
}
_EXTRA_COLORS = ("#e377c2", "#bcbd22", "#17becf", "#7f7f7f", "#000000", "#aec7e8")
_ENV_TITLES = {"pointmass": "Point Mass", "driving2d": "Driving (2D)",
               "lunarlander": "Lunar Lander", "drivingsteer": "Driving (steering)",
               "airhockey": "Air hockey"}
_ENV_ORDER = ("pointmass", "lunarlander", "driving2d", "drivingsteer", "airhockey")
DPI = 120


def env_key(env: str) -> str:
    """Normalise ``lili/PointMass-v0`` / ``point-mass`` / ``PointMass`` to ``pointmass``."""
    name = env.rsplit("/", 1)[-1]
    name = re.sub(r"-v\d+$", "", name)
    return re.sub(r"[^0-9a-z]", "", name.lower())


def algo_sort_key(algo: str) -> tuple[int, str]:
    """Display order: :data:`ALGO_ORDER`, then unknown algos alphabetically."""
    return (ALGO_ORDER.index(algo) if algo in ALGO_ORDER else len(ALGO_ORDER), algo)


def algo_label(algo: str) -> str:
    """Display name of an algo (``lili-no-influence`` -> ``LILI (no influence)``)."""
    return ALGO_LABELS.get(algo, algo)


def algo_color(algo: str) -> str:
    """A fixed colour per algo, the same in every figure."""
    if algo in ALGO_COLORS:
        return ALGO_COLORS[algo]
    return _EXTRA_COLORS[zlib.crc32(algo.encode()) % len(_EXTRA_COLORS)]


def env_sort_key(env: str) -> tuple[int, str]:
    """Display order of envs: the paper's, then unknown envs alphabetically."""
    key = env_key(env)
    return (_ENV_ORDER.index(key) if key in _ENV_ORDER else len(_ENV_ORDER), env)


def env_title(env: str) -> str:
    """``Point Mass (lili/PointMass-v0)`` for the paper's envs, the id itself otherwise."""
    pretty = _ENV_TITLES.get(env_key(env))
    return f"{pretty} ({env})" if pretty else env
