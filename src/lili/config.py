# Over 400 lines: each AgentConfig field is checked here, beside the YAML rules it is read by.
"""Agent configuration: one dataclass for every agent, validated on construction.

Defaults follow the paper's appendix (encoder and decoder 2x128, latent 8, actor and critic 2x256)
and softlearning's SAC (Adam 3e-4, gamma 0.99, tau 5e-3, automatic temperature with target
entropy -|A|). The few additions, each documented below, address the failure modes measured in
``shared/notes/lili-calibration.md``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
import re
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, TypeVar

import yaml

from lili.errors import shown
from lili.yaml_bounds import MAX_VALUE_CHARS, BoundedComposer, yaml_problem

T = TypeVar("T")

__all__ = ["check_seed", "MAX_SEED", "AgentConfig", "load_config", "read_yaml", "yaml_value",
           "BOUNDARY_DISCOUNTS", "BOUNDARY_MODES", "RETIRED_FIELDS", "LOOP_FIELDS", "SAC_FIELDS",
           "LATENT_FIELDS", "dataclass_options", "stored_agent_config"]

MAX_SEED = 2**32 - 1
"""Largest seed: NumPy's and JAX's generators take 32-bit seeds without folding them."""


def check_seed(seed: Any, name: str = "seed") -> int:
    """``seed`` as an int, or ValueError naming it and the allowed range (one rule for the
    agents, the command line and ``check-env``)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, numbers.Integral)) \
            or not 0 <= seed <= MAX_SEED:
        raise ValueError(f"{name}={seed!r} is invalid; allowed: an integer in [0, {MAX_SEED}]")
    return int(seed)

BOUNDARY_MODES = ("bootstrap", "influence", "cut", "same_z")
BOUNDARY_DISCOUNTS = ("step", "horizon")
# String fields with a fixed set of values: name -> (values, how the error message joins them).
_CHOICES = {"boundary_discount": (BOUNDARY_DISCOUNTS, " or ")}

RETIRED_FIELDS: dict[str, tuple[Any, str | dict[str, str] | tuple[str, str]]] = {
    "latent_kind": ("continuous", {"categorical": "lili-categorical",
                                   "quantised": "lili-quantised"}),
    "latent_target": ("decoder", {"posterior": "lili-posterior"}),
    "critic_latent": ("latent", {"prediction": "lili-prediction-critic"}),
    "latent_bottleneck": (0.0, ("lili-bottleneck", "weight")),
    "latent_balance": (1.0, ("lili-categorical", "balance")),
    "latent_codes": (16, ("lili-quantised", "codes")),
    "boundary_gamma": (None, "was removed; boundary_discount='horizon' took its place"),
}
"""Fields of earlier releases, which run folders' config.yaml still hold: name -> (the value
they ran with by default, where the other values went: a value -> contrib algo mapping, the
contrib algo and option that took the field, or a note). :meth:`AgentConfig.from_dict` drops
them at their default and refuses any other value with one message naming what to use."""

LOOP_FIELDS: frozenset[str] = frozenset({
    "warmup_interactions", "random_interactions", "buffer_capacity", "checkpoint_every"})
"""The fields every agent reads: the training loop's (the random policy reads only these)."""
SAC_FIELDS: frozenset[str] = LOOP_FIELDS | {
    "gamma", "boundary_discount", "tau", "lr_actor", "lr_critic", "lr_alpha", "hidden",
    "batch_interactions", "per_interaction", "updates_per_step", "target_entropy", "init_alpha",
    "phase_feature", "normalize", "boundary"}
"""The fields every learning agent reads: the SAC core's (SAC, SLAC, the Oracles)."""
LATENT_FIELDS: frozenset[str] = SAC_FIELDS | {
    "lr_encoder", "lr_decoder", "enc_hidden", "latent_dim", "history", "encoder_transitions",
    "target_encoder", "critic_to_encoder", "rep_weight"}
"""The fields the agents with a latent read (LILI's encoder and decoder; LILAC and two contrib
variants read all but one, see their ``reads`` in ``lili.agents.registry.TABLE``)."""


