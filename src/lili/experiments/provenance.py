"""Where a results page's numbers come from, in words: what a run changed from its preset's
setting, the ``lili reproduce`` commands that retrain the runs, and the list of committed
record folders (the sources file's entries) behind a section. Shared by the page's sections
(:mod:`lili.experiments.page`, :mod:`lili.experiments.influence_page`)."""

from __future__ import annotations

from collections.abc import Sequence

from lili.agents.registry import config_for
from lili.config import AgentConfig, stored_agent_config
from lili.experiments.claims import Evidence, Locate
from lili.experiments.presets import PRESETS, Group, Preset
from lili.report.files import Run
from lili.report.style import algo_label

__all__ = ["departures", "setting", "reproduce_commands", "interactions_text", "sources_markdown"]


def departures(run: Run, group: Group, part: Preset) -> list[str]:
    """What a run changed from its preset's setting, as ``lili reproduce`` flags would set it:
    ``interactions=N``, agent fields (``--set``) and env options (``--env-kwarg``)."""
    out = []
    if run.budget is not None and run.budget != part.interactions:
        out.append(f"interactions={run.budget}")
    stored = stored_agent_config(run.config.get("agent"))
    if isinstance(stored, dict):
        want = AgentConfig.from_dict(config_for(run.algo, group.config)).to_dict()
        out += [f"{k}={stored[k]}" for k in want if k in stored and stored[k] != want[k]
                and k != "checkpoint_every"]  # when checkpoints are written changes no number
    kwargs = run.config.get("env_kwargs") or {}
    out += [f"env {k}={v}" for k, v in sorted(kwargs.items()) if group.env_kwargs.get(k) != v]
    return out


def setting(runs: Sequence[Run], group: Group, part: Preset) -> str:
    """The departures of ``runs`` (each once, in order) as code spans; "the preset's" when none."""
    found = dict.fromkeys(d for r in runs for d in departures(r, group, part))
    return ", ".join(f"`{d}`" for d in found) or "the preset's"


def _seeds(runs: Sequence[Run]) -> int:
    return max(r.seed for r in runs) + 1


def _owner(folder: str, algo: str) -> Preset:
    """The first preset (in PRESETS order) that runs ``algo`` in ``folder``."""
    return next(p for p in PRESETS.values() if not p.includes
                and any(g.folder == folder and algo in g.algos for g in p.groups))


def reproduce_commands(part: Preset, evidence: Evidence) -> list[str]:
    """``lili reproduce`` commands that retrain the runs behind ``part``'s evidence: one per
    (preset, setting, seeds), the setting read from the runs' config.yaml."""
    commands: dict[tuple, list[str]] = {}
    for group in part.groups:
        for algo in group.algos:
            runs = evidence.get((group.folder, algo), [])
            if not runs:
                continue
            owner = _owner(group.folder, algo)
            owner_group = next((g for g in owner.groups if g.folder == group.folder
                                and g.env == group.env),
                               next(g for g in owner.groups if g.folder == group.folder))
            for run in runs:
                key = (owner.name, tuple(departures(run, owner_group, owner)), _seeds(runs))
                commands.setdefault(key, [])
                if algo not in commands[key]:
                    commands[key].append(algo)
    lines = []
    for (name, changes, seeds), algos in commands.items():
        owner = PRESETS[name]
        cmd = [f"lili reproduce {name}"]
        if set(owner.algos) - set(algos):
            cmd.append("--algos " + " ".join(algos))
        if set(owner.envs) - set(part.envs):  # a preset of several envs, one of them here
            cmd.append("--envs " + " ".join(part.envs))
        if seeds != owner.seeds:
            cmd.append(f"--seeds {seeds}")
        for change in changes:
            if change.startswith("interactions="):
                cmd.append(f"--interactions {change.split('=', 1)[1]}")
            elif change.startswith("env "):
                cmd.append(f"--env-kwarg {change[4:]}")
            else:
                cmd.append(f"--set {change}")
        line = " ".join(cmd)
        if line not in lines:
            lines.append(line)
    return lines


def interactions_text(runs: Sequence[Run]) -> str:
    """The runs' interactions: ``2000``, or ``1500-2000`` where they differ."""
    low, high = min(r.n_interactions for r in runs), max(r.n_interactions for r in runs)
    return f"{low}" if low == high else f"{low}-{high}"


def sources_markdown(part: Preset, locate: Locate) -> str:
    """A bullet per source folder ``locate`` names for ``part``'s groups: its path, the algos
    taken from it and why (the sources file's note)."""
    lines, seen = [], set()
    for group in part.groups:
        for source in locate(group):
            key = (str(source.path), source.algos)
            if key in seen:
                continue
            seen.add(key)
            algos = ("" if source.algos is None
                     else " (" + ", ".join(algo_label(a) for a in source.algos) + ")")
            note = f": {source.note}" if source.note else ""
            lines.append(f"- `{source.path.as_posix()}`{algos}{note}")
    return "\n".join(lines) + "\n"
