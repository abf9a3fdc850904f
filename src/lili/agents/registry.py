"""The one ordered registry of algos: their names, the modules that define them, their option
checks, and :func:`make_agent` / :func:`load_agent` (with the agent file's reader).

:data:`TABLE` is the one list of algos, in the order every table, figure and ``--help`` lists
them; the command line, the presets (:data:`PAPER_ALGOS`) and the report read it from here.
Reading it imports no agent (and no JAX): each algo names the module that defines and
:func:`register`-s its class, imported on first use, so ``lili.contrib`` can sit above the core
it subclasses while its algos are made and loaded like the others.
"""

from __future__ import annotations

import importlib
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lili.config import AgentConfig

__all__ = ["Algo", "TABLE", "ALGOS", "PAPER_ALGOS", "CONTRIB_ALGOS", "CORE_ALGOS",
           "AGENTS", "OPTIONS",
           "AGENT_FORMAT", "register", "register_options", "check_extra", "check_config",
           "make_agent", "load_agent", "read_agent_file"]


@dataclass(frozen=True)
class Algo:
    """One algo: its name (``--algo``), the module that registers it, and whether it is one of
    the paper's Fig. 4-6 algos (what the paper presets run)."""

    name: str
    module: str
    paper: bool = False


TABLE: tuple[Algo, ...] = (
    Algo("random", "lili.agents.random_policy"),
    Algo("sac", "lili.agents.sac", paper=True),
    Algo("slac", "lili.agents.slac", paper=True),
    Algo("lili-no-influence", "lili.agents.lili", paper=True),
    Algo("lili", "lili.agents.lili", paper=True),
    Algo("lilac", "lili.agents.lilac", paper=True),
    Algo("oracle-last", "lili.agents.oracle"),
    Algo("oracle", "lili.agents.oracle", paper=True),
    # Variants of LILI that measured no gain (lili.contrib, README "Contrib variants").
    Algo("lili-categorical", "lili.contrib.latents"),
    Algo("lili-quantised", "lili.contrib.latents"),
    Algo("lili-bottleneck", "lili.contrib.latents"),
    Algo("lili-posterior", "lili.contrib.latents"),
    Algo("lili-prediction-critic", "lili.contrib.latents"),
)
"""Every algo, in display order."""

ALGOS: tuple[str, ...] = tuple(a.name for a in TABLE)
"""Every algo name (``lili train --algo``), in the order reports list them."""
PAPER_ALGOS: tuple[str, ...] = tuple(a.name for a in TABLE if a.paper)
"""The paper's algos (the env presets run these)."""
CONTRIB_ALGOS: tuple[str, ...] = tuple(a.name for a in TABLE if a.module.startswith("lili.contrib"))
"""The algos of :mod:`lili.contrib`."""
CORE_ALGOS: tuple[str, ...] = tuple(a for a in ALGOS if a not in CONTRIB_ALGOS)
"""The algos of :mod:`lili.agents` (the contract tests run every one of them)."""

AGENT_FORMAT = "lili-agent-2"
"""Version tag of saved agent files (2: the typed ``AgentState``)."""

AGENTS: dict[str, tuple[type, dict[str, Any]]] = {}
"""Every algo name -> (facade class, its extra constructor arguments); see :func:`register`."""

OPTIONS: dict[str, Callable[[AgentConfig], Any]] = {}
"""Agents with options of their own (``AgentConfig.extra[name]``) -> the function that checks
them; see :func:`register_options`."""


def _load_all() -> None:
    """Import every module of :data:`TABLE` (each registers its algos) once."""
    if len(AGENTS) < len(TABLE):
        for module in dict.fromkeys(a.module for a in TABLE):
            importlib.import_module(module)
        assert set(AGENTS) == set(ALGOS), "every algo's module registers it"