@dataclass(frozen=True)
class AgentConfig:
    """Hyperparameters of the agents: the fields they share, and ``extra`` for each agent's own.

    Each algo reads only some of the fields: :data:`LOOP_FIELDS` (every agent: the training
    loop reads them), :data:`SAC_FIELDS` (every learning agent) and :data:`LATENT_FIELDS` (the
    agents with a latent: LILI, LILI (no influence), LILAC, the contrib variants); the exact set
    of each algo is ``reads`` of its entry in :data:`lili.agents.registry.TABLE`. A field that
    an algo does not read, set to anything but its default, is an error when an agent is made
    (``lili.agents.check_config``), not silently ignored. An algo's own options live in
    ``extra[<algo>]``, as the frozen dataclass the algo registers (SLAC, LILAC, the
    last-interaction Oracle and the variants of :mod:`lili.contrib`, which took the fields of
    :data:`RETIRED_FIELDS`).

    Attributes:
        gamma: per-step discount, applied across interaction boundaries too (the stream of
            interactions goes on; 0.99**50 = 0.6 per Point Mass interaction).
        boundary_discount: how far away the next interaction is when one ends early.
            ``step`` (the paper): every step discounts by ``gamma``, so an interaction that
            ends at step t < H reaches the next one H - 1 - t steps sooner, and an agent that
            bootstraps across the boundary is paid for ending interactions early (measured on
            Lunar Lander, whose interactions end on contact: LILI, SAC and the Oracle land in
            about 24 steps, LILI (no influence) in about 40). ``horizon``: the next
            interaction is discounted as if this one had run to the horizon H, by an extra
            ``gamma ** (H - 1 - t)`` at a last step at t, so when an interaction ends does not
            change the next one's weight. The two are the same where every interaction runs
            to H.
        tau: Polyak rate of the target critic (and the target encoder), every update.
        lr_actor, lr_critic, lr_alpha: Adam learning rates (SAC defaults).
        lr_encoder: encoder learning rate (critic and representation gradients).
        lr_decoder: decoder learning rate (notes: LILI's code used 1e-3 for the model).
        hidden: actor and critic hidden widths (paper: 2x256).
        enc_hidden: encoder and decoder hidden widths (paper: 2x128).
        latent_dim: size of z (paper: 8).
        history: number of past interactions the encoder reads (1 = the paper's LILI; LILAC's
            window is its own option ``prior_window``).
        batch_interactions, per_interaction: a batch is ``batch_interactions`` interactions
            with ``per_interaction`` transitions each (32 x 8 = 256, as in LILI's code), drawn
            uniformly over time steps (the boundary is not oversampled).
        encoder_transitions: during updates the encoder reads this many transitions of each
            interaction (the last one always among them; the rest uniform), None = all. LILI's
            original code used 8. Acting always encodes every transition. 16 cuts LILI's update
            cost by about a third on Point Mass (H = 50) against encoding all 50.
        updates_per_step: gradient updates per environment step; all updates of one
            interaction run as one fused ``lax.scan`` block.
        warmup_interactions: interactions with uniform random actions before learning starts.
        random_interactions: after the warm-up, the probability that an interaction is played
            with uniform random actions all the same (0 = never; the paper's agents explore
            only through SAC's entropy). Which interactions is decided from the seed and the
            interaction's index (``lili.train.plays_at_random``); they are trained on and
            logged like the others (``summary.json`` adds ``final_return_policy`` and
            ``final_success_policy`` without them). Measured on Drift, where the greedy
            policy never ends an interaction on the side that influence needs
            (``docs/journal/2026-11-to-12.md``).
        target_entropy: None = -|A| (SAC's default).
        init_alpha: initial temperature (0.1: the rewards here are O(0.05..1) per step, so
            SAC's usual 1.0 lets the entropy bonus swamp them for hundreds of interactions).
        phase_feature: give actor, critic and encoder the step's phase t/H. Without it the last
            step of an interaction (whose target jumps to the next interaction) is aliased with
            the same state earlier in the interaction (calibration note, failure 2).
        normalize: standardise observations, rewards and the decoder's targets with statistics
            fitted on the warm-up interactions and then frozen (calibration note, failure 4:
            the raw decoder loss is ~1e-4 and hardly shapes the encoder).
        target_encoder: compute the latents inside the critic target with a Polyak-averaged
            copy of the encoder, so the target does not chase the encoder that the critic loss
            itself moves (calibration note, failure 1).
        critic_to_encoder: weight of the critic loss's gradient into the encoder (paper: the
            encoder learns from both J_Q and J_rep).
        rep_weight: weight of the representation loss J_rep.
        boundary: how the critic target treats the last step of an interaction:
            ``bootstrap`` (SAC, Oracle: y = r + gamma V(s^{i+1}_1)), ``influence`` (LILI:
            y = r + gamma V(s^{i+1}_1, E(tau^i))), ``cut`` (LILI no influence: y = r) or
            ``same_z`` (a public re-implementation's reading of no influence: bootstrap with
            the unchanged z^i). Set by the agent; override only to compare readings. (Every
            learning agent but SLAC takes every mode; SLAC takes bootstrap and cut.)
        buffer_capacity: interactions kept (ring buffer); at least ``warmup_interactions``
            (the normalisation statistics are fitted on every warm-up interaction, so a
            smaller ring would forget some before they are used) and ``history + 1`` (the
            encoder's window plus the interaction it is applied to).
        checkpoint_every: interactions between checkpoints in a run folder.
        extra: the options of the agent the config is for, under its algo name, e.g.
            ``{"slac": {"model_every": 2}}`` (see ``lili.agents.slac.SLACOptions``). This class
            checks the shape (algo name -> mapping of options); ``lili.agents.check_config``
            checks that the only entry is the algo's own and its names and values.

    Every field is checked on construction: a value of the wrong type (``gamma=False``,
    ``hidden=[256.5]``), out of range, NaN or infinite raises ValueError naming the field,
    the value and what is allowed. NumPy scalars are accepted and stored as Python numbers.
    """

    gamma: float = 0.99
    boundary_discount: str = "step"
    tau: float = 0.005
    lr_actor: float = 3e-4
    lr_critic: float = 3e-4
    lr_alpha: float = 3e-4
    lr_encoder: float = 3e-4
    lr_decoder: float = 1e-3
    hidden: tuple[int, ...] = (256, 256)
    enc_hidden: tuple[int, ...] = (128, 128)
    latent_dim: int = 8
    history: int = 1
    batch_interactions: int = 32
    per_interaction: int = 8
    encoder_transitions: int | None = 16
    updates_per_step: float = 1.0
    warmup_interactions: int = 20
    random_interactions: float = 0.0
    target_entropy: float | None = None
    init_alpha: float = 0.1
    phase_feature: bool = True
    normalize: bool = True
    target_encoder: bool = True
    critic_to_encoder: float = 1.0
    rep_weight: float = 1.0
    boundary: str | None = None
    buffer_capacity: int = 10_000
    checkpoint_every: int = 100
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name, (ok, allowed) in _NUMBERS.items():
            _set(self, name, _number(self, name, ok, allowed))
        for name, low in _INTEGERS.items():
            _set(self, name, _integer(self, name, low))
        if self.target_entropy is not None:
            _set(self, "target_entropy", _number(self, "target_entropy", _ANY,
                                                 "a finite number or null (= -|A|)"))
        if self.encoder_transitions is not None:
            _set(self, "encoder_transitions",
                 _integer(self, "encoder_transitions", 1, " or null (= all)"))
        # The buffer must hold the warm-up interactions (the normalisation statistics and the
        # first updates are fitted on all of them) and the encoder's window of ``history``
        # interactions plus the one it is applied to.
        low = max(self.warmup_interactions, self.history + 1)
        if self.buffer_capacity < low:
            raise _bad(self, "buffer_capacity", f"an integer >= {low} (it must hold the "
                       f"warmup_interactions={self.warmup_interactions} and history + 1 = "
                       f"{self.history + 1} interactions)")
        for name in ("hidden", "enc_hidden"):
            v = getattr(self, name)
            if not isinstance(v, (tuple, list)) or not v or not all(
                isinstance(h, numbers.Integral) and not isinstance(h, bool) and h > 0 for h in v
            ):
                raise _bad(self, name, "a non-empty list of positive integers")
            _set(self, name, tuple(int(h) for h in v))
        for name in ("phase_feature", "normalize", "target_encoder"):
            if not isinstance(getattr(self, name), bool):
                raise _bad(self, name, "true or false")
        if self.boundary is not None and (not isinstance(self.boundary, str)
                                          or self.boundary not in BOUNDARY_MODES):
            raise _bad(self, "boundary", ", ".join(BOUNDARY_MODES) + " or null (the agent's "
                       "default)")
        for name, (choices, sep) in _CHOICES.items():
            value = getattr(self, name)
            if not isinstance(value, str) or value not in choices:
                raise _bad(self, name, sep.join(choices))
        _check_extra_shape(self.extra)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> AgentConfig:
        """Build from a mapping; unknown keys are an error that names them and the allowed ones."""
        if not isinstance(d, dict):
            raise ValueError(f"config must be a mapping of field: value; got {type(d).__name__}")
        for name in RETIRED_FIELDS:  # in its order: the variant's name before its options
            if name in d:
                _check_retired(name, d[name])
        d = {k: v for k, v in d.items() if k not in RETIRED_FIELDS}
        _check_keys(d)
        return cls(**d)

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["hidden"], d["enc_hidden"] = list(self.hidden), list(self.enc_hidden)
        return d

    def replace(self, **changes: Any) -> AgentConfig:
        return dataclasses.replace(self, **changes)


