"""The play server over a real WebSocket on 127.0.0.1: 200 malformed, out-of-range and oversized
messages, each answered with an error, after which the server still serves a correct game;
foreign origins refused before the upgrade; and, against a real `lili play` process, a bounded
fuzz that leaves no traceback in its log, and a port that refuses until the page is ready."""

from __future__ import annotations

import csv
import json
import logging
import os
import re
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from test_play import SMALL, make_run_folder, untrained_agent_file
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from lili.agents.registry import config_for
from lili.play.policy import Blocker
from lili.play.record import Recorder
from lili.play.server import WS_MAX_BYTES, ServerThread, create_app
from lili.play.session import make_play_env

SHOTS = 3


@pytest.fixture(scope="module")
def blocker(tmp_path_factory):
    return Blocker.load(untrained_agent_file(tmp_path_factory), make_play_env({}))


def _server(blocker, record, **kw):
    app = create_app(blocker, {}, SHOTS, Recorder(file=record), None, speed=kw.pop("speed", 20.0),
                     **kw)
    return ServerThread(app)


def _connect(srv, **kw):
    """A WebSocket to the server's /ws with the page's own Origin (as a browser sends it)."""
    return connect(srv.url.replace("http", "ws") + "/ws", origin=srv.url, **kw)


def _recv(ws) -> dict:
    return json.loads(ws.recv(timeout=30))


def _play_game(ws) -> list[dict]:
    """Shoot until the game is over; return the result messages (checking every frame)."""
    results = []
    for aim in np.linspace(-0.5, 0.5, SHOTS):
        ws.send(json.dumps({"type": "shoot", "aim": float(aim)}))
        t = -1
        while True:
            msg = _recv(ws)
            if msg["type"] == "frame":
                assert msg["t"] == t + 1 and len(msg["puck"]) == 2
                t = msg["t"]
                continue
            assert msg["type"] == "result", msg
            assert msg["steps"] == t and msg["aim"] == pytest.approx(aim, abs=1e-5)
            results.append(msg)
            break
    assert _recv(ws)["type"] == "game_over"
    return results


