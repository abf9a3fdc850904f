"""The play page's server: Starlette + uvicorn, one game per WebSocket connection.

``GET /`` serves the page (``static/``: HTML, JS, CSS; no CDN, no build step) and ``/ws`` plays
the game (messages: :mod:`lili.play.protocol`). An upgrade from another origin or host is
refused before it happens (HTTP 403, one log line; :mod:`lili.play.origin`). Every client
message is validated; a bad one is answered with an ``error`` message and ignored, a text frame
that is not UTF-8 closes its connection (code 1007, one log line), and nothing a client sends
ends the server or puts a traceback in its log.

:func:`bind` takes the port without listening, so a visitor who comes before the page is ready
is refused at once rather than left waiting; :func:`serve` listens once the app is built.
"""

from __future__ import annotations

import asyncio
import json
import logging
import socket
import threading
from pathlib import Path
from typing import Any

import uvicorn
from starlette.applications import Starlette
from starlette.responses import FileResponse
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

try:  # uvicorn >= 0.35; older ones use their legacy implementation, which closes with 1007
    from uvicorn.protocols.websockets.websockets_sansio_impl import (
        WebSocketsSansIOProtocol as _SansIO,
    )
    from websockets.protocol import State
except ImportError:  # pragma: no cover
    _SansIO = None

from lili.envs.air_hockey import env as table
from lili.play.bot import PAPER_HUMAN, PAPER_LILI
from lili.play.origin import OriginPolicy
from lili.play.policy import Blocker
from lili.play.probe import ModeProbe
from lili.play.protocol import ProtocolError, RateLimiter, parse_message
from lili.play.record import Recorder, RecordError
from lili.play.session import GameSession
from lili.play.striker import AIM_LIMIT, MODE_NAMES, mode_aims

__all__ = ["create_app", "bind", "listen", "serve", "ServerThread", "STATIC", "WS_MAX_BYTES"]

STATIC = Path(__file__).with_name("static")
# Frames above this are closed by the WebSocket layer (code 1009) before the app sees them;
# everything below it reaches the validator and gets an error message back.
WS_MAX_BYTES = 1 << 20
BACKLOG = 64
log = logging.getLogger("lili.play")


def _geometry(bank_shots: bool) -> dict[str, Any]:
    return {"half_width": table.HALF_WIDTH, "half_length": table.HALF_LENGTH,
            "ego_y": table.EGO_Y, "ego_range": table.EGO_RANGE,
            "puck_radius": table.PUCK_RADIUS, "paddle_radius": table.PADDLE_RADIUS,
            "puck_start": [float(v) for v in table.PUCK_START],
            "aim_limit": AIM_LIMIT, "mode_aims": list(mode_aims(bank_shots)),
            "mode_names": list(MODE_NAMES), "dt": table.FRAME_SKIP * 0.002,
            "bank_shots": bank_shots}


def create_app(blocker: Blocker, env_kwargs: dict[str, Any], shots: int, recorder: Recorder,
               probe: ModeProbe | None = None, seed: int = 0, speed: float = 1.0,
               rate: float = 10.0, burst: int = 20,
               allow_origins: tuple[str, ...] = ()) -> Starlette:
    """The ASGI app. ``speed`` scales the pace of the streamed frames (1 = real time);
    ``allow_origins`` are accepted besides the page's own (``--allow-origin``)."""
    counter = {"sessions": 0}
    origins = OriginPolicy(allow_origins)

    async def index(request: Any) -> FileResponse:
        return FileResponse(STATIC / "index.html")

    async def play(ws: WebSocket) -> None:
        client = _client(ws.scope)
        refusal = origins.refusal(ws.scope)
        if refusal is not None:
            log.warning("lili play: refused a WebSocket from %s: %s (HTTP 403)", client, refusal)
            await ws.close()  # before accept(): the server answers the upgrade with 403
            return
        await ws.accept()
        counter["sessions"] += 1
        session = GameSession(blocker, env_kwargs, shots, recorder.session(), probe,
                              seed + counter["sessions"] - 1)
        lock = asyncio.Lock()
        limiter = RateLimiter(rate, burst)
        shot: asyncio.Task | None = None

        async def send(msg: dict[str, Any]) -> None:
            async with lock:
                await ws.send_text(json.dumps(msg))

        def next_message(frames: Any) -> dict[str, Any] | None:
            """The shot's next message; a failure ends the game with its reason."""
            try:
                return next(frames)
            except StopIteration:
                return None
            except RecordError as e:
                log.error("lili play: %s; that game ended after %d recorded shots", e,
                          session.shot)
                session.end(f"{e}. The game ends here; the {session.shot} shots before it "
                            "are recorded")
            except Exception as e:  # a bug, not the client: log it, end this game only
                log.exception("lili play: a shot failed")
                session.end(f"server error ({type(e).__name__}); the game ends here; the "
                            f"{session.shot} shots before it are recorded")
            return {"type": "game_over", "score": session.score(), "ended": session.ended}

        async def run_shot(aim: float) -> None:
            frames = session.shoot(aim)
            try:
                while (msg := next_message(frames)) is not None:
                    await send(msg)
                    if msg["type"] == "frame":
                        await asyncio.sleep(session.table.dt / speed)
                    elif msg["type"] == "game_over":
                        return
                if session.over:
                    await send({"type": "game_over", "score": session.score(), "ended": None})
            except (WebSocketDisconnect, RuntimeError):
                pass  # the client left mid-shot

        init = {"type": "init", "shots": shots, "speed": speed, "algo": blocker.algo,
                "source": blocker.source, "interactions": blocker.interactions,
                "latent_dim": blocker.latent_dim, "table": _geometry(session.table.bank_shots),
                "probe": None if probe is None else probe.summary(),
                "paper": {"blocks": PAPER_HUMAN, "shots": 40, "lili": PAPER_LILI},
                "belief": session.belief(), "score": session.score()}
        try:
            await send(init)
            while True:
                message = await ws.receive()
                if message["type"] == "websocket.disconnect":
                    break
                raw = message.get("text")
                raw = message.get("bytes") if raw is None else raw
                if not limiter.allow():
                    await send({"type": "error", "error": f"too many messages; allowed: at most "
                                f"{rate:g} a second (bursts of {burst})"})
                    continue
                try:
                    msg = parse_message(raw)
                except ProtocolError as e:
                    await send({"type": "error", "error": str(e)})
                    continue
                if session.over:
                    await send({"type": "error", "error": f"the game is over ({session.shot} of "
                                f"{shots} shots played); reconnect for a new game"})
                elif shot is not None and not shot.done():
                    await send({"type": "error", "error": "a shot is in flight; wait for its "
                                "result"})
                else:
                    shot = asyncio.create_task(run_shot(msg["aim"]))
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            if shot is not None:
                shot.cancel()
            session.close()

    routes = [Route("/", index), WebSocketRoute("/ws", play),
              Mount("/static", StaticFiles(directory=STATIC), name="static")]
    return Starlette(routes=routes)


