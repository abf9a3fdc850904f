"""Air hockey against a mode-switching striker, simulated in MuJoCo (``lili/AirHockey-v0``)."""

from lili.envs.air_hockey.env import (
    LEFT,
    MIDDLE,
    NEXT_MODE,
    RIGHT,
    TARGET_X,
    AirHockeyEnv,
    StrikerPartner,
    aim_direction,
)

__all__ = ["AirHockeyEnv", "StrikerPartner", "aim_direction", "LEFT", "MIDDLE", "RIGHT",
           "NEXT_MODE", "TARGET_X"]
