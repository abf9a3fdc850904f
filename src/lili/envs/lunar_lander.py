"""Lunar Lander (the paper's appendix): land on a launchpad that the other agent moves.

Built on Gymnasium's continuous Lunar Lander (``gymnasium.envs.box2d.lunar_lander.LunarLander``
with ``continuous=True``), by composition: the env owns one lander (a thin subclass that adds
the two launchpads and draws the flags at the target) and drives it, so the physics, terrain,
engines, crash and rest detection are Gymnasium's and a Gymnasium upgrade reaches them.

The partner (the appendix): the launchpad alternates between z = (0.4, 0.2) and z = (-0.4, 0.2)
at every interaction, whatever the ego does; ``reset(seed)`` draws which one comes first.
Coordinates are those of the lander's observation (``obs[0], obs[1]``: x in units of half the
viewport width, 0 at the centre; y in units of half the viewport height, 0 where the lander
rests on Gymnasium's central helipad).

Reward, as the appendix gives it, in one of two readings (``reward``). The appendix's shaping
potential and fuel terms are

    phi(s) = -||s_pos - z||^2 - ||s_vel||^2 - |s_theta|
    fuel(a) = -0.0015 * (clip(a_0, 0, 1) + 1) - 0.0003 * clip(|a_1|, 0.5, 1)

with ``s_pos = obs[0:2]``, ``s_vel = obs[2:4]``, ``s_theta = obs[4]`` (the observation's units)
and ``a`` the action of that step. Every step that is not the last of the interaction pays

- ``reward="difference"`` (the default): ``r_t = phi(s_{t+1}) - phi(s_t) + fuel(a_t)``, the
  potential's change, which is how Gymnasium pays its own shaping (``shaping -
  prev_shaping``). The appendix's fuel coefficients 0.0015 and 0.0003 and its +-1 terminal
  reward are exactly Gymnasium's (0.30 x 0.5, 0.03, +-100) divided by 100, so this is
  Gymnasium's reward at the appendix's scale, with the appendix's squared norms.
- ``reward="potential"`` (the appendix read literally): ``r_t = phi(s_{t+1}) + fuel(a_t)``.

The two fuel terms are charged as written, on every step:
Gymnasium charges them (x100) only while an engine fires (``a_0 > 0``, ``|a_1| > 0.5``), the
appendix's formula does not make that exception. The last step of an interaction (terminated or
at the horizon) gets the terminal reward instead of the per-step one: +1 if
``||s_pos - z|| < 0.1``, otherwise ``-||s_pos - z||``. Replacing (not adding) follows
Gymnasium's lander, whose terminal rewards (+-100) also replace that step's reward, and the
appendix calls the last step's reward "the terminal reward". ``info["success"]`` is
``||s_pos - z|| < 0.1`` at the end.

Choices where the appendix is silent (and why):

- **Launchpads you can land on.** z has y = 0.2, above the stock terrain (the ground near
  x = +-0.4 is lower than Gymnasium's central helipad, which is at y = 0). To make "land on the
  launchpad" physically possible, two flat-topped mesas stand at x = +-0.4, their tops at the
  height where a lander resting on them has y = 0.2, each as wide as the success disc (0.2 in x).
  Both always exist; only the flags (drawn where Gymnasium draws its helipad flags) show which
  one is the target, so the physics do not depend on z and the ego cannot feel the target.
- **Action repeat.** Gymnasium's lander runs at 50 frames per second and lands in about 200
  frames, too many decisions per interaction for the paper's agents on 2 CPU cores. Each
  env step holds the action for ``frame_skip`` frames (default 5, i.e. 10 decisions per second)
  and an interaction lasts ``horizon`` steps (default 60, i.e. 6 s of flight). That is long
  enough: :func:`pad_controller`, a scripted PD controller that knows z (Gymnasium's heuristic
  with the target moved and retuned for 10 Hz), touches down within 0.1 of the pad in 89% of
  interactions (``end_on_contact=True``, 400 interactions over seeds 0-3, 78-94% per pad and
  seed), after 38 steps on average, mostly by Gymnasium's crash rule (the body touches the mesa
  as it sets down still drifting or tilted). Played to the horizon it is still within 0.1 at the
  end in about 40%: it often bounces or topples off the mesa, or has not settled by step 60
  (63% with ``horizon=100``). So success at the end is a strict measure here; the return is the
  smoother one.
- **End of an interaction** (``end_on_contact``). With ``True`` (the default, Gymnasium's
  ends) it ends when Gymnasium's lander crashes (its body touches the ground) or comes to
  rest. With ``False`` it lasts ``horizon`` steps whatever happens: a lander that crashed or
  came to rest lies there until the horizon. Either way it also ends when the lander leaves the
  screen sideways (|x| >= 1) or a state component leaves Gymnasium's observation box (flown off
  the top, spun beyond 2 pi; the observation is clipped into the box then).
- **Which reading is the default, and why.** Mean return per interaction (success) of four
  scripted policies, 50 interactions x seeds 0-1 each
  (``python benchmarks/lunar_lander_scripted.py``):

  ==========================  ============  ============  ============  ============
  reward, end_on_contact      to the pad    to centre     wrong pad     drop
  ==========================  ============  ============  ============  ============
  difference, True (default)  +2.33 (87%)   +0.34 (6%)    -0.04 (0%)    -2.12 (13%)
  difference, False           +0.76 (35%)   +0.40 (1%)    -1.38 (1%)    -0.02 (7%)
  potential, True             -35.60 (87%)  -32.88 (6%)   -44.92 (0%)   -32.01 (13%)
  potential, False            -45.50 (35%)  -66.98 (1%)   -72.94 (1%)   -84.24 (7%)
  ==========================  ============  ============  ============  ============

  ("to the pad" is :func:`pad_controller` told this interaction's pad, "to centre" the same
  controller landing on the ground between the mesas, "wrong pad" it told the other pad,
  "drop" engines off from the start.) Read literally, the potential is a per-step *cost* of
  at least the squared distance to the pad, so with Gymnasium's ends dropping at once earns
  the most. Played to the horizon it ranks the four as the task intends too (the default
  before issue 14), but every return is then mostly the price of the path: the flight down
  from the top of the screen and the steps spent on the ground (the pad lander's -45.5 is
  46.5 below the +1 of a perfect landing, and how fast it got down matters as much as where),
  and SAC, LILI and the Oracle trained under it for 2000 interactions learned to sit in the
  middle, not to land (``docs/journal/2026-11-to-12.md``). Paid as a difference, the per-step
  terms telescope to ``phi(s_{T-1}) - phi(s_0)`` plus fuel (the last step pays the terminal
  reward instead): potential-based shaping (Ng et al. 1999) up to that last step, which keeps
  the sparse task's preferences (land on the pad: +1) nearly intact, and the ranking is
  the task's: pad, centre, wrong pad, drop, with landing worth 2 more than the next best. Played
  to the horizon the difference reading ranks the drop above the wrong pad (a lander that fell
  and lies still stops paying, one that toppled off a mesa keeps losing potential), so the
  default pairs it with Gymnasium's ends. The old game (before issue 14) is
  ``reward="potential", end_on_contact=False``. Across interactions, the difference reading
  also removes the reason that drove agents that bootstrap across the boundary (LILI) to hover
  to the horizon under the literal reading with early ends: the next interaction's value no
  longer carries the flight's large cost, so ending an interaction sooner does not look worse.
  It now looks better: each interaction to come is worth about +2.3, and under the paper's
  per-step discount an agent that bootstraps across the boundary (LILI, SAC, the Oracle)
  reaches their value sooner by ending sooner, so they land in about 24 steps where LILI (no
  influence) takes about 40, and LILI lands less often. ``AgentConfig(boundary_discount=
  "horizon")`` removes that pay (``docs/journal/2026-11-to-12.md``, "Lunar Lander").
- **Terrain and initial push.** Gymnasium draws them from its lander's ``np_random``. At every
  interaction the lander is reset with a seed drawn from this env's ``np_random``, so
  ``reset(seed)`` replays the whole sequence (terrain, push, engine dispersion, pads).

Observation: the lander's own 8-dim state (x, y, vx, vy, angle, angular velocity, two leg
contacts), never the pad. ``info["strategy"]`` = z (float32, shape (2,)),
``info["strategy_id"]`` = 0 for the left pad (x = -0.4) and 1 for the right pad (x = +0.4).
The partner has no options: its rule depends on time only, so the noise and history variants of
the other envs have no meaning here.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.envs.box2d import lunar_lander as gym_ll

from lili.envs.core import RepeatedInteractionEnv

__all__ = ["LunarLanderEnv", "AlternatingPadPartner", "PadLander", "PADS", "REWARDS",
           "pad_controller"]

PADS = np.array([[-0.4, 0.2], [0.4, 0.2]])
SUCCESS_RADIUS = 0.1
REWARDS = ("potential", "difference")  # the two readings of the appendix's per-step reward
# The world (Box2D) frame of Gymnasium's lander: width W, height H, and the factors that turn
# world coordinates into the observation's.
_W = gym_ll.VIEWPORT_W / gym_ll.SCALE
_H = gym_ll.VIEWPORT_H / gym_ll.SCALE
_HALF_W, _HALF_H = _W / 2, _H / 2
PAD_HALF_WIDTH = SUCCESS_RADIUS * _HALF_W  # the mesa top spans the success disc in x


class AlternatingPadPartner:
    """Picks the launchpad: x = -0.4 and x = +0.4 in turn (y = 0.2), whatever the ego does."""

    strategy_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)

    def __init__(self) -> None:
        self.pad = 0

    def reset(self, rng: np.random.Generator) -> None:
        self.pad = int(rng.integers(0, 2))

    def strategy(self) -> np.ndarray:
        return PADS[self.pad].astype(np.float32)

    def strategy_id(self) -> int | None:
        return self.pad

    def update(self, outcome: Any, rng: np.random.Generator) -> None:
        """Switch pads; ``outcome`` (the lander's final position) does not matter."""
        self.pad = 1 - self.pad


class PadLander(gym_ll.LunarLander):
    """Gymnasium's continuous lander with two landing mesas and the flags at the target pad.

    ``target`` (0 or 1, an index into :data:`PADS`) only changes where the flags are drawn.
    """

    def __init__(self, render_mode: str | None = None) -> None:
        super().__init__(render_mode=render_mode, continuous=True)
        self.target = 0
        self.mesas: list[Any] = []

    def reset(self, *, seed: int | None = None, options: dict | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        out = super().reset(seed=seed, options=options)
        # Gymnasium's reset builds a fresh Box2D world (the old mesas die with the old one).
        self.mesas = [self._make_mesa(pad) for pad in PADS]
        # Drawn first, so that the lander and its flames show in front of them.
        self.drawlist = self.mesas + [self.lander] + self.legs
        return out

    def _make_mesa(self, pad: np.ndarray) -> Any:
        x, top = self.pad_world(pad)
        body = self.world.CreateStaticBody(
            shapes=gym_ll.polygonShape(vertices=[
                (x - PAD_HALF_WIDTH, 0.0), (x + PAD_HALF_WIDTH, 0.0),
                (x + PAD_HALF_WIDTH, top), (x - PAD_HALF_WIDTH, top)]),
        )
        body.fixtures[0].friction = 0.1  # the terrain's friction
        body.color1 = body.color2 = (255, 255, 255)  # the terrain's colour
        return body

    def pad_world(self, pad: np.ndarray) -> tuple[float, float]:
        """World x of a pad's centre and the height of its mesa's top.

        The lander rests on flat ground at height ``helipad_y`` with observation y = 0, so a top
        at ``helipad_y + y * H / 2`` lets it rest at observation y = ``y``.
        """
        return _HALF_W + float(pad[0]) * _HALF_W, self.helipad_y + float(pad[1]) * _HALF_H

    def render(self) -> np.ndarray | None:
        # Gymnasium draws its flags at helipad_x1/x2 and height helipad_y; point them at the
        # target mesa for the duration of the call (step() reads helipad_y for the observation).
        saved = self.helipad_x1, self.helipad_x2, self.helipad_y
        x, top = self.pad_world(PADS[self.target])
        self.helipad_x1, self.helipad_x2, self.helipad_y = (
            x - PAD_HALF_WIDTH, x + PAD_HALF_WIDTH, top)
        try:
            return super().render()
        finally:
            self.helipad_x1, self.helipad_x2, self.helipad_y = saved


class LunarLanderEnv(RepeatedInteractionEnv):
    """``lili/LunarLander-v0``: land on the launchpad the partner picks (see the module docs).

    Args:
        frame_skip: Gymnasium frames (1/50 s each) per env step; the action is held for all of
            them. An integer >= 1.
        horizon: the most env steps in one interaction. An integer >= 1.
        end_on_contact: end the interaction when Gymnasium's lander crashes (its body touches
            the ground) or comes to rest (True, the default, as Gymnasium), or play on to the
            horizon (False).
        reward: ``"difference"`` (the default: the appendix's potential paid as its change
            per step, as Gymnasium pays its shaping) or ``"potential"`` (the appendix read
            literally). See "Which reading is the default, and why" in the module docs.
        render_mode: ``"rgb_array"`` or None.
    """

    strategy_names = ("left pad", "right pad")

    def __init__(
        self, frame_skip: int = 5, horizon: int = 60, end_on_contact: bool = True,
        reward: str = "difference", render_mode: str | None = None,
    ) -> None:
        super().__init__(render_mode)
        if not isinstance(reward, str) or reward not in REWARDS:
            raise ValueError(
                f"reward={reward!r} is invalid; allowed: {', '.join(map(repr, REWARDS))}")
        self.reward = reward
        if not isinstance(end_on_contact, (bool, np.bool_)):
            raise ValueError(f"end_on_contact={end_on_contact!r} is invalid; allowed: True, False")
        self.end_on_contact = bool(end_on_contact)
        for name, value in (("frame_skip", frame_skip), ("horizon", horizon)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name}={value!r} is invalid; allowed: an integer >= 1")
        self.frame_skip = int(frame_skip)
        self.horizon = int(horizon)
        self.metadata = dict(self.metadata, render_fps=max(1, round(gym_ll.FPS / frame_skip)))
        self.partner = AlternatingPadPartner()
        self.lander = PadLander(render_mode=render_mode)
        self.observation_space = self.lander.observation_space
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._state = np.zeros(8, dtype=np.float32)
        self._pad = PADS[0]
        self._potential = 0.0

    def _begin(self) -> np.ndarray:
        self._pad = PADS[self.partner.pad]
        self.lander.target = self.partner.pad
        obs, _ = self.lander.reset(seed=int(self.np_random.integers(2**31)))
        self._state = np.clip(obs, self.observation_space.low, self.observation_space.high)
        self._potential = self.potential(self._state, self._pad)
        return self._state.copy()

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        action = np.clip(action, -1.0, 1.0)
        for _ in range(self.frame_skip):
            # Gymnasium's terminated flag means a crash, rest or |x| >= 1 (off the screen
            # sideways); only the last always ends the interaction here.
            obs, _, contact, _, _ = self.lander.step(action)
            ended = (contact and self.end_on_contact) or abs(obs[0]) >= 1.0
            if ended:
                break
        inside = self.observation_space.contains(obs)
        self._state = np.clip(obs, self.observation_space.low, self.observation_space.high)
        terminated = ended or not inside
        if terminated or self.t + 1 >= self.horizon:
            reward = self.terminal_reward(self._state, self._pad)
        elif self.reward == "potential":
            reward = self.step_reward(self._state, action, self._pad)
        else:
            potential = self.potential(self._state, self._pad)
            reward = potential - self._potential + self.fuel_reward(action)
            self._potential = potential
        return self._state.copy(), reward, terminated

    @staticmethod
    def potential(state: np.ndarray, pad: np.ndarray) -> float:
        """The appendix's shaping potential: -||s_pos - z||^2 - ||s_vel||^2 - |s_theta|."""
        s = np.asarray(state, dtype=np.float64)
        return float(-np.sum((s[0:2] - pad) ** 2) - np.sum(s[2:4] ** 2) - abs(s[4]))

    @staticmethod
    def fuel_reward(action: np.ndarray) -> float:
        """The appendix's two fuel terms (charged on every step, as written)."""
        a = np.asarray(action, dtype=np.float64)
        return float(-0.0015 * (np.clip(a[0], 0.0, 1.0) + 1.0)
                     - 0.0003 * np.clip(abs(a[1]), 0.5, 1.0))

    @staticmethod
    def step_reward(state: np.ndarray, action: np.ndarray, pad: np.ndarray) -> float:
        """The appendix's per-step reward read literally: potential plus fuel terms."""
        return LunarLanderEnv.potential(state, pad) + LunarLanderEnv.fuel_reward(action)

    @staticmethod
    def terminal_reward(state: np.ndarray, pad: np.ndarray) -> float:
        """The appendix's terminal reward: +1 within 0.1 of the pad, else minus the distance."""
        dist = float(np.linalg.norm(np.asarray(state[0:2], dtype=np.float64) - pad))
        return 1.0 if dist < SUCCESS_RADIUS else -dist

    def _outcome(self) -> np.ndarray:
        return self._state[0:2].copy()

    def _success(self) -> bool:
        dist = np.linalg.norm(self._state[0:2].astype(np.float64) - self._pad)
        return bool(dist < SUCCESS_RADIUS)

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        return self.lander.render()

    def close(self) -> None:
        self.lander.close()
        super().close()


def pad_controller(obs: np.ndarray, pad: np.ndarray) -> np.ndarray:
    """A scripted controller that knows the pad: Gymnasium's heuristic lander, retargeted.

    It tilts towards the pad (PD on x and vx), holds a height that falls linearly to the pad's
    as it closes in (1.5 per unit of x-distance, so it stays clear of the mesa's edge until it
    is above the top) and, once a leg touches, only brakes its fall. The gains were tuned for
    the default 10 decisions per second. It is the reference that shows the task is solvable
    within the default horizon (see the module docstring); no agent uses it.
    """
    s = np.asarray(obs, dtype=np.float64)
    dx = s[0] - float(pad[0])
    angle_target = np.clip(dx + s[2], -0.4, 0.4)
    height_target = float(pad[1]) + 1.5 * abs(dx)
    angle_todo = (angle_target - s[4]) * 0.5 - s[5]
    height_todo = (height_target - s[1]) * 0.5 - 0.3 * s[3]
    if s[6] or s[7]:
        angle_todo, height_todo = 0.0, -0.5 * s[3]
    return np.clip([height_todo * 20 - 1, -angle_todo * 20], -1, 1).astype(np.float32)
