"""A repeated-interaction env written as a plain ``gymnasium.Env`` (no lili base class).

One episode is one interaction. The partner (a hider) sits at -0.5 or +0.5 for a whole
interaction and, between interactions, moves to the side opposite to where the ego ended.
Everything lili needs beyond Gymnasium's API is marked "lili:".
"""

import gymnasium as gym
import numpy as np
from gymnasium import spaces


class PlainHideAndSeek(gym.Env):
    metadata = {"render_modes": []}

    def __init__(self):
        self.observation_space = spaces.Box(-1, 1, (1,), np.float32)
        self.action_space = spaces.Box(-1, 1, (1,), np.float32)
        self.horizon = 5  # lili: the most steps an interaction takes
        self.strategy_space = spaces.Box(-1, 1, (1,), np.float32)  # lili: info["strategy"]
        self.interaction = -1

    def _info(self):  # lili: the partner's true strategy, a label, the interaction index
        return {"strategy": np.array([self.spot], np.float32),
                "strategy_id": int(self.spot > 0), "interaction": self.interaction}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        if seed is not None or self.interaction < 0:  # lili: reset(seed) restarts the sequence
            self.spot, self.interaction = float(self.np_random.choice([-0.5, 0.5])), 0
        else:  # lili: reset() goes on with the next interaction, the partner already moved
            self.interaction += 1
        self.x, self.t = 0.0, 0
        return np.array([self.x], np.float32), self._info()

    def step(self, action):
        self.x = float(np.clip(self.x + 0.25 * float(action[0]), -1, 1))
        self.t += 1
        reward = -abs(self.x - self.spot)
        info = self._info()
        done = self.t == self.horizon
        if done:  # lili: the partner reacts to the interaction when it ends
            info["success"] = abs(self.x - self.spot) < 0.1
            self.spot = -0.5 if self.x > 0 else 0.5
        return np.array([self.x], np.float32), reward, done, False, info
