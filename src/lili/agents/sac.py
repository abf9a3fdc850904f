"""SAC over interactions, the paper's baseline without a latent, and the names this module
has always exported.

:class:`SAC` is the facade (:class:`lili.agents.facade.AgentFacade`) over the plain
:class:`lili.agents.core.SACCore`: ``SAC(env).learn(n).save(path)``, ``predict``,
``SAC.load(path, env)``. The core and the registry have modules of their own
(:mod:`lili.agents.core`, :mod:`lili.agents.registry`; the Oracles :mod:`lili.agents.oracle`);
the names of the first two are re-exported here for code written against earlier releases.
"""

from __future__ import annotations

from typing import ClassVar

from lili.agents.base import ActingState, CheckpointError
from lili.agents.core import SACCore, core_jit, sg
from lili.agents.facade import AgentFacade
from lili.agents.registry import (
    AGENT_FORMAT,
    AGENTS,
    OPTIONS,
    check_config,
    check_extra,
    load_agent,
    make_agent,
    read_agent_file,
    register,
    register_options,
)

__all__ = ["SAC", "SACCore", "CheckpointError", "ActingState", "read_agent_file",
           "AGENT_FORMAT", "AGENTS", "register", "make_agent", "load_agent", "check_extra",
           "check_config", "register_options", "OPTIONS", "core_jit", "sg"]


class SAC(AgentFacade):
    """Soft actor-critic over interactions (no latent): the paper's SAC baseline.

    ``SAC(env, config=None, seed=0)`` with a Gymnasium env (or a registered id; continuous Box
    actions, flat Box observations, a known interaction length) and an
    :class:`~lili.config.AgentConfig`; then ``learn(n_interactions)``, ``predict(obs, state)``,
    ``save(path)`` and ``SAC.load(path, env)``. Across the interaction boundary SAC bootstraps
    from the next interaction's first observation (the stream of interactions goes on).
    """

    algo: ClassVar[str] = "sac"
    core_cls: ClassVar[type[SACCore]] = SACCore


register("sac", SAC)