class UnknownConfigKey(ValueError, TypeError):
    """A config key that is no field of :class:`AgentConfig` (a TypeError too, as Python's own
    for an unknown keyword)."""


def _check_keys(keys: Any) -> None:
    names = {f.name for f in fields(AgentConfig)}
    unknown = sorted(set(keys) - names, key=str)
    if unknown:
        raise UnknownConfigKey(f"unknown config key(s) {', '.join(shown(k) for k in unknown)}; "
                               f"allowed: {', '.join(sorted(names))}")


_dataclass_init = AgentConfig.__init__


@functools.wraps(_dataclass_init)
def _init(self: AgentConfig, *args: Any, **kwargs: Any) -> None:
    # ``AgentConfig(foo=1)`` names the fields instead of the dataclass's bare TypeError.
    _check_keys(kwargs)
    _dataclass_init(self, *args, **kwargs)


AgentConfig.__init__ = _init  # type: ignore[method-assign]


def _check_retired(name: str, value: Any) -> None:
    """Nothing when the retired field ``name`` holds its old default; else ValueError naming
    where it went."""
    default, went = RETIRED_FIELDS[name]
    if value is default or (not isinstance(value, bool) and value == default):
        return
    if isinstance(went, str):
        raise ValueError(f"config {name}={value!r} is no longer supported: the field {went}")
    if isinstance(went, tuple):
        algo, option = went
        raise ValueError(f"config {name}={value!r} moved to lili.contrib: use --algo {algo} with "
                         f"extra: {{{algo}: {{{option}: {value!r}}}}}")
    if isinstance(value, str) and value in went:
        raise ValueError(f"config {name}={value!r} moved to lili.contrib: use --algo "
                         f"{went[value]}")
    raise ValueError(f"config {name}={value!r} is invalid: the field was removed (its default "
                     f"{default!r} is what every agent does; the other values are the algos "
                     f"{', '.join(went.values())})")


