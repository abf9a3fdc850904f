"""The Oracles: SAC told the partner's strategy, the upper bound LILI is read against."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from lili.agents.registry import register
from lili.agents.sac import SAC
from lili.config import dataclass_options

__all__ = ["Oracle", "LastInteractionOracle", "OracleLastOptions"]


@dataclass(frozen=True)
class OracleLastOptions:
    """The last-interaction Oracle's options, ``AgentConfig.extra["oracle-last"]``: ``outcome``
    (see :class:`LastInteractionOracle`)."""

    outcome: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.outcome, bool):
            raise ValueError(f"config extra.oracle-last.outcome={self.outcome!r} is invalid; "
                             "allowed: true or false")


class Oracle(SAC):
    """SAC on :class:`~lili.envs.OracleObservation`: it sees the partner's true strategy.

    Because the first observation of interaction i+1 carries z^{i+1} and the critic bootstraps
    across the boundary, the Oracle can learn to influence too: it bounds LILI from above.
    """

    algo = "oracle"
    needs_strategy = True

    def wrap_env(self, env: gym.Env) -> gym.Env:
        from lili.envs.wrappers import OracleObservation

        return env if isinstance(env, OracleObservation) else OracleObservation(env)

    def wrap_jax_env(self, env: Any) -> Any:
        from lili.envs.jax.wrappers import StrategyObservation

        return env if isinstance(env, StrategyObservation) else StrategyObservation(env)


class LastInteractionOracle(Oracle):
    """SAC on :class:`~lili.envs.wrappers.LastInteractionObservation`: told the partner's
    strategy in the *last* interaction and how that interaction ended, not the current
    strategy. A diagnostic, not a paper baseline: it is what LILI's encoder (which reads only
    the last interaction) could at best tell LILI's policy, so LILI below it falls short in its
    latent or in learning to use it; it below the Oracle means the last interaction does not
    determine the partner's next strategy or acting on it is harder to learn.

    Option (``AgentConfig.extra["oracle-last"]``): ``outcome`` (default False) also tells it the
    last interaction's ``info["outcome"]``, what the partner reacted to, where the last
    observation leaves it out (air hockey's side of the paddle).
    """

    algo = "oracle-last"

    def wrap_env(self, env: gym.Env) -> gym.Env:
        from lili.envs.wrappers import LastInteractionObservation

        if isinstance(env, LastInteractionObservation):
            return env
        return LastInteractionObservation(env, outcome=self._options().outcome)

    def wrap_jax_env(self, env: Any) -> Any:
        from lili.envs.jax.wrappers import LastInteractionObservation

        if isinstance(env, LastInteractionObservation):
            return env
        return LastInteractionObservation(env, outcome=self._options().outcome)

    def _options(self) -> OracleLastOptions:
        return dataclass_options(self.config, "oracle-last", OracleLastOptions)


register("oracle", Oracle)
register("oracle-last", LastInteractionOracle, options=OracleLastOptions)
