"""Test envs written as a module of their own, importable by name (``module:Class`` specs)."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType


@contextmanager
def importable(folder: Path, name: str, source: str) -> Iterator[ModuleType]:
    """Write ``source`` as ``folder/name.py`` and make it importable while the block runs."""
    (folder / f"{name}.py").write_text(source)
    sys.path.insert(0, str(folder))
    try:
        yield importlib.import_module(name)
    finally:
        sys.path.remove(str(folder))
        sys.modules.pop(name, None)
