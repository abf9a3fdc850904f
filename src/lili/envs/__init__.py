"""Repeated-interaction environments (see ``lili.envs.core`` for the contract)."""

from lili.envs.core import (
    ENV_ALIASES,
    Partner,
    RepeatedInteractionEnv,
    register_envs,
    resolve_env_id,
)
from lili.envs.wrappers import OracleObservation

register_envs()

__all__ = ["ENV_ALIASES", "OracleObservation", "Partner", "RepeatedInteractionEnv",
           "register_envs", "resolve_env_id"]
