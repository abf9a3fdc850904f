"""Driving (2D) (the paper's appendix): pass a car that merges into the lane you used last time.

Rules (the appendix) and the geometry chosen here (the appendix gives none):

- Three lanes with centres x = -1 (left), 0 (middle), +1 (right); the road is x in [-1.5, 1.5].
- The ego starts behind the other car, both in the middle lane: ego at (0, 0) moving forward
  0.4 per step, the other car at (0, 1.2) moving forward 0.1 per step. The ego controls only its
  lateral displacement: x += 0.35 * a, a in [-1, 1].
- The other car holds the middle lane for 3 steps and then merges into lane L within 2 steps
  (x = 0.5 L after step 4, L after step 5). L is the lane the ego passed in during the previous
  interaction (the sign of its final x; with ``history`` N, the majority of the last N).
- Cars collide when |dx| < 0.6 and |dy| < 0.5. The gap closes at 0.3 per step, so the ego must
  leave the middle lane by step 3 (or rear-end the other car) and therefore commits to a side
  before the other car shows where it will merge: a policy that ignores the previous interaction
  succeeds about half the time, one that models the partner always.
- Reward -1 on the first step in collision, 0 otherwise; H = 10 steps, no early termination.

Observation: (ego x, ego y, other x, other y). ``info["strategy"]`` = [L],
``info["strategy_id"]`` = 0 for left and 1 for right, ``info["success"]`` = passed without
collision.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from lili.envs.core import RepeatedInteractionEnv
from lili.envs.partners import MajorityHistory, check_partner_options

__all__ = ["Driving2DEnv", "LanePartner"]

ROAD = 1.5
EGO_SPEED, OTHER_SPEED, LATERAL = 0.4, 0.1, 0.35
OTHER_START = 1.2
MERGE_AFTER = 3
CAR_WIDTH, CAR_LENGTH = 0.6, 0.5


class LanePartner:
    """Merges into the lane the ego used last (majority of the last ``history`` interactions)."""

    strategy_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

    def __init__(self, history: int = 1) -> None:
        check_partner_options(0.0, history)
        self.votes = MajorityHistory(history)
        self.lane = 1

    def reset(self, rng: np.random.Generator) -> None:
        self.votes.clear()
        self.lane = int(rng.choice([-1, 1]))

    def strategy(self) -> np.ndarray:
        return np.array([self.lane], dtype=np.float32)

    def strategy_id(self) -> int | None:
        return 0 if self.lane < 0 else 1

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is the ego's lane: -1 (left) or +1 (right)."""
        self.lane = int(self.votes.push(int(outcome)))


class Driving2DEnv(RepeatedInteractionEnv):
    """``lili/Driving2D-v0``: pass the other car without colliding (see the module docstring)."""

    strategy_names = ("left lane", "right lane")

    def __init__(self, history: int = 1, render_mode: str | None = None) -> None:
        super().__init__(render_mode)
        self.horizon = 10
        self.partner = LanePartner(history)
        high = np.array([ROAD, 5.0, ROAD, 5.0], dtype=np.float32)
        low = np.array([-ROAD, 0.0, -ROAD, 0.0], dtype=np.float32)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.ego = np.zeros(2)
        self.other = np.array([0.0, OTHER_START])
        self.collided = False

    def _obs(self) -> np.ndarray:
        return np.concatenate([self.ego, self.other]).astype(np.float32)

    def _begin(self) -> np.ndarray:
        self.ego = np.zeros(2)
        self.other = np.array([0.0, OTHER_START])
        self.collided = False
        self._lane = self.partner.lane
        return self._obs()

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        a = float(np.clip(action[0], -1.0, 1.0))
        t = self.t + 1
        self.ego = np.array([np.clip(self.ego[0] + LATERAL * a, -ROAD, ROAD), EGO_SPEED * t])
        merge = np.clip((t - MERGE_AFTER) * 0.5, 0.0, 1.0)
        self.other = np.array([self._lane * merge, OTHER_START + OTHER_SPEED * t])
        hit = (abs(self.ego[0] - self.other[0]) < CAR_WIDTH
               and abs(self.ego[1] - self.other[1]) < CAR_LENGTH)
        reward = -1.0 if hit and not self.collided else 0.0
        self.collided = self.collided or hit
        return self._obs(), reward, False

    def _outcome(self) -> int:
        return -1 if self.ego[0] < 0 else 1

    def _success(self) -> bool:
        return not self.collided

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        from lili.envs.rendering import Canvas

        y0 = self.ego[1] - 1.0
        canvas = Canvas(150, 250, (-ROAD, ROAD), (y0, y0 + 5.0))
        for x in (-0.5, 0.5):
            canvas.vline(x, (200, 200, 200))
        canvas.rect(self.other, (CAR_WIDTH, CAR_LENGTH), (220, 60, 60))
        canvas.rect(self.ego, (CAR_WIDTH, CAR_LENGTH), (40, 90, 220))
        return canvas.image
