"""Expand a preset into runs and find each run's state on disk (new, half-finished or done).

Nothing here writes: :func:`plan` checks every run folder that already exists against the run
it would become, so that a folder holding another config is one clear error before any process
starts.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml

from lili.agents.registry import config_for, reads, stored_config
from lili.config import AgentConfig
from lili.envs.core import resolve_env_id
from lili.errors import shown
from lili.experiments.presets import PRESETS, Preset
from lili.limits import MAX_INTERACTIONS, MAX_SEEDS, check_count
from lili.runs import run_dir_for
from lili.yaml_bounds import safe_load

__all__ = ["RunSpec", "plan", "run_status", "jax_reason", "BACKENDS", "QUICK_INTERACTIONS",
           "QUICK_CONFIG"]

BACKENDS = ("gym", "jax")
"""``--backend`` values: the Gymnasium envs (every run), or the JAX-native path
(:mod:`lili.jax_train`) for the runs whose env and algo it supports."""

QUICK_INTERACTIONS = 6
# Learning starts after 3 random interactions (LILAC's prior window needs 3) and a checkpoint
# every 2, so that --quick goes through every stage of a run (warm-up, updates, checkpoint,
# resume) in seconds.
QUICK_CONFIG = {"warmup_interactions": 3, "checkpoint_every": 2}


@dataclass(frozen=True, eq=False)
class RunSpec:
    """One ``lili train`` run: where it lives and everything its config.yaml will hold.

    Compared and hashed by identity: :func:`plan` makes one object per run folder.
    """

    preset: str
    folder: str
    experiment: Path
    env: str
    algo: str
    seed: int
    interactions: int
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    backend: str = "gym"  # "jax": trained by lili.jax_train (lili train --backend jax)

    @property
    def run_dir(self) -> Path:
        """The run folder (:func:`lili.runs.run_dir_for`)."""
        return run_dir_for(self.experiment, self.env, self.algo, self.seed)

    @property
    def agent(self) -> dict[str, Any]:
        """The resolved agent config, as ``lili train`` writes it into config.yaml."""
        return AgentConfig.from_dict(self.config).to_dict()

    @property
    def name(self) -> str:
        """Short display name: ``noise/sigma_0.2 lili seed 0``."""
        return f"{self.folder} {self.algo} seed {self.seed}"


def _expand_one(preset: Preset, out: Path, seeds: int, interactions: int | None,
                algos: tuple[str, ...] | None, envs: tuple[str, ...] | None,
                extra_config: dict[str, Any], extra_env: dict[str, Any]) -> list[RunSpec]:
    budget = interactions if interactions is not None else preset.interactions
    specs = []
    for seed in range(seeds):
        for group in preset.groups:
            if envs is not None and group.env not in envs:
                continue
            for algo in group.algos:
                if algos is not None and algo not in algos:
                    continue
                specs.append(RunSpec(preset=preset.name, folder=group.folder,
                                     experiment=out / group.folder,
                                     env=group.env, algo=algo, seed=seed, interactions=budget,
                                     env_kwargs={**group.env_kwargs, **extra_env},
                                     config={**config_for(algo, group.config),
                                             **config_for(algo, extra_config)}))
    return specs


def plan(preset: Preset, out: str | Path, seeds: int | None = None,
         interactions: int | None = None, algos: tuple[str, ...] | None = None,
         quick: bool = False, overrides: dict[str, Any] | None = None,
         envs: tuple[str, ...] | None = None,
         env_kwargs: dict[str, Any] | None = None,
         paper_settings: bool = False, backend: str = "gym") -> list[RunSpec]:
    """Every run of ``preset`` under ``out``, each once (presets share runs; see presets).
    ``paper_settings``: each part without its departures from the paper's setting
    (:meth:`Preset.paper_setting`).

    ``quick``: :data:`QUICK_INTERACTIONS` interactions, 1 seed and :data:`QUICK_CONFIG`, unless
    ``seeds`` / ``interactions`` are given. ``algos`` keeps only those algos, ``envs`` only
    those envs (registered ids or aliases, e.g. ``influence-drift``). ``overrides``:
    agent-config fields set, over the preset's own, in every run whose algo reads them
    (``lili reproduce --set``; an ablation, so give it its own ``--out``); ValueError when no
    algo of the plan reads one. ``env_kwargs``: env options set in every run,
    over the preset's own (``lili reproduce --env-kwarg``, e.g. the old air hockey game with
    ``aim_noise=0.02``); every env of the plan must take them (narrow it with ``envs``).
    ``backend``: ``"jax"`` gives the runs whose env (with its kwargs) and algo the JAX-native
    path supports (:func:`jax_reason`) ``backend="jax"``; the others stay ``"gym"``.
    Raises ValueError for a bad value, or when an existing run folder holds another config.
    """
    if backend not in BACKENDS:
        raise ValueError(f"--backend {shown(backend)} is invalid; allowed: {', '.join(BACKENDS)}")
    if seeds is not None:
        check_count(seeds, "--seeds", MAX_SEEDS)
    if interactions is not None:
        check_count(interactions, "--interactions", MAX_INTERACTIONS)
    if algos is not None:
        unknown = [a for a in algos if a not in preset.algos]
        if unknown:
            raise ValueError(f"--algos {' '.join(unknown)} is not in preset {preset.name!r}; "
                             f"allowed: {', '.join(preset.algos)}")
    parts = [PRESETS[n] for n in preset.includes] or [preset]
    if paper_settings:
        parts = [part.paper_setting() for part in parts]
    env_ids = None if envs is None else tuple(resolve_env_id(e) for e in envs)
    if env_ids is not None:
        offered = tuple(dict.fromkeys(e for part in parts for e in part.envs))
        # Name the value as given (an alias stays an alias in the message).
        unknown = [a for a, e in zip(envs, env_ids, strict=True) if e not in offered]
        if unknown:
            raise ValueError(f"--envs {' '.join(unknown)} is not in preset {preset.name!r}; "
                             f"allowed: {', '.join(offered)}")
    out = Path(out)
    if quick:
        seeds = 1 if seeds is None else seeds
        interactions = QUICK_INTERACTIONS if interactions is None else interactions
    specs: dict[Path, RunSpec] = {}
    for part in parts:
        n_seeds = seeds if seeds is not None else part.seeds
        for spec in _expand_one(part, out, n_seeds, interactions, algos, env_ids,
                                {**(QUICK_CONFIG if quick else {}), **(overrides or {})},
                                env_kwargs or {}):
            known = specs.get(spec.run_dir)
            if known is None:
                specs[spec.run_dir] = spec
            elif (known.env_kwargs, known.config, known.interactions) != (
                    spec.env_kwargs, spec.config, spec.interactions):
                raise ValueError(f"presets {known.preset!r} and {spec.preset!r} define the run "
                                 f"{spec.run_dir} differently")
    result = list(specs.values())
    _check_overrides(overrides or {}, tuple(dict.fromkeys(s.algo for s in result)))
    if env_kwargs:
        _check_env_kwargs(result, env_kwargs)
    from lili.agents import check_config  # here: it imports JAX, which --dry-run need not

    if backend == "jax":
        result = [replace(s, backend="jax") if jax_reason(s) is None else s for s in result]
    for spec in result:
        # Before anything runs: the overrides, and what each algo demands of them.
        check_config(spec.algo, AgentConfig.from_dict(spec.config))
        run_status(spec)
    return result


def jax_reason(spec: RunSpec) -> str | None:
    """None when ``spec``'s env (with its kwargs) and algo train on the JAX-native path, else
    why not (one phrase)."""
    from lili.jax_train import why_not_jax

    return why_not_jax(spec.algo, spec.env, spec.env_kwargs)


def _check_overrides(overrides: dict[str, Any], algos: tuple[str, ...]) -> None:
    """ValueError naming the field unless some algo of the plan reads each ``--set`` field
    (and each ``extra`` entry is one of the plan's algos): a field no run takes would be
    ignored."""
    if not algos:
        return
    for name, value in overrides.items():
        if name == "extra" and isinstance(value, dict):
            for key in value:
                if key not in algos:
                    raise ValueError(f"--set extra.{key} is read by no algo of this plan "
                                     f"({', '.join(algos)}); allowed: extra.<one of them>")
        elif not any(name in reads(a) for a in algos):
            allowed = sorted(set().union(*(reads(a) for a in algos)))
            raise ValueError(f"--set {name}={value!r} is read by no algo of this plan "
                             f"({', '.join(algos)}); allowed: {', '.join(allowed)}")


def _check_env_kwargs(specs: list[RunSpec], given: dict[str, Any]) -> None:
    """ValueError naming the env and the bad ``--env-kwarg`` unless every env of the plan takes
    the given options: checked by name, then by building the env once with the kwargs its
    runs will get, so that a bad value fails here and not in every run."""
    from lili.envs.spec import check_env_kwargs, load_env_class

    for env_id, kwargs in {s.env: s.env_kwargs for s in specs}.items():
        factory = load_env_class(env_id)
        try:
            check_env_kwargs(factory, given, env_id)
            factory(**kwargs).close()
        except (TypeError, ValueError) as e:
            items = " ".join(f"{k}={v}" for k, v in given.items())
            raise ValueError(f"--env-kwarg {items} does not fit {env_id} (every env of the "
                             f"plan must take it; choose them with --envs): {e}") from None


def run_status(spec: RunSpec) -> str:
    """``"done"`` (summary.json at the budget), ``"resume"`` (a started run) or ``"new"``.

    Raises ValueError naming the folder and the difference when the folder holds a run of
    another env, env kwargs, algo, seed or agent config.
    """
    folder = spec.run_dir
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder} is a file; allowed: a run folder or nothing")
    cfg_path = folder / "config.yaml"
    if not (folder / "metrics.csv").exists():
        return "new"
    try:
        old = safe_load(cfg_path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        raise ValueError(f"{cfg_path} is missing or unreadable; the folder holds a run that "
                         "reproduce cannot check: move it away or choose another --out") from None
    want = {"env": spec.env, "env_kwargs": spec.env_kwargs, "algo": spec.algo,
            "seed": spec.seed, "agent": spec.agent}
    for key, value in want.items():
        have = old.get(key) if isinstance(old, dict) else None
        if key == "agent":
            have = stored_config(spec.algo, have)
        if have != value:
            detail = (_diff(have, value) if key == "agent"
                      else f"{shown(have)} there, {shown(value)} here")
            raise ValueError(f"{folder} holds a run of another config ({key}: {detail}); "
                             "allowed: an --out whose runs match the preset (choose another "
                             "--out or move the folder away)")
    summary = folder / "summary.json"
    if summary.is_file():
        try:
            done = int(json.loads(summary.read_text())["interactions"])
        except (ValueError, KeyError, TypeError):
            raise ValueError(f"{summary} is unreadable; allowed: JSON with 'interactions' as "
                             "`lili train` writes it") from None
        if done >= spec.interactions:
            return "done"  # a finished run counts, whichever path trained it
    have = old.get("backend", "gym") if isinstance(old, dict) else "gym"
    if have != spec.backend:
        raise ValueError(f"{folder} holds a run started with --backend {shown(have)}, which "
                         "resumes only on that backend (its env's random draws differ); "
                         f"allowed: --backend {shown(have)} for this --out, or another --out")
    return "resume"


def _diff(have: Any, want: dict[str, Any]) -> str:
    if not isinstance(have, dict):
        return f"{shown(have)} there"
    keys = sorted(k for k in set(have) | set(want) if have.get(k) != want.get(k))
    return ", ".join(f"{k}={have.get(k)!r} there, {want.get(k)!r} here" for k in keys)
