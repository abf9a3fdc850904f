"""The one ordered registry of algos: their names, the modules that define them, the config
each takes, and :func:`make_agent` / :func:`load_agent` (with the agent file's reader).

:data:`TABLE` is the one list of algos, in the order every table, figure and ``--help`` lists
them; the command line, the presets (:data:`PAPER_ALGOS`) and the report read it from here.
Reading it imports no agent (and no JAX): each algo names the module that defines and
:func:`register`-s its class, imported on first use, so ``lili.contrib`` can sit above the core
it subclasses while its algos are made and loaded like the others.

What an algo takes is checked in one way for every algo (:func:`check_config`): the shared
:class:`~lili.config.AgentConfig` fields it ``reads`` (any other field must keep its default),
and its own options in ``extra[<algo>]``, a frozen dataclass given to :func:`register` (no other
``extra`` entry). :func:`config_for` keeps of a config meant for several algos (a preset's
``--set``) what one algo reads; :func:`stored_config` reads a run folder's config for its algo.
"""

from __future__ import annotations

import importlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lili.config import (
    LATENT_FIELDS,
    LOOP_FIELDS,
    SAC_FIELDS,
    AgentConfig,
    dataclass_options,
    stored_agent_config,
)

__all__ = ["Algo", "TABLE", "ALGOS", "PAPER_ALGOS", "CONTRIB_ALGOS", "CORE_ALGOS",
           "LILI_VARIANTS", "AGENTS", "OPTIONS", "AGENT_FORMAT", "register", "register_options",
           "check_extra",
           "check_config", "agent_options", "reads", "config_for", "stored_config",
           "make_agent", "load_agent", "read_agent_file"]


@dataclass(frozen=True)
class Algo:
    """One algo: its name (``--algo``), the module that registers it, the
    :class:`~lili.config.AgentConfig` fields it reads (``extra`` aside: an algo reads
    ``extra[<its name>]`` when it has options), whether it is one of the paper's Fig. 4-6
    algos (what the paper presets run), and for a variant of :mod:`lili.contrib` the core
    algo it subclasses."""

    name: str
    module: str
    reads: frozenset[str]
    paper: bool = False
    variant_of: str = ""

    def __post_init__(self) -> None:
        # "Is contrib" has one source, variant_of; the module must agree with it.
        if bool(self.variant_of) != self.module.startswith("lili.contrib."):
            raise ValueError(f"algo {self.name!r}: module {self.module!r} with variant_of="
                             f"{self.variant_of!r}; allowed: a lili.contrib module with the core "
                             "algo it subclasses as variant_of, or a core module without one")


TABLE: tuple[Algo, ...] = (
    Algo("random", "lili.agents.random_policy", LOOP_FIELDS),
    Algo("sac", "lili.agents.sac", SAC_FIELDS, paper=True),
    Algo("slac", "lili.agents.slac", SAC_FIELDS, paper=True),
    Algo("lili-no-influence", "lili.agents.lili", LATENT_FIELDS, paper=True),
    Algo("lili", "lili.agents.lili", LATENT_FIELDS, paper=True),
    # LILAC's window is its option prior_window, not LILI's encoder window.
    Algo("lilac", "lili.agents.lilac", LATENT_FIELDS - {"history"}, paper=True),
    Algo("oracle-last", "lili.agents.oracle", SAC_FIELDS),
    Algo("oracle", "lili.agents.oracle", SAC_FIELDS, paper=True),
    # Variants of LILI kept out of the core (lili.contrib, README "Contrib variants"); these
    # five measured no gain on Drift.
    Algo("lili-categorical", "lili.contrib.latents", LATENT_FIELDS, variant_of="lili"),
    Algo("lili-quantised", "lili.contrib.latents", LATENT_FIELDS, variant_of="lili"),
    Algo("lili-bottleneck", "lili.contrib.latents", LATENT_FIELDS, variant_of="lili"),
    Algo("lili-posterior", "lili.contrib.latents", LATENT_FIELDS, variant_of="lili"),
    # Its critic reads z's predictions, detached: no critic gradient reaches the encoder.
    Algo("lili-prediction-critic", "lili.contrib.latents", LATENT_FIELDS - {"critic_to_encoder"},
         variant_of="lili"),
    # A variant not yet measured (issue 36's candidate fix for critic divergence).
    Algo("lili-critic-ln", "lili.contrib.critics", LATENT_FIELDS, variant_of="lili"),
    # Tried on Flee (issue 36): an MLP after E's pooling.
    Algo("lili-set-encoder", "lili.contrib.latents", LATENT_FIELDS, variant_of="lili"),
    # The history table's N = 11 (issue 34): one MLP over every step of the N interactions; it
    # reads all steps, so not encoder_transitions.
    Algo("lili-flat-encoder", "lili.contrib.latents", LATENT_FIELDS - {"encoder_transitions"},
         variant_of="lili"),
    # ... with lili-critic-ln's critic: is a normalised critic what stops its divergence?
    Algo("lili-flat-encoder-critic-ln", "lili.contrib.critics",
         LATENT_FIELDS - {"encoder_transitions"}, variant_of="lili"),
    # Lunar Lander's SLAC hovers (issue 34): its critic reads the observation beside the latent.
    Algo("slac-obs-critic", "lili.contrib.slac", SAC_FIELDS, variant_of="slac"),
    # ... and its actor reads one frame while the model keeps SLAC's K.
    Algo("slac-frame-actor", "lili.contrib.slac", SAC_FIELDS, variant_of="slac"),
    # ... and its critic reads the filter's means / the current frame with no latent.
    Algo("slac-mean-critic", "lili.contrib.slac", SAC_FIELDS, variant_of="slac"),
    Algo("slac-frame-critic", "lili.contrib.slac", SAC_FIELDS, variant_of="slac"),
)
"""Every algo, in display order."""

