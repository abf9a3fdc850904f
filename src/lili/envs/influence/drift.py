"""``lili/InfluenceDrift-v0``: a goal that drifts toward the side where the ego ended.

Rules. The ego starts at x = 0, moves by ``0.5 * a`` per step (``a`` in [-1, 1], x clipped to
[-1, 1]) for H = 4 steps and pays ``-|x - g|`` per step. The partner's goal g lies on the grid
{+-0.125, +-0.375, +-0.625, +-0.875}. After each interaction, with probability ``returns``
(default 0.05) the partner loses interest and goes back to one of the two goals next to the
start, +-0.125, chosen at random; otherwise g moves one grid step (0.25) toward the side of 0
where the ego ended (right when ``x_end >= 0``, left otherwise), clipped to the outermost
points. The first g is drawn uniformly from the grid.

Why the partner returns. Without it (``returns=0``, the first version of this env) the walls
are a trap no learner escapes: whatever an agent does in its first few interactions pushes g
to one wall, and a greedy response keeps it there, so in 2000 interactions SAC, LILI and the
Oracle all saw g = +-0.875 and nothing else after interaction ~10 (3 seeds each,
``benchmarks/results/runs/s10/influence``): none can learn the value of states it never
visits, and the env measured exploration, not influence. Returning to the start every ~20
interactions shows every agent the states where influence pays, while keeping the wall
costly to leave, so the greedy response still drifts out.

Known optima (long-run return per interaction, p = ``returns``; derivations, then
``benchmarks/influence.py`` measures them). Each return restarts a renewal cycle at +-0.125
whose length is geometric with mean 1/p, so a policy whose k-th interaction after a return
costs c_k earns ``-(p * sum_{k<m} (1-p)^k c_k + c_tail (1-p)^m)`` when c_k = c_tail from
k = m on.

- **greedy** (told g, best for this interaction): run to g (one step of 0.5 reaches |g| <=
  0.5, two steps the rest) and stay; it ends on g's side, so g drifts out: 0.125, 0.375
  (both free), 0.625 (the first step pays 0.125), then the wall (0.375 each):
  ``-(0.125 p (1-p)^2 + 0.375 (1-p)^3)`` = **-0.327** at p = 0.05 (-0.375 at p = 0).
- **no information** (not told g; a fixed trajectory, as a deterministic policy of x alone
  is here, e.g. SAC's): the scripted one runs to the right wall's goal and stays, x = 0.5,
  0.875, 0.875, 0.875 (the best fixed trajectory once g sits at the wall, where it spends
  most of its time); after a return to +0.125 it pays 2.625, 1.625, 0.875, then 0.375; after
  one to -0.125 3.625 first: **-0.646** at p = 0.05 (-0.375 at p = 0, where it is the best
  fixed trajectory and knowing g is worth nothing).
- **influencer** (told g): hold g at +-0.125, one step from the start, by ending each
  interaction just across 0 from g, so g flips between +0.125 and -0.125 (returns land
  there too). Every interaction then costs only its last step, ``|x_end - g|`` > 0.125, so
  the optimum is -0.125 (a supremum: ending exactly on 0 counts as right). Any other cycle
  must visit |g| >= 0.375 and end there on the far side of 0, costing >= 0.375 every other
  interaction (>= 0.1875 on average). The scripted influencer ends 0.05 across 0 (a margin a
  learned policy needs too): **-0.175** for every p, worth 0.152 per interaction over greedy
  at p = 0.05 (0.2 at p = 0). It also crosses back from the walls; for p > 0 waiting there
  for the partner to return earns the same long-run return (once at +-0.125 the partner
  never leaves), so only the states next to the start decide it, and those are the states
  "held" counts (:data:`lili.envs.influence.HELD`). Greedy spends about p of its
  interactions there, the influencer all of them.

What the last interaction allows. The greedy and influencing policies above are *told* g^i, as
the Oracle is. An agent that infers g^i from interaction i-1 (LILI's encoder reads only that)
can know the drift but not a return, which nothing before it shows, so after each return it
acts on the wrong goal once. Scripted with exactly that knowledge
(:func:`from_last_interaction`), measured by ``benchmarks/influence.py`` (not derived): greedy
**-0.47**, influencer **-0.20**. Greedy loses most (after a wrong guess it runs the full
distance the wrong way, and a return it misses leaves g drifting out again), the influencer
little (a return lands on +-0.125, where it holds g anyway, half the time on the side it
predicted). So influence is worth about 0.27 to such an agent, and the influencer told g lies
only 0.025 above what it can reach.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from lili.envs.influence.line import LineEnv, check_horizon, check_probability, move_to

__all__ = ["InfluenceDriftEnv", "DriftPartner", "GOALS", "NEAR_START", "RETURNS", "SCRIPTED",
           "KNOWN_RETURNS", "known_returns", "renewal_return", "from_last_interaction"]

GOALS = np.array([-0.875, -0.625, -0.375, -0.125, 0.125, 0.375, 0.625, 0.875])
NEAR_START = (3, 4)  # the ids of g = -0.125, +0.125, where a returning partner goes
SPEED = 0.5
RETURNS = 0.05  # the default probability that the partner goes back near the start
MARGIN = 0.05  # how far across 0 the scripted influencer ends


def drifted(index: int, outcome: int) -> int:
    """The goal id one grid step toward ``outcome``'s side (-1 left, +1 right), held at the
    outermost points: the partner's move when it does not return."""
    return int(np.clip(index + outcome, 0, len(GOALS) - 1))


