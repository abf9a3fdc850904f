"""The play page's WebSocket messages, and their validation.

The client sends JSON text messages of at most ``MAX_MESSAGE_CHARS`` characters, at most
``rate`` a second on average (bursts of ``burst``):

- ``{"type": "shoot", "aim": A}``: strike the puck at ``A`` radians from straight down the table
  (positive towards the blocker's right), ``|A| <= AIM_LIMIT``.

The server sends ``init`` (table geometry, the game's length, the probe), ``frame`` (the table
after each decision step), ``result`` (a finished shot, the score and the blocker's belief),
``game_over`` and ``error`` (``{"type": "error", "error": "..."}``: the bad message is ignored and
the game goes on).
"""

from __future__ import annotations

import json
import math
import time
from typing import Any

from lili.play.striker import AIM_LIMIT

__all__ = ["ProtocolError", "parse_message", "RateLimiter", "MAX_MESSAGE_CHARS"]

MAX_MESSAGE_CHARS = 1024
SCHEMA: dict[str, tuple[str, ...]] = {"shoot": ("aim",)}


class ProtocolError(ValueError):
    """A client message that is not allowed; its text is sent back to the client."""


def _reject_constant(name: str) -> Any:
    raise ProtocolError(f"{name} is not allowed in a message; allowed: finite numbers")


def parse_message(raw: Any) -> dict[str, Any]:
    """Validate one raw WebSocket message and return it as a dict.

    Raises ProtocolError naming what is wrong and what is allowed.
    """
    if not isinstance(raw, str):
        raise ProtocolError("binary messages are not allowed; allowed: JSON text")
    if len(raw) > MAX_MESSAGE_CHARS:
        raise ProtocolError(f"message of {len(raw)} characters is too long; allowed: at most "
                            f"{MAX_MESSAGE_CHARS}")
    try:
        msg = json.loads(raw, parse_constant=_reject_constant)
    except ProtocolError:
        raise
    except (ValueError, RecursionError):
        raise ProtocolError("message is not valid JSON; allowed: a JSON object such as "
                            '{"type": "shoot", "aim": 0.1}') from None
    if not isinstance(msg, dict):
        raise ProtocolError(f"message is a JSON {type(msg).__name__}; allowed: a JSON object")
    if "type" not in msg:
        raise ProtocolError(f"message lacks type; allowed types: {', '.join(SCHEMA)}")
    kind = msg["type"]
    if not isinstance(kind, str) or kind not in SCHEMA:
        raise ProtocolError(f"message type {_shown(kind)!r} is unknown; allowed: "
                            f"{', '.join(SCHEMA)}")
    fields = SCHEMA[kind]
    extra = sorted(set(msg) - {"type", *fields})
    if extra:
        raise ProtocolError(f"{kind} message has unknown fields {[e[:40] for e in extra[:5]]}; "
                            f"allowed: {', '.join(('type', *fields))}")
    missing = [f for f in fields if f not in msg]
    if missing:
        raise ProtocolError(f"{kind} message lacks {', '.join(missing)}")
    aim = msg["aim"]
    # Type, then finiteness (floats only), then range, all before any arithmetic: an int's
    # comparison with a float is exact whatever its size, where float(10**309) overflows.
    if isinstance(aim, bool) or not isinstance(aim, (int, float)) \
            or (isinstance(aim, float) and not math.isfinite(aim)) \
            or not -AIM_LIMIT <= aim <= AIM_LIMIT:
        raise ProtocolError(f"aim {_shown(aim)} is invalid; allowed: a number of radians in "
                            f"[-{AIM_LIMIT}, {AIM_LIMIT}]")
    return {"type": kind, "aim": float(aim)}


def _shown(value: Any, limit: int = 40) -> str:
    """``value`` as text of at most ``limit`` characters (a huge int is never fully printed)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**limit:
        return f"(an integer of {len(str(abs(value)))} digits)"
    text = str(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


class RateLimiter:
    """Token bucket: ``rate`` messages a second on average, bursts of up to ``burst``."""

    def __init__(self, rate: float = 10.0, burst: int = 20) -> None:
        self.rate, self.burst = float(rate), float(burst)
        self.tokens, self.last = self.burst, time.monotonic()

    def allow(self) -> bool:
        """Take a token if there is one."""
        now = time.monotonic()
        self.tokens = min(self.burst, self.tokens + (now - self.last) * self.rate)
        self.last = now
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False