def stored_agent_config(stored: Any) -> Any:
    """A run folder's stored agent config (``config.yaml``'s ``agent``) with the fields added
    since it was written set to their defaults, which are what it ran with (every new field
    defaults to the behaviour before it): so a run of an earlier release resumes and counts as
    done. Returned unchanged when it is not a valid config, for the caller to report; ValueError
    naming the contrib algo to use when it ran a variant that has left the core
    (:data:`RETIRED_FIELDS`)."""
    if not isinstance(stored, dict):
        return stored
    for name in RETIRED_FIELDS:
        if name in stored:
            _check_retired(name, stored[name])
    try:
        return AgentConfig.from_dict(stored).to_dict()
    except (ValueError, TypeError):
        return stored


def _bad(config: AgentConfig, name: str, allowed: str) -> ValueError:
    return ValueError(f"config {name}={getattr(config, name)!r} is invalid; allowed: {allowed}")


def _set(config: AgentConfig, name: str, value: Any) -> None:
    object.__setattr__(config, name, value)  # the dataclass is frozen


def _ANY(v: float) -> bool:
    return True


def _number(config: AgentConfig, name: str, ok: Callable[[float], bool], allowed: str) -> float:
    """The field as a Python number, or ValueError; bools, NaN and infinities are refused."""
    v = getattr(config, name)
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v) \
            or not ok(v):
        raise _bad(config, name, allowed)
    return v if type(v) in (int, float) else float(v)  # np.float64 is a float subclass


def _integer(config: AgentConfig, name: str, low: int, also: str = "") -> int:
    v = getattr(config, name)
    if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < low:
        raise _bad(config, name, f"an integer >= {low}{also}")
    return int(v)


_NUMBERS: dict[str, tuple[Callable[[float], bool], str]] = {
    "gamma": (lambda v: 0 <= v < 1, "a number in [0, 1)"),
    "tau": (lambda v: 0 < v <= 1, "a number in (0, 1]"),
    **{name: ((lambda v: v > 0), "a finite number > 0") for name in (
        "lr_actor", "lr_critic", "lr_alpha", "lr_encoder", "lr_decoder", "updates_per_step",
        "init_alpha")},
    **{name: ((lambda v: v >= 0), "a finite number >= 0") for name in (
        "critic_to_encoder", "rep_weight")},
    "random_interactions": (lambda v: 0 <= v <= 1, "a number in [0, 1]"),
}
"""Number fields: (test, what is allowed). Every number must also be finite and not a bool."""

