"""Error text of bounded size: every value a message echoes, and every message printed.

A hostile input (a 10 MB ``--set`` value, a YAML structure whose repr is gigabytes) must not
become an error line of that size: :func:`shown` writes a value at most about
``MAX_VALUE_CHARS`` long without building its full repr, and :func:`bounded` cuts each line of a
message to ``MAX_LINE_CHARS``, keeping its start (what is wrong) and its end (what is allowed).
"""

from __future__ import annotations

import reprlib
from typing import Any

__all__ = ["shown", "bounded", "flat", "MAX_LINE_CHARS", "MAX_VALUE_CHARS"]

MAX_LINE_CHARS = 600
"""Longest error line printed (``lili: error: `` included): room for the longest message
the library means to print (the list of every AgentConfig field), never the size of what a
user typed."""
MAX_VALUE_CHARS = 60
"""About the longest echo of one value inside a message."""
MAX_LINES = 12

_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = MAX_VALUE_CHARS
_REPR.maxlevel = 2
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = _REPR.maxset = _REPR.maxfrozenset = 4


def shown(value: Any) -> str:
    """``repr(value)`` cut to about ``MAX_VALUE_CHARS`` (containers to a few items and levels),
    computed without the full repr; a cut string says how long it was."""
    try:
        text = _REPR.repr(value)
    except Exception:  # a hostile __repr__ or an int too long to print
        text = f"<{type(value).__name__}>"
    if isinstance(value, str) and len(value) > MAX_VALUE_CHARS:
        text += f" ({len(value)} characters)"
    return _cut(text, 2 * MAX_VALUE_CHARS)


def _cut(line: str, limit: int) -> str:
    if len(line) <= limit:
        return line
    tail = limit // 3
    marker = f" ...({len(line)} characters in all)... "
    return line[:limit - tail - len(marker)] + marker + line[-tail:]


def bounded(message: str, limit: int = MAX_LINE_CHARS) -> str:
    """``message`` with each line cut to ``limit`` characters (its start and its end kept) and
    at most ``MAX_LINES`` lines."""
    lines = message.splitlines() or [""]
    if len(lines) > MAX_LINES:
        lines = lines[:MAX_LINES - 1] + [f"... ({len(lines) - MAX_LINES + 1} more lines)"]
    return "\n".join(_cut(line, limit) for line in lines)


def flat(text: str, limit: int = MAX_LINE_CHARS // 2) -> str:
    """``text`` (another library's message, maybe several lines) as one line of at most
    ``limit`` characters."""
    return _cut(" ".join(text[:100 * limit].split()), limit)
