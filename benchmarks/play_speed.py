"""Play page speed: the server's step time and the page's frame rate; optionally the screenshot.

    python benchmarks/play_speed.py [--run RUN] [--shots 40] [--seconds 8]
                                    [--screenshot docs/play-screenshot.png]

1. Server step time: a :class:`lili.play.session.GameSession` plays ``--shots`` shots with the
   human-like bot's aims; one step = the blocker's action (a jitted actor call) + 20 MuJoCo
   steps (40 ms of simulated time), so real-time play needs it under 40 ms. The latent update
   after each shot (z^{i+1} = E(tau^i)) is timed apart. JIT compiles are excluded (one warm-up
   shot first).
2. Over the WebSocket: the real server on 127.0.0.1 with pacing off, time per streamed frame
   from ``shoot`` to ``result`` (step + JSON + socket).
3. Page frame rate: headless Chromium (Debian's, through Playwright) loads the page and plays
   shots with mouse drags for ``--seconds``; ``requestAnimationFrame`` callbacks per second as
   the page itself counts them (``window.lili.fps``), sampled once a second.

The blocker is ``--run``'s agent, else an untrained LILI of the paper's sizes (timing does not
depend on training). Writes ``benchmarks/results/play_speed.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import lili.envs  # noqa: F401 - registers the ids
from lili.play.bot import run_bot
from lili.play.policy import Blocker, agent_file_for_run
from lili.play.probe import ModeProbe
from lili.play.record import Recorder
from lili.play.server import ServerThread, create_app
from lili.play.session import GameSession, make_play_env

RESULTS = Path(__file__).resolve().parent / "results"
CHROMIUM = "/usr/bin/chromium"
M, S = 20, 300  # the page's canvas margin (px) and scale (px per metre), as in play.js


def load_blocker(run: str | None, tmp: Path) -> tuple[Blocker, dict]:
    if run:
        path, cfg = agent_file_for_run(run)
        kwargs = dict(cfg.get("env_kwargs") or {})
    else:
        from lili.agents import make_agent

        path, kwargs = tmp / "untrained.msgpack", {}
        make_agent("lili", gym.make("lili/AirHockey-v0"), None, 0).save(path)
    return Blocker.load(path, make_play_env(kwargs)), kwargs


def ms(xs: list[float]) -> dict[str, float]:
    a = np.asarray(xs) * 1000
    return {"mean": round(float(a.mean()), 3), "median": round(float(np.median(a)), 3),
            "p95": round(float(np.percentile(a, 95)), 3), "n": int(a.size)}


def step_time(blocker: Blocker, kwargs: dict, shots: int) -> dict:
    run_bot(blocker, kwargs, 2)  # JIT compiles of acting and of the encoder
    session = GameSession(blocker, kwargs, shots)
    for aim in np.random.default_rng(0).uniform(-0.5, 0.5, shots):
        session.play(float(aim))
    return {"step_ms": ms(session.step_seconds), "latent_update_ms": ms(session.latent_seconds)}


def socket_time(blocker: Blocker, kwargs: dict, shots: int, tmp: Path) -> dict:
    from websockets.sync.client import connect

    app = create_app(blocker, kwargs, shots, Recorder(file=tmp / "ws.csv"), None, speed=1e9)
    per_frame = []
    with ServerThread(app) as srv, connect(srv.url.replace("http", "ws") + "/ws",
                                           origin=srv.url) as ws:
        ws.recv(timeout=30)
        for aim in np.linspace(-0.5, 0.5, shots):
            start, n = time.perf_counter(), 0
            ws.send(json.dumps({"type": "shoot", "aim": float(aim)}))
            while True:
                msg = json.loads(ws.recv(timeout=30))
                n += msg["type"] == "frame"
                if msg["type"] == "result":
                    break
            per_frame.append((time.perf_counter() - start) / n)
    return {"per_frame_ms": ms(per_frame)}


def page_fps(blocker: Blocker, kwargs: dict, probe: ModeProbe | None, seconds: float, tmp: Path,
             screenshot: Path | None) -> dict:
    from playwright.sync_api import sync_playwright

    app = create_app(blocker, kwargs, 40, Recorder(file=tmp / "page.csv"), probe)
    rng = np.random.default_rng(1)
    samples = []
    with ServerThread(app) as srv, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 760, "height": 760})
        page.goto(srv.url + "/")
        page.wait_for_function("window.lili && window.lili.ready", timeout=60_000)
        box = page.locator("#table").bounding_box()

        def at(x: float, y: float) -> tuple[float, float]:
            return box["x"] + (M + (x + 0.5) * S), box["y"] + (M + (1.0 - y) * S)

        end = time.time() + seconds
        while time.time() < end:
            if page.evaluate("window.lili.ready"):
                aim = float(rng.uniform(-0.55, 0.55))
                page.mouse.move(*at(0.0, 0.6))
                page.mouse.down()
                page.mouse.move(*at(1.2 * math.sin(aim), 0.6 - 1.2 * math.cos(aim)), steps=4)
                page.mouse.up()
            time.sleep(1.0)
            samples.append(float(page.evaluate("window.lili.fps")))
        shots = int(page.evaluate("window.lili.shots"))
        if screenshot is not None:
            page.wait_for_function("window.lili.ready", timeout=30_000)
            page.mouse.move(*at(0.0, 0.6))
            page.mouse.down()
            page.mouse.move(*at(-0.22, -0.2), steps=4)  # an aim line on the table
            screenshot.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(screenshot), full_page=True)
            page.mouse.up()
        browser.close()
    samples = samples[1:]  # the first second includes the page's start
    return {"fps_mean": round(statistics.mean(samples), 1), "fps_min": round(min(samples), 1),
            "seconds": len(samples), "shots_played": shots}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--run", help="run folder of a trained air hockey agent")
    p.add_argument("--shots", type=int, default=40)
    p.add_argument("--seconds", type=float, default=8.0)
    p.add_argument("--screenshot", type=Path, help="also save a screenshot of the page here")
    p.add_argument("--no-browser", action="store_true", help="skip the page's frame rate")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        blocker, kwargs = load_blocker(args.run, tmp)
        out = {"agent": args.run or "untrained lili (paper sizes)",
               "machine": f"{platform.processor() or platform.machine()}, "
                          f"{__import__('os').cpu_count()} cores (shared)"}
        out["server"] = step_time(blocker, kwargs, args.shots)
        out["websocket"] = socket_time(blocker, kwargs, min(args.shots, 20), tmp)
        if not args.no_browser:
            probe = ModeProbe.for_blocker(blocker, kwargs)
            out["page"] = page_fps(blocker, kwargs, probe, args.seconds, tmp, args.screenshot)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "play_speed.json").write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