def _client(scope: Any) -> str:
    client = scope.get("client") or ("?", 0)
    return f"{client[0]}:{client[1]}"


def bind(host: str, port: int) -> socket.socket:
    """A socket bound to (host, port), not yet listening (a connection is refused until
    :func:`listen`); port 0 picks a free one. ValueError when the port is taken."""
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"--port {port!r} is invalid; allowed: an integer in 0..65535")
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as e:
        sock.close()
        raise ValueError(f"cannot listen on {host}:{port} ({e.strerror}); allowed: a free port "
                         "and an address of this machine") from None
    return sock


def listen(sock: socket.socket) -> None:
    """Start accepting connections on the bound ``sock`` (ValueError when the port was taken
    since :func:`bind`)."""
    try:
        sock.listen(BACKLOG)
    except OSError as e:
        host, port = sock.getsockname()[:2]
        raise ValueError(f"cannot listen on {host}:{port} ({e.strerror}); allowed: a free port "
                         "and an address of this machine") from None


if _SansIO is not None:
    class _Protocol(_SansIO):  # type: ignore[misc,valid-type]
        """uvicorn's WebSocket protocol, but a text frame that is not UTF-8 closes its connection
        with code 1007 and one log line (uvicorn logs two tracebacks for it)."""

        def send_receive_event_to_app(self) -> None:
            if self.curr_msg_data_type == "text" and not self.close_sent:
                try:
                    b"".join(self.frames).decode()
                except UnicodeDecodeError:
                    self.frames = []
                    log.warning("lili play: closed the WebSocket of %s:%s: a text frame is not "
                                "UTF-8 (code 1007)", *(self.client or ("?", 0)))
                    if self.conn.state is State.OPEN:  # else the client is already closing
                        self.conn.send_close(1007, "text frames must be UTF-8")
                    self.transport.write(b"".join(self.conn.data_to_send()))
                    self.close_sent = True
                    self.queue.put_nowait({"type": "websocket.disconnect", "code": 1007})
                    self.transport.close()
                    return
            super().send_receive_event_to_app()

    _WS_PROTOCOL: Any = _Protocol
else:  # pragma: no cover
    _WS_PROTOCOL = "auto"


def _config(app: Starlette) -> uvicorn.Config:
    return uvicorn.Config(app, log_level="warning", ws_max_size=WS_MAX_BYTES, lifespan="off",
                          ws=_WS_PROTOCOL, backlog=BACKLOG)


def serve(app: Starlette, sock: socket.socket) -> None:
    """Listen on the bound socket and serve ``app`` until interrupted."""
    listen(sock)
    uvicorn.Server(_config(app)).run(sockets=[sock])


class ServerThread:
    """The real server in a background thread on 127.0.0.1 (tests, benchmarks)."""

    def __init__(self, app: Starlette, host: str = "127.0.0.1", port: int = 0) -> None:
        self.sock = bind(host, port)
        self.port = int(self.sock.getsockname()[1])
        self.url = f"http://{host}:{self.port}"
        self.server = uvicorn.Server(_config(app))
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self.sock]},
                                       daemon=True)

    def __enter__(self) -> ServerThread:
        listen(self.sock)
        self.thread.start()
        for _ in range(2000):
            if self.server.started:
                return self
            threading.Event().wait(0.01)
        raise RuntimeError("the play server did not start within 20 s")

    def __exit__(self, *exc: Any) -> None:
        self.server.should_exit = True
        self.thread.join(10)
        self.sock.close()
