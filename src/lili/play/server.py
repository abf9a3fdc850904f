"""The play page's server: Starlette + uvicorn, one game per WebSocket connection.

``GET /`` serves the page (``static/``: HTML, JS, CSS; no CDN, no build step) and ``/ws`` plays
the game (messages: :mod:`lili.play.protocol`). Every client message is validated; a bad one is
answered with an ``error`` message and ignored, and nothing a client sends ends the server.
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

from lili.envs.air_hockey import env as table
from lili.play.policy import Blocker
from lili.play.probe import ModeProbe
from lili.play.protocol import ProtocolError, RateLimiter, parse_message
from lili.play.record import Recorder
from lili.play.session import GameSession
from lili.play.striker import AIM_LIMIT, MODE_NAMES, mode_aims

__all__ = ["create_app", "bind", "serve", "ServerThread", "STATIC", "WS_MAX_BYTES"]

STATIC = Path(__file__).with_name("static")
# Frames above this are closed by the WebSocket layer (code 1009) before the app sees them;
# everything below it reaches the validator and gets an error message back.
WS_MAX_BYTES = 1 << 20
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
               rate: float = 10.0, burst: int = 20) -> Starlette:
    """The ASGI app. ``speed`` scales the pace of the streamed frames (1 = real time)."""
    counter = {"sessions": 0}

    async def index(request: Any) -> FileResponse:
        return FileResponse(STATIC / "index.html")

    async def play(ws: WebSocket) -> None:
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

        async def run_shot(aim: float) -> None:
            try:
                for msg in session.shoot(aim):
                    await send(msg)
                    if msg["type"] == "frame":
                        await asyncio.sleep(session.table.dt / speed)
                if session.over:
                    await send({"type": "game_over", "score": session.score()})
            except (WebSocketDisconnect, RuntimeError):
                pass  # the client left mid-shot
            except Exception as e:  # never let one game take the server down
                log.exception("shot failed")
                await send({"type": "error", "error": f"server error: {e}"})

        init = {"type": "init", "shots": shots, "speed": speed, "algo": blocker.algo,
                "source": blocker.source, "interactions": blocker.interactions,
                "latent_dim": blocker.latent_dim, "table": _geometry(session.table.bank_shots),
                "probe": None if probe is None else probe.summary(),
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
                    await send({"type": "error", "error": f"the game is over ({shots} of "
                                f"{shots} shots); reconnect for a new game"})
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


def bind(host: str, port: int) -> socket.socket:
    """A listening socket on (host, port); port 0 picks a free one. ValueError when taken."""
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
    sock.listen(64)
    return sock


def _config(app: Starlette) -> uvicorn.Config:
    return uvicorn.Config(app, log_level="warning", ws_max_size=WS_MAX_BYTES, lifespan="off")


def serve(app: Starlette, sock: socket.socket) -> None:
    """Serve ``app`` on the bound socket until interrupted."""
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