def register(algo: str, cls: type, **kwargs: Any) -> None:
    """Make ``algo`` (a name of :data:`TABLE`) known to :func:`make_agent` and
    :func:`load_agent`; each agent module registers its own names."""
    if algo not in ALGOS:
        raise ValueError(f"algo {algo!r} is not in lili.agents.registry.TABLE")
    AGENTS[algo] = (cls, kwargs)


def register_options(name: str, check: Callable[[AgentConfig], Any]) -> None:
    """Make ``extra[name]`` known to :func:`check_extra` (``check(config)`` raises ValueError)."""
    OPTIONS[name] = check


def check_extra(config: AgentConfig) -> None:
    """ValueError unless every entry of ``config.extra`` is an agent with options and its
    options are valid, whichever algo the config is for: an entry no agent reads (``extra:
    {slac: {bogus: 1}}`` with ``--algo lili``) would otherwise be ignored silently."""
    _load_all()
    for key in config.extra:
        if key not in OPTIONS:
            raise ValueError(f"config extra.{key} is invalid: {key!r} is not an agent with "
                             f"options; allowed: {', '.join(sorted(OPTIONS))}")
        for name, value in config.extra[key].items():
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(f"config extra.{key}.{name}={value!r} is invalid; allowed: a "
                                 "finite number")
        OPTIONS[key](config)


def check_config(algo: str, config: AgentConfig) -> None:
    """ValueError unless ``config`` is valid for ``algo``: :func:`check_extra`, plus the
    algo's own constraints (LILAC's warm-up must cover its prior window), which otherwise
    only show when the agent is built, i.e. after a sweep has started."""
    check_extra(config)
    if algo in OPTIONS:
        OPTIONS[algo](config)


def make_agent(algo: str, env: Any, config: AgentConfig | dict | None = None,
               seed: int = 0) -> Any:
    """Construct the agent named ``algo`` (one of :data:`ALGOS`) for ``env`` (a
    ``gymnasium.Env`` or a registered id)."""
    if algo not in ALGOS:
        raise ValueError(f"unknown algo {algo!r}; allowed: {', '.join(ALGOS)}")
    _load_all()
    cls, kwargs = AGENTS[algo]
    return cls(env, config, seed, **kwargs)


def load_agent(path: str | Path, env: Any) -> Any:
    """Load any saved agent; its class comes from the file."""
    from lili.agents.base import CheckpointError

    meta, state = read_agent_file(path)
    if meta.get("algo") not in ALGOS:
        raise CheckpointError(f"{path} holds an unknown algo {meta.get('algo')!r}")
    try:
        config = AgentConfig.from_dict(meta["config"])
        agent = make_agent(meta["algo"], env, config, meta["seed"])
    except (KeyError, TypeError) as e:
        raise CheckpointError(f"{path} holds an agent this lili cannot build: {e}") from None
    agent.check_meta(meta, str(path))
    agent.load_state_bytes(state, str(path))
    agent.trained_interactions = int(meta.get("num_interactions", 0))
    return agent


def read_agent_file(path: str | Path) -> tuple[dict[str, Any], bytes]:
    """Read the (meta, state bytes) of a saved agent; CheckpointError if unreadable."""
    import flax.serialization

    from lili.agents.base import CheckpointError

    p = Path(path)
    if not p.is_file():
        raise CheckpointError(f"agent file {str(p)!r} does not exist")
    try:
        raw = flax.serialization.msgpack_restore(p.read_bytes())
        meta = json.loads(raw["meta"])
        state = raw["state"]
        ok = isinstance(state, bytes) and isinstance(meta, dict)
    except Exception:
        ok = False
    if not ok:
        raise CheckpointError(f"{str(p)!r} is corrupt or not a lili agent file") from None
    if meta.get("format") != AGENT_FORMAT:
        raise CheckpointError(f"{str(p)!r} has format {meta.get('format')!r}; this lili reads "
                              f"{AGENT_FORMAT!r} (retrain, or use the lili version that wrote it)")
    return meta, state
