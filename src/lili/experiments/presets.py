"""One preset per figure or table of the paper: which runs it needs and what it reports.

A preset is a list of :class:`Group` s (runs that share env, env kwargs and agent config, one per
algo and seed) plus the budget, the seeds and the paper entry it sits beside (a key of
:data:`lili.report.PAPER` for an env, or of :data:`lili.report.PAPER_TABLES` for the two
appendix tables whose rows are partner variants). Groups name the experiment folder their runs
live in, relative to ``--out``; groups of different presets that name the same folder and
spec are the same runs, so the noise table's sigma = 0 row, the history table's N = 1 row and
both tables' SAC and Oracle bounds are the Point Mass preset's runs, trained once.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from lili.agents.registry import LILI_VARIANTS, PAPER_ALGOS

__all__ = ["Group", "Preset", "PRESETS", "get_preset", "ALL_ALGOS"]

ALL_ALGOS = PAPER_ALGOS  # the paper's algos, in the registry's order
PM = "lili/PointMass-v0"
NOISE = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)
HISTORY = (1, 3, 5, 7, 9, 11)
NOISE_BOUNDED = (0.4, 1.0)
"""Noise levels where the noise preset also runs SAC and the Oracle (issue 34)."""
HISTORY_BOUNDED = (5, 11)
"""History lengths where the history preset also runs SAC and the Oracle."""


@dataclass(frozen=True)
class Group:
    """Runs of ``algos`` on one env with one set of env kwargs and agent-config overrides.

    ``folder`` is the experiment folder under ``--out`` (``lili train --out``); ``label`` and
    ``value`` name the row in a variant table (``value`` is the partner parameter, e.g. sigma).
    """

    folder: str
    env: str
    algos: tuple[str, ...]
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    label: str = ""
    value: float | int | None = None


@dataclass(frozen=True)
class Preset:
    """One paper item: its runs (``groups`` x ``seeds``), budget, and what the report shows.

    ``kind`` is ``"env"`` (learning curves and a table per env, ``lili report``'s) or
    ``"table"`` (one row per partner variant beside :data:`lili.report.PAPER_TABLES`
    [``table``]). ``includes`` lists the presets that ``paper`` is made of.
    """

    name: str
    title: str
    where: str
    interactions: int
    groups: tuple[Group, ...]
    seeds: int = 3
    kind: str = "env"
    table: str | None = None
    metric: str = "final return: mean over the last 10% of interactions per seed"
    includes: tuple[str, ...] = ()
    departures: dict[str, Any] = field(default_factory=dict)
    paper_interactions: int | None = None
    departure_reason: str = ""

    def departs(self) -> str:
        """Where this preset's setting departs from the paper's, as flags would set it (empty
        when it is the paper's): printed in its reports' header."""
        parts = [f"`{k}={v}`" for k, v in _flat(self.departures).items()]
        if self.paper_interactions is not None:
            parts.append(f"{self.interactions} interactions (the paper: "
                         f"{self.paper_interactions})")
        if not parts:
            return ""
        return (", ".join(parts) + (f" ({self.departure_reason})" if self.departure_reason
                                    else "") + "; `--paper-settings` runs the paper's setting")

    def paper_setting(self) -> Preset:
        """This preset at the paper's literal setting (``lili reproduce --paper-settings``):
        without its departures."""
        if not self.departures and self.paper_interactions is None:
            return self
        groups = tuple(replace(g, config={k: v for k, v in g.config.items()
                                          if k not in self.departures}) for g in self.groups)
        return replace(self, groups=groups, departures={}, paper_interactions=None,
                       departure_reason="",
                       interactions=self.paper_interactions or self.interactions)

    def for_env(self, env: str) -> Preset:
        """This preset's groups on ``env`` alone: how a preset that runs several envs in one
        folder (``influence``) is read, one env at a time. ValueError for an env it does not
        run."""
        groups = tuple(g for g in self.groups if g.env == env)
        if not groups:
            raise ValueError(f"preset {self.name!r} runs no env {env!r}; allowed: "
                             f"{', '.join(self.envs)}")
        return replace(self, groups=groups)

    @property
    def algos(self) -> tuple[str, ...]:
        """Every algo any group of this preset runs, in first-seen order."""
        return tuple(dict.fromkeys(a for g in self.groups for a in g.algos))

    @property
    def envs(self) -> tuple[str, ...]:
        """Every env id any group of this preset runs on, in first-seen order."""
        return tuple(dict.fromkeys(g.env for g in self.groups))


def _flat(config: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``config`` with nested mappings spelt as dotted keys (``extra.slac.decoder_std``), as a
    config file or ``--set`` names them."""
    out: dict[str, Any] = {}
    for k, v in config.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _env_preset(name: str, env: str, where: str, interactions: int, algos: tuple[str, ...],
                title: str, metric: str | None = None, departures: dict[str, Any] | None = None,
                paper_interactions: int | None = None, reason: str = "",
                seeds: int = Preset.seeds) -> Preset:
    """An env's preset; ``departures`` (agent-config fields of every run) and
    ``paper_interactions`` say where its default departs from the paper's setting."""
    departures = departures or {}
    return Preset(name=name, title=title, where=where, interactions=interactions, seeds=seeds,
                  groups=(Group(folder=name, env=env, algos=algos, config=dict(departures)),),
                  metric=metric or Preset.metric, departures=departures,
                  paper_interactions=paper_interactions, departure_reason=reason)


def _variant_algos(value: Any, bounded: tuple[Any, ...]) -> tuple[str, ...]:
    """A variant row's algos: LILI, and SAC and the Oracle at the variants ``bounded`` (the
    paper reports them aggregated over all variants, "similar across" them: these check it)."""
    return ("lili", "sac", "oracle") if value in bounded else ("lili",)


def _variant_table(name: str, title: str, where: str, plain: Group,
                   variants: list[Group]) -> Preset:
    """An appendix table whose rows are partner variants: LILI on the plain task (``plain``,
    the Point Mass preset's own runs), a group per variant, and SAC and the Oracle of the plain
    task as the bounds."""
    bounds = Group(folder="point-mass", env=PM, algos=("sac", "oracle"), label="bounds")
    return Preset(name=name, title=title, where=where, interactions=2000,
                  groups=(plain, *variants, bounds), kind="table", table=name)


def _noise() -> Preset:
    return _variant_table(
        "noise", "Point Mass, noisy partner (LILI)", "Appendix E.1, Table 2",
        Group(folder="point-mass", env=PM, algos=("lili",), label="sigma = 0 (Point Mass)",
              value=0.0),
        [Group(folder=f"noise/sigma_{sigma:g}", env=PM, algos=_variant_algos(sigma, NOISE_BOUNDED),
               env_kwargs={"step_noise": sigma}, label=f"sigma = {sigma:g}", value=sigma)
         for sigma in NOISE[1:]])


def _history() -> Preset:
    return _variant_table(
        "history", "Point Mass, partner that reacts to the last N interactions (LILI, encoder "
        "over the last N)", "Appendix E.2, Table 3",
        Group(folder="point-mass", env=PM, algos=("lili",), label="N = 1 (Point Mass)", value=1),
        [Group(folder=f"history/n_{n}", env=PM, algos=_variant_algos(n, HISTORY_BOUNDED),
               env_kwargs={"history": n}, config={"history": n}, label=f"N = {n}", value=n)
         for n in HISTORY[1:]])


def _history_text_rule() -> Preset:
    """The history table under the other reading of the majority rule (not part of paper)."""
    base = _history()
    groups = [Group(folder=f"history-text-rule/n_{g.value}", env=PM, algos=("lili",),
                    env_kwargs={"history": g.value, "inside_turn": "counterclockwise"},
                    config={"history": g.value}, label=f"N = {g.value}", value=g.value)
              for g in base.groups if g.value is not None]
    return Preset(name="history-text-rule", title="Point Mass history table under Appendix "
                  "E.2's wording of the rule (inside -> counter-clockwise)",
                  where="Appendix E.2, Table 3 (the other reading)", interactions=2000,
                  groups=tuple(groups), kind="table", table="history")


def _quickstart() -> Preset:
    """``make run``: the paper's point in minutes (not part of ``paper``).

    Driving (2D) is the paper's task where LILI's advantage shows fastest: the other car merges
    into the lane the ego used last, so an agent must model it to pass. Two updates per step
    and 400 interactions (H = 10): about a minute of CPU per run on an idle core.
    """
    return Preset(name="quickstart", title="Quick start: LILI against SAC on Driving (2D)",
                  where="Fig. 5 (Sec. 5.2), Driving (2D), at a small budget",
                  interactions=400, seeds=1,
                  groups=(Group(folder="quickstart", env="lili/Driving2D-v0",
                                algos=("sac", "lili"), config={"updates_per_step": 2.0}),),
                  metric="final return and success: mean over the last 10% of interactions")


INFLUENCE_ENVS = ("lili/InfluenceDrift-v0", "lili/InfluenceSwitch-v0", "lili/InfluenceFlee-v0")
# Written out although it is the default, so that a run's config.yaml says which Drift it met:
# runs of the first version (returns=0) then count as another config, not as finished runs.
INFLUENCE_KWARGS: dict[str, dict[str, Any]] = {"lili/InfluenceDrift-v0": {"returns": 0.05}}


def _influence() -> Preset:
    """The influence suite's learned rows (not part of ``paper``; ``benchmarks/influence.py``
    sets them beside the scripted optima). H = 4, so 2000 interactions are 8000 updates."""
    return Preset(name="influence", title="Influence suite: learned agents beside the known "
                  "optima (docs/influence.md)",
                  where="not in the paper: envs whose best greedy and influencing returns are "
                  "known by construction", interactions=2000,
                  groups=tuple(Group(folder="influence", env=env,
                                     algos=("sac", "lili-no-influence", "lili", "oracle",
                                            "oracle-last"),
                                     env_kwargs=INFLUENCE_KWARGS.get(env, {}))
                               for env in INFLUENCE_ENVS))


def _contrib() -> Preset:
    """LILI beside its variants in :mod:`lili.contrib`, on the influence suite's envs, where
    they were measured, and on Point Mass, the paper's influence domain, which a variant must
    hold before it can become LILI's default (not part of ``paper``; ``lili reproduce contrib
    --envs influence-flee --algos lili-prediction-critic`` runs one)."""
    return Preset(name="contrib", title="LILI's variants in lili.contrib, on the influence suite "
                  "and Point Mass",
                  where="not in the paper: variants kept out of the core (README.md, "
                  "\"Contrib variants\")", interactions=2000,
                  groups=tuple(Group(folder="contrib", env=env, algos=("lili", *LILI_VARIANTS),
                                     env_kwargs=INFLUENCE_KWARGS.get(env, {}))
                               for env in (*INFLUENCE_ENVS, PM)))


def _build() -> dict[str, Preset]:
    presets = [
        _env_preset("point-mass", PM, "Fig. 4 (Sec. 5.2; curves, heatmap of the target over "
                    "the last 500 interactions) and Table 2's sigma = 0, SAC and Oracle rows",
                    2000, ALL_ALGOS, "Point Mass"),
        _noise(),
        _history(),
        _env_preset("driving-2d", "lili/Driving2D-v0", "Fig. 5 (Sec. 5.2), Appendix D.2",
                    1000, ALL_ALGOS, "Driving (2D)",
                    "final return and success: mean over the last 10% of interactions"),
        _env_preset("driving-steer", "lili/DrivingSteer-v0",
                    "Fig. 5 (Sec. 5.2, Driving CARLA), Appendix D.3", 1000, ALL_ALGOS,
                    "Driving (steering; the paper's CARLA task)",
                    "final return and success: mean over the last 10% of interactions"),
        _env_preset("lunar-lander", "lili/LunarLander-v0", "Fig. 5 (Sec. 5.2), Appendix D.1",
                    2000, ALL_ALGOS, "Lunar Lander",
                    "final return and landing success: mean over the last 10% of interactions",
                    departures={"boundary_discount": "horizon",
                                "extra": {"slac": {"decoder_std": 0.1}}},
                    reason="interactions end early here; with the per-step discount an agent "
                    "is paid for ending one early, and LILI landed less often than LILI (no "
                    "influence): the journal's Lunar Lander tables. SLAC's decoder std: the "
                    "official sqrt(0.1), sized for images, leaves its belief of the lander's "
                    "height and speed coarse before touchdown, and SLAC hovers instead of "
                    "landing (the journal's SLAC sections, benchmarks/slac_belief.py)"),
        # Eight seeds: "LILI > LILI (no influence)" needs five (lili.experiments.claims), and at
        # six one late-learning seed left the interval of P(>) touching one half (journal, s33).
        _env_preset("air-hockey", "lili/AirHockey-v0", "Fig. 6 (Sec. 5.3)", 3000,
                    ("random", "sac", "lili-no-influence", "lili", "oracle"), "Air hockey",
                    "block rate and reward per interaction over the last 10%; striker's modes "
                    "over the last 200",
                    departures={"random_interactions": 0.1}, paper_interactions=1000,
                    seeds=8,
                    reason="at the paper's setting LILI falls below LILI (no influence) at "
                    "1000 interactions; with a tenth of the interactions played at random it "
                    "comes out above it, but some seeds first settle in a cycle of the "
                    "striker's without left shots, or learn the left block late, and need more "
                    "interactions to get past it; fewer of them are left at 3000 than at 2000, "
                    "and eight seeds make the order decisive (docs/results.md, \"Air hockey\"; "
                    "the journal's air hockey sections)"),
        _history_text_rule(),
        _influence(),
        _contrib(),
        _quickstart(),
    ]
    table = {p.name: p for p in presets}
    parts = ("point-mass", "noise", "history", "driving-2d", "driving-steer", "lunar-lander",
             "air-hockey")
    table["paper"] = Preset(
        name="paper", title="Every figure and table of the paper's Sec. 5 and Appendix E",
        where="Sec. 5, Appendix E", interactions=0,
        groups=tuple(g for name in parts for g in table[name].groups), includes=parts)
    return table


PRESETS: dict[str, Preset] = _build()
"""Every preset by name; ``paper`` is all of the paper's items (not ``history-text-rule``,
``influence``, ``contrib`` or ``quickstart``)."""


def get_preset(name: str) -> Preset:
    """The preset called ``name``, or ValueError naming it and the allowed names."""
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; allowed: {', '.join(PRESETS)}")
    return PRESETS[name]
