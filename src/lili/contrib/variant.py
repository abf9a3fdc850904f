"""What every variant of :mod:`lili.contrib` shares: a LILI core with options of its own
(:class:`VariantCore`), the empty options of a variant without any (:class:`NoOptions`), and
:func:`variant`, which makes a core's facade and registers it under its algo."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from lili.agents.latent import window_part
from lili.agents.lili import LILI, LILICore
from lili.agents.registry import register
from lili.buffer import Batch, Window
from lili.config import AgentConfig, dataclass_options

__all__ = ["NoOptions", "VariantCore", "variant"]


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


def variant(core: type[VariantCore], doc: str) -> type[LILI]:
    """The facade of ``core``'s variant (in ``core``'s module), registered under its algo with
    its options' check."""
    cls = type(core.__name__.replace("Core", "LILI"), (LILI,),
               {"algo": core.algo, "core_cls": core, "__doc__": doc, "__module__": core.__module__})
    register(core.algo, cls, options=core.options_cls)
    return cls
