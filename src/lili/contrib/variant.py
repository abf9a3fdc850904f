"""What every variant of :mod:`lili.contrib` shares: a LILI core with options of its own
(:class:`VariantCore`), the empty options of a variant without any (:class:`NoOptions`), and
:func:`variant`, which makes a core's facade and registers it under its algo (through
:func:`facade`, which the SLAC variants of :mod:`lili.contrib.slac` use too)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, TypeVar

from lili.agents.latent import window_part
from lili.agents.lili import LILI, LILICore
from lili.agents.registry import register
from lili.buffer import Batch, Window
from lili.config import AgentConfig, dataclass_options

__all__ = ["NoOptions", "VariantCore", "facade", "variant"]

Facade = TypeVar("Facade", bound=type)


@dataclass(frozen=True)
class NoOptions:
    """A variant without options (``extra[<algo>]`` may only be empty)."""


class VariantCore(LILICore):
    """A LILI core with options of its own, read from ``config.extra[algo]``."""

    algo: ClassVar[str]
    options_cls: ClassVar[type] = NoOptions

    def __init__(self, obs_dim: int, act_dim: int, horizon: int, config: AgentConfig,
                 boundary: str | None = None) -> None:
        self.options = dataclass_options(config, self.algo, self.options_cls)
        super().__init__(obs_dim, act_dim, horizon, config, boundary)

    def _prev(self, batch: Batch) -> Window:
        """E's input for z^k: the window's interactions before k."""
        return window_part(batch["window"], slice(None, -1))


def facade(base: Facade, core: type, algo: str, options: type, name: str, doc: str) -> Facade:
    """The subclass ``name`` of agent class ``base`` whose core is ``core`` (defined in
    ``core``'s module), registered under ``algo`` with ``options``' check."""
    cls = type(name, (base,), {"algo": algo, "core_cls": core, "__doc__": doc,
                               "__module__": core.__module__})
    register(algo, cls, options=options)
    return cls


def variant(core: type[VariantCore], doc: str) -> type[LILI]:
    """The facade of ``core``'s variant (in ``core``'s module), registered under its algo with
    its options' check."""
    return facade(LILI, core, core.algo, core.options_cls,
                  core.__name__.replace("Core", "LILI"), doc)