_INTEGERS: dict[str, int] = {
    "latent_dim": 1, "history": 1, "batch_interactions": 1, "per_interaction": 1,
    "warmup_interactions": 2, "buffer_capacity": 2, "checkpoint_every": 1,
}
"""Integer fields and their lower bounds (``buffer_capacity`` has a further one)."""


def _check_extra_shape(extra: Any) -> None:
    """``extra`` maps agent names to mappings of options; which names and options an agent
    knows is checked by ``lili.agents.check_extra`` (this module sits below the agents)."""
    if not isinstance(extra, dict):
        raise ValueError(f"config extra={extra!r} is invalid; allowed: a mapping of agent name "
                         "to its options, e.g. {slac: {model_every: 2}}")
    for key, options in extra.items():
        if not isinstance(key, str) or not isinstance(options, dict) or not all(
                isinstance(k, str) for k in options):
            raise ValueError(f"config extra.{key}={options!r} is invalid; allowed: a mapping of "
                             "option name: value")


def dataclass_options(config: AgentConfig, key: str, cls: type[T]) -> T:
    """An agent's own options as the frozen dataclass ``cls``, from ``config.extra[key]``
    (the fields not given keep their defaults); ValueError naming ``extra.<key>`` and the
    allowed names or the bad value (``cls.__post_init__`` checks the values)."""
    names = [f.name for f in fields(cls)]  # type: ignore[arg-type]
    raw = config.extra.get(key, {})
    if not isinstance(raw, dict):
        raise ValueError(f"config extra.{key}={raw!r} is invalid; allowed: a mapping of "
                         f"{', '.join(names) or 'nothing'}")
    unknown = sorted(set(raw) - set(names))
    if unknown:
        raise ValueError(f"unknown {key} option(s) {', '.join(map(repr, unknown))} in config "
                         f"extra.{key}; allowed: {', '.join(names) or 'none'}")
    return cls(**raw)


class _Loader(BoundedComposer, yaml.SafeLoader):
    """PyYAML's safe loader, with two changes a user writing a config expects.

    ``1e-3`` is a number (YAML 1.2; PyYAML follows YAML 1.1, where a float needs a dot, so
    ``lr_actor: 1e-3`` would be the string "1e-3"), and a key given twice in one mapping is an
    error (PyYAML silently keeps the last one).
    """

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                duplicate = key in seen
            except TypeError:  # an unhashable key: PyYAML's own error follows
                continue
            if duplicate:
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key {key!r} is given twice", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep)


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float", re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)"
                                          r"[eE][-+]?[0-9]+$"), list("-+0123456789."))


class _ValueLoader(_Loader):
    max_chars = MAX_VALUE_CHARS


def yaml_value(text: str) -> Any:
    """Parse one YAML value (``--env-kwarg KEY=VALUE``) with the rules of :func:`read_yaml`."""
    try:
        return yaml.load(text, Loader=_ValueLoader)  # noqa: S506 - _Loader is a SafeLoader
    except yaml.YAMLError as e:
        raise ValueError(f"{shown(text)} is not a valid YAML value ({yaml_problem(e)})") \
            from None


def read_yaml(path: str | Path, what: str = "config file") -> Any:
    """Read a YAML file; ValueError with one line naming the file and, for malformed YAML, the
    line and column (missing file, folder, not UTF-8 text, malformed YAML)."""
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{what} {str(p)!r} is a folder; allowed: a YAML file")
    if not p.is_file():
        raise ValueError(f"{what} {str(p)!r} does not exist")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{what} {str(p)!r} is not UTF-8 text; allowed: a YAML file") from None
    except OSError as e:
        raise ValueError(f"{what} {str(p)!r} cannot be read ({e.strerror})") from None
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 - _Loader is a SafeLoader
    except yaml.YAMLError as e:
        raise ValueError(f"{what} {str(p)!r} is not valid YAML: {yaml_problem(e)}") from None


def load_config(path: str | Path) -> AgentConfig:
    """Read an AgentConfig from a YAML file (only the fields to change need to be given).

    Raises ValueError with one line naming the file and the bad value.
    """
    data = read_yaml(path)
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValueError(f"config file {str(path)!r} must hold a mapping of field: value; got "
                         f"{type(data).__name__}")
    try:
        return AgentConfig.from_dict(data)
    except (TypeError, ValueError) as e:
        raise ValueError(f"config file {str(path)!r}: {e}") from None