def _bad_messages() -> list:
    """200 messages the server must refuse: malformed, out of range, oversized, binary."""
    rng = np.random.default_rng(0)
    fixed = [
        "", " ", "{", "}", "null", "true", "3", '"shoot"', "[]", "[1,2,3]", "{}",
        '{"type": null}', '{"type": 3}', '{"type": ["shoot"]}', '{"type": "SHOOT", "aim": 0}',
        '{"type": "shoot"}', '{"type": "shoot", "aim": null}', '{"type": "shoot", "aim": "0"}',
        '{"type": "shoot", "aim": [0.1]}', '{"type": "shoot", "aim": {"x": 1}}',
        '{"type": "shoot", "aim": true}', '{"type": "shoot", "aim": NaN}',
        '{"type": "shoot", "aim": Infinity}', '{"type": "shoot", "aim": -Infinity}',
        '{"type": "shoot", "aim": 1e400}', '{"type": "shoot", "aim": 0.81}',
        '{"type": "shoot", "aim": -3.2}', '{"type": "shoot", "aim": 0.1, "x": 1}',
        '{"type": "shoot", "aim": 0.1, "type2": "shoot"}', '{"aim": 0.1}',
        '{"type": "reset"}', '{"type": "shoot", "aim": 0.1}' + "x",
        "[" * 500 + "]" * 500, '{"a":' * 200 + "1" + "}" * 200,
        '{"type": "\u0000shoot", "aim": 0}', '{"type": "shoot", "aim": 0x10}',
        "x" * 1025, "x" * 10_000, '{"type": "shoot", "aim": 0.1, "pad": "' + "p" * 5000 + '"}',
        "y" * (WS_MAX_BYTES // 2), b"\x00\x01\x02", b"{\"type\": \"shoot\", \"aim\": 0.1}",
        bytes(4096),
    ]
    out = list(fixed)
    while len(out) < 200:
        kind = len(out) % 4
        if kind == 0:  # out-of-range aims
            aim = float(rng.choice([-1, 1]) * rng.uniform(0.8001, 100))
            out.append(json.dumps({"type": "shoot", "aim": aim}))
        elif kind == 1:  # random printable garbage
            out.append("".join(chr(c) for c in rng.integers(32, 127, int(rng.integers(1, 60)))))
        elif kind == 2:  # random bytes
            out.append(rng.integers(0, 256, int(rng.integers(1, 300)), dtype=np.uint8).tobytes())
        else:  # a valid shot with a wrong field
            out.append(json.dumps({"type": "shoot", "aim": 0.1,
                                   f"f{len(out)}": int(rng.integers(0, 9))}))
    return out


def test_fuzz_then_a_correct_game(blocker, tmp_path):
    record = tmp_path / "shots.csv"
    bad = _bad_messages()
    assert len(bad) == 200
    with _server(blocker, record, rate=1e6, burst=10**6) as srv:
        with _connect(srv, max_size=None) as ws:
            assert _recv(ws)["type"] == "init"
            for raw in bad:
                ws.send(raw)
                reply = _recv(ws)
                assert reply["type"] == "error" and reply["error"], (raw[:80], reply)
            assert not record.exists()  # nothing was played, so nothing was written
            first = _play_game(ws)  # the same connection still plays a correct game
            ws.send(json.dumps({"type": "shoot", "aim": 0.0}))
            assert "game is over" in _recv(ws)["error"]
        with _connect(srv) as ws:  # and a new connection gets a new game
            init = _recv(ws)
            assert init["type"] == "init" and init["score"]["shots"] == 0
            second = _play_game(ws)
        page = urllib.request.urlopen(srv.url + "/", timeout=10).read().decode()
        assert "<canvas id=\"table\"" in page
    assert [r["reward"] for r in first] == [r["reward"] for r in second]
    assert first[-1]["score"]["shots"] == SHOTS
    rows = list(csv.DictReader(record.open()))
    assert len(rows) == 2 * SHOTS and len({r["session"] for r in rows}) == 2


def test_rate_limit_busy_and_oversized(blocker, tmp_path):
    with _server(blocker, tmp_path / "shots.csv", rate=2.0, burst=3, speed=0.5) as srv:
        with _connect(srv) as ws:
            _recv(ws)
            ws.send(json.dumps({"type": "shoot", "aim": 0.2}))
            ws.send(json.dumps({"type": "shoot", "aim": 0.2}))
            errors = []
            for _ in range(8):
                ws.send("{}")
            while len(errors) < 9:
                msg = _recv(ws)
                if msg["type"] == "error":
                    errors.append(msg["error"])
            assert "a shot is in flight" in errors[0]
            assert sum("too many messages" in e for e in errors) >= 6
        # A frame beyond the WebSocket layer's limit closes that connection (code 1009) ...
        with _connect(srv, max_size=None) as ws:
            _recv(ws)
            ws.send("z" * (WS_MAX_BYTES + 1))
            with pytest.raises(ConnectionClosed) as closed:
                while True:
                    _recv(ws)
            assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
        # ... and the server goes on serving.
        with _connect(srv) as ws:
            assert _recv(ws)["type"] == "init"


def _closed_code(ws) -> int | None:
    with pytest.raises(ConnectionClosed) as closed:
        while True:
            _recv(ws)
    return None if closed.value.rcvd is None else closed.value.rcvd.code


def test_foreign_origins_refused_before_the_upgrade(blocker, tmp_path, caplog):
    record = tmp_path / "shots.csv"
    with _server(blocker, record) as srv, caplog.at_level(logging.WARNING, "lili.play"):
        ws_url = srv.url.replace("http", "ws") + "/ws"
        for origin in ("http://evil.example", None, f"http://127.0.0.1:{srv.port + 1}"):
            with pytest.raises(InvalidStatus) as refused:
                connect(ws_url, origin=origin)
            assert refused.value.response.status_code == 403
        # DNS rebinding: the page's own Origin, but the Host is another name for 127.0.0.1.
        sock = socket.create_connection(("127.0.0.1", srv.port))
        with pytest.raises(InvalidStatus) as refused:
            connect(f"ws://evil.example:{srv.port}/ws", sock=sock, origin=srv.url)
        assert refused.value.response.status_code == 403
        lines = [r.getMessage() for r in caplog.records if r.name == "lili.play"]
        assert len(lines) == 4 and all(line.startswith("lili play: refused a WebSocket from "
                                                       "127.0.0.1:") for line in lines)
        assert "Origin 'http://evil.example' is not this page's" in lines[0]
        assert "no Origin header" in lines[1] and "Host 'evil.example:" in lines[3]
        with connect(ws_url.replace("127.0.0.1", "localhost"),
                     origin=f"http://localhost:{srv.port}") as ws:  # another own name
            assert _recv(ws)["type"] == "init"
    assert not record.exists()


def test_allowed_origin_for_a_demo(blocker, tmp_path):
    with _server(blocker, tmp_path / "s.csv", allow_origins=("http://demo.lan:9000",)) as srv:
        sock = socket.create_connection(("127.0.0.1", srv.port))
        with connect("ws://demo.lan:9000/ws", sock=sock, origin="http://demo.lan:9000") as ws:
            assert _recv(ws)["type"] == "init"


def test_invalid_utf8_and_huge_numbers(blocker, tmp_path, caplog):
    with _server(blocker, tmp_path / "s.csv") as srv, caplog.at_level(logging.INFO):
        with _connect(srv) as ws:
            _recv(ws)
            ws.send('{"type": "shoot", "aim": 1' + "0" * 309 + "}")
            assert "an integer of 310 digits) is invalid" in _recv(ws)["error"]
            ws.send(b'{"type": "shoot", "aim": 0.1}\xff', text=True)
            assert _closed_code(ws) == 1007
        with _connect(srv) as ws:  # the server goes on
            assert _recv(ws)["type"] == "init"
            ws.send(json.dumps({"type": "shoot", "aim": 0.1}))
            while _recv(ws)["type"] != "result":
                pass
    lines = [r.getMessage() for r in caplog.records if r.name == "lili.play"]
    assert len(lines) == 1 and re.fullmatch(r"lili play: closed the WebSocket of 127\.0\.0\.1:"
                                            r"\d+: a text frame is not UTF-8 \(code 1007\)",
                                            lines[0])
    assert not [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]


# -- a real `lili play` process --------------------------------------------------------------

class LivePlay:
    """`lili play air-hockey --run RUN --port 0` as a user starts it; its stdout and stderr are
    read by threads. Records how its port answered while it was getting ready."""

    def __init__(self, run: Path, record: Path, *extra: str) -> None:
        cmd = [sys.executable, "-m", "lili.cli", "play", "air-hockey", "--run", str(run),
               "--port", "0", "--shots", "3", "--record", str(record), *extra]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.out: list[str] = []
        self.err: list[str] = []
        for stream, into in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=lambda s=stream, o=into: o.extend(iter(s.readline, "")),
                             daemon=True).start()
        first = self._wait_for("getting ready")
        self.port = int(re.search(r"http://127\.0\.0\.1:(\d+)/", first)[1])
        self.url = f"http://127.0.0.1:{self.port}"
        # Until the page is ready the port refuses; the first connection it accepts is served.
        self.refused_while_loading = 0
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline:
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=5).close()
                break
            except ConnectionRefusedError:
                self.refused_while_loading += 1
                time.sleep(0.2)
        start = time.monotonic()
        self.first_page = urllib.request.urlopen(self.url + "/", timeout=60).status
        self.first_page_s = time.monotonic() - start
        self._wait_for("  ready: open http://127.0.0.1:")

    def _wait_for(self, text: str) -> str:
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline:
            for line in self.out:
                if text in line:
                    return line
            if self.proc.poll() is not None:
                raise AssertionError(f"lili play exited: {''.join(self.err)[-2000:]}")
            time.sleep(0.05)
        raise AssertionError(f"lili play never printed {text!r}")

    def stop(self) -> str:
        """Stop the server (Ctrl-C) and return its log (stderr)."""
        self.proc.send_signal(2)
        try:
            self.proc.wait(60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(10)
        time.sleep(0.2)
        return "".join(self.err)


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    """One `lili play` process for the module: an untrained SAC (no latent, so no probe to fit:
    start-up is imports, loading and one warm-up shot)."""
    import gymnasium as gym

    from lili.agents import make_agent

    root = tmp_path_factory.mktemp("live")
    agent = make_agent("sac", gym.make("lili/AirHockey-v0"), config_for("sac", SMALL), seed=0)
    run = make_run_folder(root, agent.save(root / "sac.msgpack"), algo="sac")
    server = LivePlay(run, root / "shots.csv")
    yield server
    server.stop()


def test_the_port_refuses_until_the_page_is_ready(live):
    """Bound but not listening while it loads: an early visitor is refused at once (the
    browser says so) instead of waiting on a connection nobody answers."""
    assert live.refused_while_loading >= 1
    assert live.first_page == 200 and live.first_page_s < 10


def _fuzz_messages(rng: np.random.Generator, n: int) -> list:
    """``n`` hostile messages: mutations of a valid shot, huge and odd numbers, garbage."""
    valid = '{"type": "shoot", "aim": 0.1}'
    atoms = ["1" + "0" * 309, "-1" + "0" * 400, "1e999", "0.8000001", "NaN", "[]", "{}",
             "null", "true", '"0.1"', "9" * 1000, "0" * 5 + "1", '"\\ud800"']
    out: list = []
    while len(out) < n:
        k = len(out) % 5
        if k == 0:
            out.append(valid.replace("0.1", str(rng.choice(atoms))))
        elif k == 1:  # a valid shot with bytes flipped, cut or repeated
            b = bytearray(valid.encode())
            for _ in range(int(rng.integers(1, 4))):
                b[int(rng.integers(0, len(b)))] = int(rng.integers(32, 127))
            out.append(b.decode("latin-1")[: int(rng.integers(1, len(b) + 1))])
        elif k == 2:
            out.append(rng.integers(0, 256, int(rng.integers(0, 200)), dtype=np.uint8).tobytes())
        elif k == 3:
            out.append(json.dumps({"type": str(rng.choice(["shoot", "reset", "", "SHOOT"])),
                                   "aim": float(rng.choice([-1, 1]) * rng.uniform(0.81, 1e6)),
                                   **({"x": 1} if rng.random() < 0.5 else {})}))
        else:
            codes = rng.integers(1, 0x3000, int(rng.integers(1, 80)))
            out.append("".join(chr(int(c)) for c in codes))
    return out


def test_fuzz_leaves_no_traceback_and_the_server_plays(live):
    """A few hundred hostile messages over 127.0.0.1 in bursts the rate limit allows, text
    frames that are not UTF-8, oversized frames and foreign origins: every message gets the
    documented error or close, the log has one line per refusal and no traceback, and the
    server still plays a shot."""
    rng = np.random.default_rng(35)
    messages = _fuzz_messages(rng, 300)
    ws_url = live.url.replace("http", "ws") + "/ws"
    answered = not_utf8 = oversized = refused = 0
    for start in range(0, len(messages), 15):  # the CLI's limit: bursts of 20 a connection
        with connect(ws_url, origin=live.url, max_size=None) as ws:
            assert _recv(ws)["type"] == "init"
            for raw in messages[start:start + 15]:
                ws.send(raw)
                reply = _recv(ws)
                assert reply["type"] == "error" and reply["error"], (raw, reply)
                answered += 1
            if start % 60 == 0:
                ws.send(bytes([0xC3, 0x28]) + b"{}", text=True)
                assert _closed_code(ws) == 1007
                not_utf8 += 1
            elif start % 60 == 15:
                ws.send("z" * (WS_MAX_BYTES + 1))
                assert _closed_code(ws) == 1009
                oversized += 1
        if start % 45 == 0:
            with pytest.raises(InvalidStatus):
                connect(ws_url, origin="http://evil.example")
            refused += 1
    assert (answered, not_utf8, oversized, refused) == (300, 5, 5, 7)
    with connect(ws_url, origin=live.url) as ws:
        _recv(ws)
        ws.send(json.dumps({"type": "shoot", "aim": -0.3}))
        while (msg := _recv(ws))["type"] == "frame":
            pass
        assert msg["type"] == "result" and msg["score"]["shots"] == 1
    time.sleep(0.5)  # the last log lines
    log = "".join(live.err)
    assert "Traceback" not in log, log[-3000:]
    assert log.count("lili play: refused a WebSocket") == refused
    assert log.count("a text frame is not UTF-8 (code 1007)") == not_utf8
