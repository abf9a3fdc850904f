"""The striker's side of the play page: a person's (or a bot's) aim turned into an air hockey shot.

The env's own striker (:class:`lili.envs.air_hockey.StrikerPartner`) picks a mode from the
appendix's table and adds aim noise; the env then strikes along the mode's aim direction rotated
by ``partner.aim_offset``. Here the *person* picks the direction instead: :class:`AimedStriker`
is a partner object that takes an aim angle before each shot and presents it to the env as the
mode whose aim is nearest plus the offset from that mode's aim. Physics, rules and observation
are the env's own; only who chooses the direction changes.

Angles are radians from straight down the table (towards the ego), positive towards the ego's
right (+x): the shot's direction is ``(sin(aim), -cos(aim))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from lili.envs.air_hockey.env import MODE_NAMES, NEXT_MODE, aim_direction

__all__ = ["AIM_LIMIT", "AimedStriker", "BotStriker", "BotConfig", "mode_aims", "nearest_mode",
           "MODE_NAMES"]

# Beyond about 0.8 rad the puck bounces off both side walls and needs 22 or more of the
# horizon's 30 decisions; past 1.05 rad it no longer arrives within the horizon at all.
AIM_LIMIT = 0.8


def mode_aims(bank_shots: bool = True) -> tuple[float, float, float]:
    """The aim angle of each mode's noise-free shot (left, middle, right)."""
    out = []
    for mode in range(3):
        d = aim_direction(mode, bank_shots)
        out.append(float(np.arctan2(d[0], -d[1])))
    return tuple(out)  # type: ignore[return-value]


def nearest_mode(aim: float, bank_shots: bool = True) -> int:
    """The mode whose noise-free aim is nearest to ``aim`` (the mode a shot is recorded as)."""
    return int(np.argmin([abs(aim - a) for a in mode_aims(bank_shots)]))


class AimedStriker:
    """A partner whose next shot is set from outside with :meth:`aim`.

    It satisfies the env's partner protocol: ``strategy()`` is the one-hot of the nearest mode
    (so ``info["strategy"]`` means what it means in training) and ``update`` only records where
    the puck ended (``last_outcome``: -1 left of the ego's paddle, +1 right), because the person,
    not a table, decides the next shot.
    """

    strategy_space = spaces.Box(0.0, 1.0, shape=(3,), dtype=np.float32)

    def __init__(self, bank_shots: bool = True) -> None:
        self.bank_shots = bool(bank_shots)
        self._aims = mode_aims(self.bank_shots)
        self.mode = 1
        self.aim_offset = 0.0
        self.last_outcome: int | None = None

    def aim(self, angle: float) -> int:
        """Set the next shot's direction; return the mode it is recorded as."""
        angle = float(angle)
        if not np.isfinite(angle) or abs(angle) > AIM_LIMIT:
            raise ValueError(f"aim={angle!r} is invalid; allowed: radians in "
                             f"[-{AIM_LIMIT}, {AIM_LIMIT}]")
        self.mode = nearest_mode(angle, self.bank_shots)
        # The env rotates the mode's aim direction by aim_offset (counter-clockwise), and a
        # counter-clockwise rotation adds to this angle convention's value.
        self.aim_offset = angle - self._aims[self.mode]
        return self.mode

    def reset(self, rng: np.random.Generator) -> None:
        """Keep the aim already set: the person chose the first shot, not the env's generator."""
        self.last_outcome = None

    def strategy(self) -> np.ndarray:
        one_hot = np.zeros(3, dtype=np.float32)
        one_hot[self.mode] = 1.0
        return one_hot

    def strategy_id(self) -> int:
        return self.mode

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        self.last_outcome = int(outcome)


@dataclass(frozen=True)
class BotConfig:
    """A human-like striker for headless sessions.

    Attributes:
        aim_noise: standard deviation of each shot's aim error in radians (the env's robot
            striker uses 0.02; 0.05 is about 8 cm at the ego's line, a careful person).
        lapse: probability that a shot ignores the rule and picks a mode at random (a person
            does not follow a table every time).
        reaction: probability that the bot reacts to the last shot at all; otherwise it repeats
            its last mode (a person who has not yet noticed where the ego blocked).
    """

    aim_noise: float = 0.05
    lapse: float = 0.1
    reaction: float = 1.0

    def __post_init__(self) -> None:
        for name, value, hi in (("aim_noise", self.aim_noise, 0.5), ("lapse", self.lapse, 1.0),
                                ("reaction", self.reaction, 1.0)):
            if (isinstance(value, bool) or not isinstance(value, (int, float))
                    or not np.isfinite(value) or not 0 <= value <= hi):
                raise ValueError(f"bot {name}={value!r} is invalid; allowed: a number in "
                                 f"[0, {hi}]")


class BotStriker:
    """Aims away from where the ego blocked last time, as the paper's human and robot did.

    The next mode follows the env's table (``NEXT_MODE``: where the puck ended relative to the
    ego's paddle sends the striker to the ego's weak side), then :class:`BotConfig`'s lapses,
    missed reactions and aim noise make it human-like. Deterministic from ``seed``.
    """

    def __init__(self, config: BotConfig | None = None, seed: int = 0,
                 bank_shots: bool = True) -> None:
        self.config = config or BotConfig()
        self.rng = np.random.default_rng(seed)
        self.aims = mode_aims(bank_shots)
        self.mode = int(self.rng.integers(0, 3))

    def next_aim(self) -> float:
        """The angle of the next shot (its intended mode's aim plus aim noise)."""
        noise = float(self.rng.normal(0.0, 1.0)) * self.config.aim_noise
        return float(np.clip(self.aims[self.mode] + noise, -AIM_LIMIT, AIM_LIMIT))

    def observe(self, mode: int, outcome: int) -> None:
        """React to a finished shot recorded as ``mode`` whose puck ended on side ``outcome``."""
        # Draw every number on every shot so that one setting cannot shift the others' stream.
        react, lapse, pick = self.rng.random(), self.rng.random(), int(self.rng.integers(0, 3))
        nxt = NEXT_MODE[(int(mode), int(outcome))] if react < self.config.reaction else int(mode)
        self.mode = pick if lapse < self.config.lapse else nxt