class DriftPartner:
    """A goal on :data:`GOALS` that moves one point toward the side where the ego ended, or
    with probability ``returns`` goes back to one of :data:`NEAR_START`."""

    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self, returns: float = RETURNS) -> None:
        self.returns = returns
        self.index = 0

    def reset(self, rng: np.random.Generator) -> None:
        self.index = int(rng.integers(0, len(GOALS)))

    def goal(self) -> float:
        return float(GOALS[self.index])

    def strategy(self) -> np.ndarray:
        return np.array([self.goal()], np.float32)

    def strategy_id(self) -> int | None:
        return self.index

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is the side of 0 where the ego ended: -1 left, +1 right."""
        # The draws depend only on the partner's own generator, never on ``outcome``, so the
        # ego's actions cannot shift the partner's later randomness.
        if rng.random() < self.returns:
            self.index = NEAR_START[int(rng.integers(2))]
        else:
            self.index = drifted(self.index, outcome)


class InfluenceDriftEnv(LineEnv):
    """``lili/InfluenceDrift-v0`` (see the module docstring).

    ``horizon``: an integer >= 3. ``returns``: the probability in [0, 1] that the partner goes
    back near the start after an interaction (0 gives the first version of the env, whose
    walls trap every learner).
    """

    def __init__(self, horizon: int = 4, returns: float = RETURNS,
                 render_mode: str | None = None) -> None:
        # Two steps reach every goal; the influencer needs one more to cross back.
        super().__init__(check_horizon(horizon, 3), SPEED, render_mode)
        self.partner = DriftPartner(check_probability(returns, "returns"))

    def goal(self) -> float:
        return self.partner.goal()

    def _outcome(self) -> int:
        return -1 if self.x < 0 else 1


def greedy(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Told g: run to it and stay."""
    return move_to(float(obs[0]), float(info["strategy"][0]), SPEED)


def no_information(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
    """Not told g: run to the right wall's goal and stay (the best fixed trajectory)."""
    return move_to(float(obs[0]), float(GOALS[-1]), SPEED)


def influencer(obs: np.ndarray, info: dict[str, Any], horizon: int = 4) -> np.ndarray:
    """Told g: stay as near g as it can while still ending ``MARGIN`` across 0 from it."""
    g = float(info["strategy"][0])
    end = -np.sign(g) * MARGIN
    reach = SPEED * (horizon - info["t"] - 1)  # how far the end may be after this step
    return move_to(float(obs[0]), float(np.clip(g, end - reach, end + reach)), SPEED)


def from_last_interaction(told: Any) -> Any:
    """``told`` (a policy told g) handed instead the g that the last interaction predicts:
    the last g moved one step toward the side where the ego ended, i.e. everything that
    interaction reveals (its rewards give g, its last state the side), but not a return of
    the partner, which nothing before it shows. Before any interaction it plays
    :func:`no_information`. The best that any agent inferring g^i from tau^{i-1} (LILI, whose
    encoder reads only the last interaction) can hope to do with ``told``'s strategy.
    Stateful: one instance per rollout."""
    memory: dict[str, float | None] = {"g": None, "end": 0.0, "predicted": None}

    def policy(obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        if info["t"] == 0 and memory["g"] is not None:
            index = int(np.argmin(np.abs(GOALS - memory["g"])))
            memory["predicted"] = float(GOALS[drifted(index, 1 if memory["end"] >= 0 else -1)])
        # Within the interaction its rewards reveal this g; it is only used after it ends.
        memory["g"] = float(info["strategy"][0])
        if memory["predicted"] is None:
            action = no_information(obs, info)
        else:
            action = told(obs, {**info, "strategy": np.array([memory["predicted"]], np.float32)})
        memory["end"] = float(np.clip(obs[0] + SPEED * action[0], -1.0, 1.0))
        return action

    return policy


# name -> factory(seed) -> policy(obs, info) (deterministic: seed unused). The first three are
# the suite's (:data:`lili.envs.influence.POLICIES`); the last two are the reachable bounds of
# an agent that infers g from the last interaction (:func:`from_last_interaction`).
SCRIPTED = {"no-information": lambda seed: no_information, "greedy": lambda seed: greedy,
            "influencer": lambda seed: influencer,
            "greedy (last interaction)": lambda seed: from_last_interaction(greedy),
            "influencer (last interaction)": lambda seed: from_last_interaction(influencer)}


def renewal_return(costs: list[float], tail: float, p: float) -> float:
    """Long-run return per interaction of a policy whose k-th interaction after each return of
    the partner costs ``costs[k]``, and ``tail`` from ``len(costs)`` on (module docstring)."""
    m = len(costs)
    return -(p * sum((1 - p) ** k * c for k, c in enumerate(costs)) + tail * (1 - p) ** m)


def known_returns(p: float = RETURNS) -> dict[str, float]:
    """The scripted policies' long-run returns per interaction at ``returns=p`` (derived in the
    module docstring; returns land on +-0.125 with equal chance, hence the averages)."""
    no_info = 0.5 * (renewal_return([2.625, 1.625, 0.875], 0.375, p)
                     + renewal_return([3.625, 2.625, 1.625, 0.875], 0.375, p))
    return {"no-information": no_info, "greedy": renewal_return([0.0, 0.0, 0.125], 0.375, p),
            "influencer": renewal_return([], 0.175, p)}


# Long-run return per interaction of each scripted policy under the default env.
KNOWN_RETURNS = known_returns()
