"""Agent configuration: one dataclass for every agent, validated on construction.

Defaults follow the paper's appendix (encoder and decoder 2x128, latent 8, actor and critic 2x256)
and softlearning's SAC (Adam 3e-4, gamma 0.99, tau 5e-3, automatic temperature with target
entropy -|A|). The few additions, each documented below, address the failure modes measured in
``shared/notes/lili-calibration.md``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

__all__ = ["AgentConfig", "load_config", "BOUNDARY_MODES", "extra_options"]

BOUNDARY_MODES = ("bootstrap", "influence", "cut", "same_z")


@dataclass(frozen=True)
class AgentConfig:
    """Hyperparameters of every agent (fields irrelevant to an agent are ignored by it).

    Attributes:
        gamma: per-step discount, applied across interaction boundaries too (the stream of
            interactions goes on; 0.99**50 = 0.6 per Point Mass interaction).
        tau: Polyak rate of the target critic (and the target encoder), every update.
        lr_actor, lr_critic, lr_alpha: Adam learning rates (SAC defaults).
        lr_encoder: encoder learning rate (critic and representation gradients).
        lr_decoder: decoder learning rate (notes: LILI's code used 1e-3 for the model).
        hidden: actor and critic hidden widths (paper: 2x256).
        enc_hidden: encoder and decoder hidden widths (paper: 2x128).
        latent_dim: size of z (paper: 8).
        history: number of past interactions the encoder reads (1 = the paper's LILI).
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
            the unchanged z^i). Set by the agent; override only to compare readings.
        buffer_capacity: interactions kept (ring buffer).
        checkpoint_every: interactions between checkpoints in a run folder.
        extra: options of one agent, keyed by its name, e.g. ``{"slac": {"model_every": 2}}``
            (see ``lili.agents.slac.SLAC_OPTIONS``); each agent checks its own entry.
    """

    gamma: float = 0.99
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
        def bad(name: str, allowed: str) -> ValueError:
            value = getattr(self, name)
            return ValueError(f"config {name}={value!r} is invalid; allowed: {allowed}")

        for name in ("gamma",):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not 0 <= v < 1:
                raise bad(name, "a number in [0, 1)")
        for name in ("tau",):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not 0 < v <= 1:
                raise bad(name, "a number in (0, 1]")
        for name in ("lr_actor", "lr_critic", "lr_alpha", "lr_encoder", "lr_decoder",
                     "updates_per_step", "init_alpha"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
                raise bad(name, "a number > 0")
        for name in ("critic_to_encoder", "rep_weight"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or v < 0:
                raise bad(name, "a number >= 0")
        for name, low in (("latent_dim", 1), ("history", 1), ("batch_interactions", 1),
                          ("per_interaction", 1), ("warmup_interactions", 2),
                          ("buffer_capacity", 2), ("checkpoint_every", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise bad(name, f"an integer >= {low}")
        for name in ("hidden", "enc_hidden"):
            v = getattr(self, name)
            if not isinstance(v, (tuple, list)) or not v or not all(
                isinstance(h, int) and not isinstance(h, bool) and h > 0 for h in v
            ):
                raise bad(name, "a non-empty list of positive integers")
            object.__setattr__(self, name, tuple(v))
        for name in ("phase_feature", "normalize", "target_encoder"):
            if not isinstance(getattr(self, name), bool):
                raise bad(name, "true or false")
        et = self.encoder_transitions
        if et is not None and (isinstance(et, bool) or not isinstance(et, int) or et < 1):
            raise bad("encoder_transitions", "an integer >= 1 or null (= all)")
        te = self.target_entropy
        if te is not None and (isinstance(te, bool) or not isinstance(te, (int, float))):
            raise bad("target_entropy", "a number or null (= -|A|)")
        if self.boundary is not None and self.boundary not in BOUNDARY_MODES:
            raise bad("boundary", ", ".join(BOUNDARY_MODES) + " or null (the agent's default)")

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> AgentConfig:
        """Build from a mapping; unknown keys are an error that names them and the allowed ones."""
        if not isinstance(d, dict):
            raise ValueError(f"config must be a mapping of field: value; got {type(d).__name__}")
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(
                f"unknown config key(s) {', '.join(map(repr, unknown))}; allowed: "
                f"{', '.join(sorted(names))}"
            )
        return cls(**d)

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["hidden"], d["enc_hidden"] = list(self.hidden), list(self.enc_hidden)
        return d

    def replace(self, **changes: Any) -> AgentConfig:
        return dataclasses.replace(self, **changes)


def extra_options(config: AgentConfig, key: str, defaults: dict[str, Any],
                  label: str) -> dict[str, Any]:
    """An agent's own options: ``config.extra[key]`` over ``defaults``, keys checked.

    Raises ValueError naming the bad value when ``extra[key]`` is not a mapping or has keys that
    ``defaults`` lacks; checking each value is the agent's job.
    """
    raw = config.extra.get(key, {})
    if not isinstance(raw, dict):
        raise ValueError(f"config extra.{key}={raw!r} is invalid; allowed: a mapping of "
                         f"{', '.join(defaults)}")
    unknown = sorted(set(raw) - set(defaults))
    if unknown:
        raise ValueError(f"unknown {label} option(s) {', '.join(map(repr, unknown))} in config "
                         f"extra.{key}; allowed: {', '.join(defaults)}")
    return {**defaults, **raw}


def load_config(path: str | Path) -> AgentConfig:
    """Read an AgentConfig from a YAML file (only the fields to change need to be given)."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"config file {str(p)!r} does not exist")
    try:
        data = yaml.safe_load(p.read_text()) or {}
    except yaml.YAMLError as e:
        raise ValueError(f"config file {str(p)!r} is not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ValueError(f"config file {str(p)!r} must hold a mapping of field: value")
    try:
        return AgentConfig.from_dict(data)
    except TypeError as e:
        raise ValueError(f"config file {str(p)!r}: {e}") from None