_BY_NAME: dict[str, Algo] = {a.name: a for a in TABLE}

ALGOS: tuple[str, ...] = tuple(a.name for a in TABLE)
"""Every algo name (``lili train --algo``), in the order reports list them."""
PAPER_ALGOS: tuple[str, ...] = tuple(a.name for a in TABLE if a.paper)
"""The paper's algos (the env presets run these)."""
CONTRIB_ALGOS: tuple[str, ...] = tuple(a.name for a in TABLE if a.variant_of)
"""The algos of :mod:`lili.contrib`."""
LILI_VARIANTS: tuple[str, ...] = tuple(a.name for a in TABLE if a.variant_of == "lili")
"""The variants of LILI in :mod:`lili.contrib` (what the ``contrib`` preset runs beside LILI)."""
CORE_ALGOS: tuple[str, ...] = tuple(a for a in ALGOS if a not in CONTRIB_ALGOS)
"""The algos of :mod:`lili.agents` (the contract tests run every one of them)."""

AGENT_FORMAT = "lili-agent-2"
"""Version tag of saved agent files (2: the typed ``AgentState``)."""

AGENTS: dict[str, tuple[type, dict[str, Any]]] = {}
"""Every algo name -> (facade class, its extra constructor arguments); see :func:`register`."""

OPTIONS: dict[str, type] = {}
"""Algos with options of their own (``AgentConfig.extra[<algo>]``) -> their frozen dataclass;
see :func:`register`."""


def _load_all() -> None:
    """Import every module of :data:`TABLE` (each registers its algos) once."""
    if len(AGENTS) < len(TABLE):
        for module in dict.fromkeys(a.module for a in TABLE):
            importlib.import_module(module)
        assert set(AGENTS) == set(ALGOS), "every algo's module registers it"


def _algo(algo: str) -> Algo:
    if algo not in _BY_NAME:
        raise ValueError(f"unknown algo {algo!r}; allowed: {', '.join(ALGOS)}")
    return _BY_NAME[algo]


def register(algo: str, cls: type, options: type | None = None, **kwargs: Any) -> None:
    """Make ``algo`` (a name of :data:`TABLE`) known to :func:`make_agent` and
    :func:`load_agent`; each agent module registers its own names. ``options``: the frozen
    dataclass of the algo's own options (``extra[algo]``), whose ``__post_init__`` checks their
    values and whose ``check(config)``, if it has one, what they demand of the shared fields."""
    if algo not in ALGOS:
        raise ValueError(f"algo {algo!r} is not in lili.agents.registry.TABLE")
    AGENTS[algo] = (cls, kwargs)
    if options is not None:
        OPTIONS[algo] = options


def register_options(name: str, options: type) -> None:
    """Make ``options`` the options dataclass of the algo ``name`` (as :func:`register`'s
    ``options``)."""
    _algo(name)
    OPTIONS[name] = options


def reads(algo: str) -> frozenset[str]:
    """The :class:`AgentConfig` fields ``algo`` reads (``extra`` aside); ValueError for an
    unknown algo. Imports no agent."""
    return _algo(algo).reads


