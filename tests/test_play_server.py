"""The play server over a real WebSocket on 127.0.0.1: 200 malformed, out-of-range and oversized
messages, each answered with an error, after which the server still serves a correct game."""

from __future__ import annotations

import csv
import json
import urllib.request

import numpy as np
import pytest
from test_play import untrained_agent_file
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

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
        ws_url = srv.url.replace("http", "ws") + "/ws"
        with connect(ws_url, max_size=None) as ws:
            assert _recv(ws)["type"] == "init"
            for raw in bad:
                ws.send(raw)
                reply = _recv(ws)
                assert reply["type"] == "error" and reply["error"], (raw[:80], reply)
            assert not record.exists()  # nothing was played, so nothing was written
            first = _play_game(ws)  # the same connection still plays a correct game
            ws.send(json.dumps({"type": "shoot", "aim": 0.0}))
            assert "game is over" in _recv(ws)["error"]
        with connect(ws_url) as ws:  # and a new connection gets a new game
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
        ws_url = srv.url.replace("http", "ws") + "/ws"
        with connect(ws_url) as ws:
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
        with connect(ws_url, max_size=None) as ws:
            _recv(ws)
            ws.send("z" * (WS_MAX_BYTES + 1))
            with pytest.raises(ConnectionClosed) as closed:
                while True:
                    _recv(ws)
            assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
        # ... and the server goes on serving.
        with connect(ws_url) as ws:
            assert _recv(ws)["type"] == "init"
