"""What the blocker believes: a small probe that reads the striker's next mode off the latent.

The probe is fitted when the server starts, on the blocker's own latents: it plays
``n`` interactions against the env's robot striker (the one it trained against, with the run's
env options), pairs each latent z^i with the mode of interaction i, and fits a multinomial
logistic regression (NumPy, a few hundred gradient steps) on the first 70% of them; the rest
measure its accuracy, which the page shows beside the prediction. A 2-D view of the latent
(its two principal components over the same latents) places the current z among them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lili.play.policy import Blocker, interaction_steps, make_play_env

__all__ = ["ModeProbe", "collect_latents"]


def collect_latents(blocker: Blocker, env_kwargs: dict[str, Any], n: int,
                    seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Latents z^i (n x d) and the striker's modes of interaction i (n) in the training env."""
    env = blocker.wrap(make_play_env(env_kwargs))
    game = blocker.new_game()
    zs, modes = [], []
    obs, info = env.reset(seed=seed)
    for _ in range(n):
        zs.append(game.latent)
        modes.append(int(info["strategy_id"]))
        for _t, _r, _done, _info in interaction_steps(env, game, obs):
            pass
        obs, info = env.reset()
        game.end_interaction(obs)
    env.close()
    return np.asarray(zs, np.float32), np.asarray(modes, np.int64)


class ModeProbe:
    """Softmax regression z -> mode, plus a 2-D principal-component view of the latents."""

    def __init__(self, zs: np.ndarray, modes: np.ndarray, steps: int = 500, lr: float = 0.5,
                 l2: float = 1e-3) -> None:
        if len(zs) < 10:
            raise ValueError(f"a probe needs at least 10 latents; got {len(zs)}")
        self.mean = zs.mean(0)
        self.scale = np.where(zs.std(0) < 1e-6, 1.0, zs.std(0))
        x = (zs - self.mean) / self.scale
        split = int(0.7 * len(x))
        self.w, self.b = self._fit(x[:split], modes[:split], steps, lr, l2)
        held = self._probs(x[split:]).argmax(1)
        self.accuracy = float(np.mean(held == modes[split:]))
        self.n_fit, self.n_test = split, len(x) - split
        _, _, vt = np.linalg.svd(x - x.mean(0), full_matrices=False)
        self.axes = vt[:2] if len(vt) >= 2 else np.vstack([vt, np.zeros_like(vt)])[:2]
        self.points = [{"xy": self._xy(xi), "mode": int(m)} for xi, m in zip(x, modes, strict=True)]

    @staticmethod
    def _fit(x: np.ndarray, y: np.ndarray, steps: int, lr: float, l2: float):
        w, b = np.zeros((x.shape[1], 3)), np.zeros(3)
        onehot = np.eye(3)[y]
        for _ in range(steps):
            logits = x @ w + b
            p = np.exp(logits - logits.max(1, keepdims=True))
            p /= p.sum(1, keepdims=True)
            g = (p - onehot) / len(x)
            w -= lr * (x.T @ g + l2 * w)
            b -= lr * g.sum(0)
        return w, b

    def _probs(self, x: np.ndarray) -> np.ndarray:
        logits = x @ self.w + self.b
        p = np.exp(logits - logits.max(-1, keepdims=True))
        return p / p.sum(-1, keepdims=True)

    def _xy(self, x: np.ndarray) -> list[float]:
        return [round(float(v), 3) for v in self.axes @ x]

    def belief(self, z: np.ndarray) -> dict[str, Any]:
        """Predicted probabilities of the next shot's mode and z's place in the 2-D view."""
        x = (np.asarray(z, np.float64) - self.mean) / self.scale
        return {"probs": [round(float(p), 3) for p in self._probs(x)], "xy": self._xy(x)}

    def summary(self) -> dict[str, Any]:
        """What the page shows once: the probe's held-out accuracy and the cloud of latents."""
        return {"accuracy": round(self.accuracy, 3), "n_fit": self.n_fit,
                "n_test": self.n_test, "points": self.points}

    @classmethod
    def for_blocker(cls, blocker: Blocker, env_kwargs: dict[str, Any], n: int = 150,
                    seed: int = 0) -> ModeProbe | None:
        """Fit a probe on ``n`` simulated interactions; None for an agent without a latent."""
        if blocker.latent_dim == 0:
            return None
        return cls(*collect_latents(blocker, env_kwargs, n, seed))