def agent_options(algo: str, config: AgentConfig) -> Any:
    """``algo``'s own options from ``config.extra[algo]`` as its dataclass, checked (also
    against the shared fields), or None for an algo without options."""
    _load_all()
    cls = OPTIONS.get(_algo(algo).name)
    if cls is None:
        return None
    raw = config.extra.get(algo, {})
    for name, value in raw.items() if isinstance(raw, dict) else ():
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"config extra.{algo}.{name}={value!r} is invalid; allowed: a "
                             "finite number")
    options = dataclass_options(config, algo, cls)
    check = getattr(options, "check", None)
    if check is not None:
        check(config)
    return options


def _reads_text(algo: str) -> str:
    _load_all()
    own = f" and extra.{algo}" if algo in OPTIONS else " (and no extra options)"
    return f"{algo} reads {', '.join(sorted(reads(algo)))}{own}"


def check_config(algo: str, config: AgentConfig) -> None:
    """ValueError, one line, unless ``config`` is a config of ``algo``: every field that
    ``algo`` does not read at its default (one set to another value would be ignored), no
    ``extra`` entry but ``extra[algo]``, and ``algo``'s options valid (:func:`agent_options`),
    which otherwise only show when the agent is built, i.e. after a sweep has started."""
    _algo(algo)
    _load_all()
    given = config.to_dict()
    for name, default in AgentConfig().to_dict().items():
        if name != "extra" and name not in reads(algo) and given[name] != default:
            raise ValueError(f"config {name}={given[name]!r} is not read by {algo} (it would "
                             f"be ignored); allowed: {_reads_text(algo)}")
    for key in config.extra:
        if key != algo or algo not in OPTIONS:
            why = f"{algo} has no options" if key == algo else f"it is not read by {algo}"
            raise ValueError(f"config extra.{key} is invalid: {why} (it would be ignored); "
                             f"allowed: {_reads_text(algo)}")
    agent_options(algo, config)


def check_extra(config: AgentConfig) -> None:
    """ValueError unless every entry of ``config.extra`` is the options of an algo that has
    them, valid for it (:func:`agent_options`); :func:`check_config` checks a config for one
    algo."""
    _load_all()
    for key in config.extra:
        if key not in OPTIONS:
            raise ValueError(f"config extra.{key} is invalid: {key!r} is not an algo with "
                             f"options; allowed: {', '.join(a for a in ALGOS if a in OPTIONS)}")
        agent_options(key, config)


def config_for(algo: str, config: Any) -> Any:
    """The part of ``config`` that ``algo`` reads: its fields and ``extra[algo]``, of a config
    meant for several algos (``lili reproduce --set``, one sweep over algos). ``config``: a
    mapping of :class:`AgentConfig` fields (a mapping is returned) or an :class:`AgentConfig`
    (one is returned, the fields ``algo`` does not read at their defaults). Imports no
    agent."""
    if isinstance(config, AgentConfig):
        return AgentConfig.from_dict(config_for(algo, config.to_dict()))
    out = {k: v for k, v in config.items() if k in reads(algo)}
    extra = config.get("extra")
    if isinstance(extra, dict) and algo in extra:
        out["extra"] = {algo: extra[algo]}
    return out


def stored_config(algo: str, stored: Any) -> Any:
    """A run folder's or agent file's stored config (a full :class:`AgentConfig` dump) as a
    config of ``algo``: :func:`lili.config.stored_agent_config`, and the fields ``algo`` does
    not read back at their defaults (runs of earlier releases, which accepted any field for
    any algo, ran with them ignored), ``extra`` kept to ``extra[algo]``. Returned as
    ``stored_agent_config`` gives it when it is no valid config or ``algo`` is unknown."""
    stored = stored_agent_config(stored)
    if not isinstance(stored, dict) or algo not in _BY_NAME:
        return stored
    try:
        full = AgentConfig.from_dict(stored).to_dict()
    except (ValueError, TypeError):
        return stored
    defaults = AgentConfig().to_dict()
    own = {k: (v if k in reads(algo) else defaults[k]) for k, v in full.items()}
    extra = full["extra"]
    own["extra"] = {algo: extra[algo]} if isinstance(extra, dict) and algo in extra else {}
    return own


def make_agent(algo: str, env: Any, config: AgentConfig | dict | None = None,
               seed: int = 0) -> Any:
    """Construct the agent named ``algo`` (one of :data:`ALGOS`) for ``env`` (a
    ``gymnasium.Env`` or a registered id)."""
    _algo(algo)
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
        config = AgentConfig.from_dict(stored_config(meta["algo"], meta["config"]))
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
