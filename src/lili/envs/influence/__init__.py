"""The influence suite: small repeated-interaction envs whose best greedy and best influencing
policies are known by construction, with those policies scripted next to each env.

- ``lili/InfluenceDrift-v0`` (:mod:`.drift`): a goal that drifts toward the side where the ego
  ended and returns near the start 5% of the time. Knowing the goal is worth 0.32 per
  interaction, holding it near the start 0.15 more; to an agent that infers the goal from the
  last interaction, as LILI does, 0.18 and 0.27.
- ``lili/InfluenceSwitch-v0`` (:mod:`.switch`): the partner's next mode is a known function of
  its mode and of the direction of the ego's last action. Knowing the mode is worth 1.05,
  steering it to the cheap mode 0.45 more.
- ``lili/InfluenceFlee-v0`` (:mod:`.flee`): a partner on nine slots that flees one slot from
  where the ego stopped and stays home (at the start) once chased there. Knowing the slot is
  worth 1.58 per interaction, chasing it home 0.625 more; the partner is deterministic, so the
  last interaction tells the next slot exactly.
- ``lili/PointMass-v0`` (the paper's task; scripted policies in :mod:`.point_mass`).

:data:`SUITE` maps each env id to its scripted policies (name -> factory(seed) -> policy) and
their known long-run returns per interaction. Each env module's docstring gives the rules and
derives those returns; ``benchmarks/influence.py`` measures them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from lili.envs.influence import drift, flee, point_mass, switch
from lili.envs.influence.drift import InfluenceDriftEnv
from lili.envs.influence.flee import InfluenceFleeEnv
from lili.envs.influence.scripted import Rollout, ScriptedPolicy, play
from lili.envs.influence.switch import InfluenceSwitchEnv

__all__ = ["SUITE", "POLICIES", "HELD", "HELD_WHERE", "InfluenceDriftEnv", "InfluenceFleeEnv",
           "InfluenceSwitchEnv", "Rollout", "ScriptedPolicy", "play"]

POLICIES = ("no-information", "greedy", "influencer")

SUITE: dict[str, tuple[dict[str, Callable[[int], ScriptedPolicy]], dict[str, float]]] = {
    "lili/InfluenceDrift-v0": (drift.SCRIPTED, drift.KNOWN_RETURNS),
    "lili/InfluenceSwitch-v0": (switch.SCRIPTED, switch.KNOWN_RETURNS),
    "lili/InfluenceFlee-v0": (flee.SCRIPTED, flee.KNOWN_RETURNS),
    "lili/PointMass-v0": (point_mass.SCRIPTED, point_mass.KNOWN_RETURNS),
}


# The strategy ids the scripted influencer holds the partner at in the long run (the greedy
# policy drives Drift to its walls, ids 0 and 7, between returns, cycles Switch through all
# three modes and Flee through its eight slots away from home):
# the share of interactions spent there is the behavioural evidence of influence.
HELD: dict[str, tuple[int, ...]] = {
    "lili/InfluenceDrift-v0": (3, 4),  # g = -0.125, +0.125
    "lili/InfluenceSwitch-v0": (switch.MIDDLE,),
    "lili/InfluenceFlee-v0": (flee.HOME,),  # g = 0
}
HELD_WHERE: dict[str, str] = {
    "lili/InfluenceDrift-v0": "g = -0.125 or +0.125, next to the start",
    "lili/InfluenceSwitch-v0": "the middle mode",
    "lili/InfluenceFlee-v0": "home, g = 0",
}
"""What the ids of :data:`HELD` are, in words (reports name them so)."""


def make_scripted(env_id: str, name: str, seed: int = 0) -> Any:
    """The scripted policy ``name`` of the suite's env ``env_id``: one of :data:`POLICIES`,
    which every env has, or one of the env's own further references (Drift's "... (last
    interaction)" policies, see :func:`lili.envs.influence.drift.from_last_interaction`)."""
    if env_id not in SUITE:
        raise ValueError(f"env {env_id!r} has no scripted policies; allowed: {', '.join(SUITE)}")
    policies = SUITE[env_id][0]
    if name not in policies:
        raise ValueError(f"unknown scripted policy {name!r} for {env_id}; allowed: "
                         f"{', '.join(policies)}")
    return policies[name](seed)


__all__ += ["make_scripted"]
