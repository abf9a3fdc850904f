"""Scripted blockers for air hockey: the reference points of the value of influence.

Each is a policy ``policy(obs, info) -> action`` for :func:`lili.envs.influence.scripted.play`.
The two that are *told* the striker's mode (``info["strategy_id"]``) drive the paddle with a
P-controller to a point on the ego's line chosen before the shot arrives:

- :class:`GreedyBlocker` goes to the mode's *contact point*: where the noise-free shot's centre
  is when it first touches a paddle centred below it (:func:`contact_points`, simulated once per
  table). That is the best block of this shot, and the side of the paddle where the puck ends is
  left to the aim noise, so the striker's next mode is a fair coin between the table's two.
  (Meeting a bank shot at ``TARGET_X``, where it *crosses* the ego's line, would not be
  neutral: it arrives at an angle and touches the paddle 9 cm before the line, 1-2 cm to the
  wall's side of ``TARGET_X``, so the side, and with it the next mode, would be fixed.)
- :class:`InfluencingBlocker` goes ``offset`` metres beside it, so that the puck touches the
  paddle on the side it chooses, and chooses the side that sends the striker to *left* next
  time whenever the table allows: after a middle shot left of the paddle (-> left), after a
  right shot right of it (-> left), after a left shot left of it (-> middle, whose next shot it
  then turns left again). Left can never follow left in the table, so the left/middle cycle it
  drives (left every other shot) is the most left shots any blocker can get: with every shot
  blocked it earns (2 + 1) / 2 = 1.5 per interaction, against 4/3 when the modes are uniform.

:class:`CrossingBlocker` is told the mode and meets the puck where its noise-free path crosses
the ego's line (``TARGET_X``), head-on: it blocks as often as the greedy blocker but turns every
bank shot to the wall's side of the paddle, a fixed (and here lucky) influence, so it is shown
for comparison, not as the greedy reference. :class:`MiddleBlocker` holds the middle and
:class:`RandomBlocker` acts uniformly at random; neither is told the mode.
:class:`PredictingBlocker` is told only the last shot's mode and side, on a wrapped env.
"""

from __future__ import annotations

import functools
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np

from lili.envs.air_hockey.env import (
    EGO_RANGE,
    EGO_Y,
    FRAME_SKIP,
    LEFT,
    MIDDLE,
    NEXT_MODE,
    PADDLE_RADIUS,
    PUCK_RADIUS,
    RIGHT,
    TARGET_X,
    AirHockeyEnv,
)

__all__ = ["contact_points", "CrossingBlocker", "GreedyBlocker", "InfluencingBlocker",
           "MiddleBlocker", "PredictingBlocker", "RandomBlocker", "BLOCKERS",
           "READS_LAST_INTERACTION", "blocker_env", "make_blocker"]

# The side (of the paddle) where the influencer lets the puck end, per mode (see the docs).
INFLUENCE_SIDE = {LEFT: -1, MIDDLE: -1, RIGHT: +1}
GAIN_DISTANCE = 0.04  # the P-controller commands full speed beyond 4 cm from its point


@functools.lru_cache(maxsize=8)
def contact_points(bank_shots: bool = True) -> tuple[float, float, float]:
    """Puck x, per mode, where a noise-free shot's centre reaches ``EGO_Y`` + both radii.

    That is where the puck first touches a paddle centred below it. Measured by simulating the
    three shots once, the ego's paddle parked at the far wall, out of the way.
    """
    env = AirHockeyEnv(aim_noise=0.0, bank_shots=bank_shots)
    env.reset(seed=0)
    m, d = env.model, env.data
    touch_y = EGO_Y + PADDLE_RADIUS + PUCK_RADIUS
    points = []
    for mode in (LEFT, MIDDLE, RIGHT):
        env.partner.mode, env.partner.aim_offset = mode, 0.0
        env.reset()
        d.qpos[env._ego_q] = EGO_RANGE if mode != RIGHT else -EGO_RANGE
        prev = env.puck
        for k in range(50 * FRAME_SKIP):
            if k == FRAME_SKIP:  # the striker's follow-through ends, as in the env's step
                d.ctrl[env._striker_act] = 0.0
            mujoco.mj_step(m, d)
            now = env.puck
            if now[1] <= touch_y:
                w = (prev[1] - touch_y) / (prev[1] - now[1])
                points.append(float(prev[0] + w * (now[0] - prev[0])))
                break
            prev = now
        else:
            raise RuntimeError(f"the noise-free shot of mode {mode} never reached the ego")
    env.close()
    return points[0], points[1], points[2]


