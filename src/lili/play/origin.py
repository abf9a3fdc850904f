"""Who may open the play page's WebSocket: the page's own origin, and origins allowed by name.

A browser sends ``Origin`` (the page that opens the socket) and ``Host`` (the name it used for
the server) with every WebSocket upgrade. The server serves ``http://HOST:PORT/`` and accepts an
upgrade only when ``Origin`` is ``http://N:PORT`` and ``Host`` is ``N:PORT`` for a loopback
name N (127.0.0.1, localhost, [::1]) and the port it serves, or when they name an origin given
with ``--allow-origin`` (a deliberate demo on a LAN). Everything else, a missing ``Origin``
included, is refused before the upgrade (HTTP 403): another web page open in the same browser
cannot play or record shots, and neither can a page reached through DNS rebinding (its
``Host`` is its own name). A program on this machine can send any header it likes; these
checks keep out web pages, not local programs.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any
from urllib.parse import urlsplit

__all__ = ["LOOPBACK", "LOOPBACK_NAMES", "check_origin", "OriginPolicy"]

# This machine's addresses and names, and the same as they appear in a URL or a Host header.
LOOPBACK = ("127.0.0.1", "localhost", "::1")
LOOPBACK_NAMES = tuple(f"[{h}]" if ":" in h else h for h in LOOPBACK)
_EXAMPLE = "http://192.168.1.5:8000"


def check_origin(value: str) -> str:
    """``value`` as an origin (``scheme://host[:port]``, lower case); ValueError otherwise."""
    shown = value if len(value) <= 80 else value[:77] + "..."
    allowed = (f"allowed: an origin such as {_EXAMPLE} (http or https, a host and an optional "
               "port; no path, query or user)")
    try:
        parts = urlsplit(value.strip())
        parts.port  # noqa: B018 - raises ValueError for a port that is not a number in range
    except ValueError:
        raise ValueError(f"--allow-origin {shown!r} is invalid; {allowed}") from None
    if parts.scheme not in ("http", "https") or not parts.hostname or parts.username \
            or parts.password or parts.path not in ("", "/") or parts.query or parts.fragment:
        raise ValueError(f"--allow-origin {shown!r} is invalid; {allowed}")
    return f"{parts.scheme}://{parts.netloc.lower()}"


class OriginPolicy:
    """Decides each WebSocket upgrade from its ``Origin`` and ``Host`` headers."""

    def __init__(self, allowed: Iterable[str] = ()) -> None:
        self.extra = tuple(check_origin(o) for o in allowed)

    def origins(self, port: int) -> set[str]:
        """Every accepted ``Origin`` for a server on ``port``."""
        own = {f"http://{name}:{port}" for name in LOOPBACK_NAMES}
        if port == 80:  # a browser leaves out the scheme's default port
            own |= {f"http://{name}" for name in LOOPBACK_NAMES}
        return own | set(self.extra)

    def hosts(self, port: int) -> set[str]:
        """Every accepted ``Host`` for a server on ``port``."""
        return {urlsplit(o).netloc for o in self.origins(port)}

    def refusal(self, scope: Mapping[str, Any]) -> str | None:
        """Why the upgrade in ASGI ``scope`` is refused, or None when it is accepted."""
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        port = int((scope.get("server") or ("", 0))[1] or 0)
        origin, host = headers.get("origin"), headers.get("host")
        if origin is None:
            return "no Origin header (a browser always sends one)"
        if origin.lower() not in self.origins(port):
            return f"Origin {_short(origin)!r} is not this page's"
        if host is None or host.lower() not in self.hosts(port):
            return f"Host {_short(host or '')!r} is not this server's"
        return None


def _short(text: str, limit: int = 80) -> str:
    return text if len(text) <= limit else text[:limit - 3] + "..."