def _go_to(x: float, obs: np.ndarray) -> np.ndarray:
    return np.array([np.clip((x - float(obs[0])) / GAIN_DISTANCE, -1.0, 1.0)], np.float32)


class RandomBlocker:
    """Uniform random actions from its own generator (seeded, so a run replays)."""

    def __init__(self, seed: int = 0) -> None:
        self.rng = np.random.default_rng(seed)

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, size=1).astype(np.float32)


class MiddleBlocker:
    """Holds the paddle in the middle of the ego's line (blocks middle shots only)."""

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return _go_to(0.0, obs)


class GreedyBlocker:
    """Told the mode: meets the puck at the mode's contact point (see the module docs)."""

    def __init__(self, bank_shots: bool = True) -> None:
        self.points = contact_points(bool(bank_shots))

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return _go_to(self.points[int(info["strategy_id"])], obs)


class CrossingBlocker:
    """Told the mode: meets the puck head-on where its path crosses the ego's line."""

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        return _go_to(TARGET_X[int(info["strategy_id"])], obs)


class InfluencingBlocker:
    """Told the mode: meets the puck ``offset`` metres beside its contact point (see the docs)."""

    def __init__(self, offset: float = 0.04, bank_shots: bool = True) -> None:
        self.offset = float(offset)
        self.points = contact_points(bool(bank_shots))

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        mode = int(info["strategy_id"])
        # The puck ends left of the paddle (side -1) when the paddle is right of the puck.
        return _go_to(self.points[mode] - INFLUENCE_SIDE[mode] * self.offset, obs)


class PredictingBlocker:
    """Told the *last* shot's mode and side, not this one's: predicts the mode by the table.

    It plays on ``LastInteractionObservation(AirHockeyEnv(...), outcome=True)``, whose
    observation ends with the last interaction's mode one-hot, last observation, last action
    and outcome (the side of the paddle where the puck ended), and meets the predicted mode
    at its contact point, as :class:`GreedyBlocker` meets the told one; it holds the middle
    before the first outcome. The striker's next mode is the table's function of exactly that
    mode and side, apart from its lapses, so this is the ceiling of a greedy blocker that
    reads the last interaction (LILI's encoder reads no more, and sees the side only through
    the rewards): against a striker that lapses with probability p it predicts right
    1 - 2p/3 of the time.
    """

    def __init__(self, bank_shots: bool = True) -> None:
        self.points = contact_points(bool(bank_shots))

    def __call__(self, obs: np.ndarray, info: dict[str, Any]) -> np.ndarray:
        # [x_paddle, y_puck] + last mode one-hot (3) + last obs (2) + last action (1) + outcome
        if obs.shape != (9,):
            raise ValueError(f"PredictingBlocker needs the 9 numbers of LastInteractionObservation"
                             f"(AirHockeyEnv(), outcome=True); got an observation of shape "
                             f"{obs.shape}")
        last_mode, outcome = obs[2:5], float(obs[8])
        if outcome == 0.0:  # no interaction before this one
            return _go_to(0.0, obs)
        mode = NEXT_MODE[(int(np.argmax(last_mode)), -1 if outcome < 0 else 1)]
        return _go_to(self.points[mode], obs)


BLOCKERS = ("random", "middle", "crossing", "greedy", "influencer", "predictor")
READS_LAST_INTERACTION = ("predictor",)
"""The blockers of :data:`BLOCKERS` that play on ``LastInteractionObservation(env, outcome=True)``
(see :func:`blocker_env`); the others play on the env itself."""


def blocker_env(name: str, env: gym.Env) -> gym.Env:
    """The env the scripted blocker ``name`` plays on, built around ``env``."""
    if name in READS_LAST_INTERACTION:
        from lili.envs.wrappers import LastInteractionObservation

        return LastInteractionObservation(env, outcome=True)
    return env


def make_blocker(name: str, seed: int = 0, bank_shots: bool = True) -> Any:
    """One of :data:`BLOCKERS` as a policy; ``seed`` seeds the random blocker."""
    if name == "random":
        return RandomBlocker(seed)
    if name == "middle":
        return MiddleBlocker()
    if name == "crossing":
        return CrossingBlocker()
    if name == "greedy":
        return GreedyBlocker(bank_shots)
    if name == "influencer":
        return InfluencingBlocker(bank_shots=bank_shots)
    if name == "predictor":
        return PredictingBlocker(bank_shots)
    raise ValueError(f"unknown blocker {name!r}; allowed: {', '.join(BLOCKERS)}")
