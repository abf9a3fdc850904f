"""The play page in a real browser: Debian's Chromium driven by Playwright against the real server
(one per module): shots by mouse drags recorded end to end, a click that does not shoot, a bad
message after which the game goes on, a page of another origin refused, a recording failure
shown with nothing recorded lost, and the phone layout.

Nothing downloads a browser: Chromium comes from ``apt-get install chromium`` (``.ci/run`` does
that). Without it the tests are skipped on a developer's machine and FAIL under CI=true.
"""

from __future__ import annotations

import csv
import functools
import http.server
import logging
import math
import os
import threading
from pathlib import Path

import pytest
from test_play import untrained_agent_file

from lili.play.policy import Blocker
from lili.play.record import Recorder
from lili.play.server import ServerThread, create_app
from lili.play.session import make_play_env

CHROMIUM = Path(os.environ.get("LILI_CHROMIUM", "/usr/bin/chromium"))
SHOTS = 5
M, S = 20, 300  # the page's canvas margin (px) and scale (px per metre), as in play.js
TIMEOUT = 60_000  # ms; the 2-core CI machine is shared


def chromium_or_fail() -> Path:
    """The browser binary; a CI run without it fails instead of skipping silently."""
    if CHROMIUM.is_file():
        return CHROMIUM
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"{CHROMIUM} is missing: CI must `apt-get install -y chromium` (.ci/run)")
    pytest.skip(f"{CHROMIUM} is missing (apt-get install chromium)")


def launch(playwright):
    """Headless Chromium from Debian's package (root needs --no-sandbox)."""
    return playwright.chromium.launch(executable_path=str(chromium_or_fail()),
                                      args=["--no-sandbox"])


def canvas_point(box: dict, x: float, y: float) -> tuple[float, float]:
    """Page coordinates of table point (x, y) metres on the 340 x 640 canvas."""
    return (box["x"] + (M + (x + 0.5) * S) * box["width"] / 340,
            box["y"] + (M + (1.0 - y) * S) * box["height"] / 640)


@pytest.fixture(scope="module")
def browser():
    chromium_or_fail()
    try:
        from playwright import sync_api
    except ImportError:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail("playwright is missing: CI installs it with the dev extras")
        pytest.skip("playwright is missing (pip install -e '.[dev]')")
    with sync_api.sync_playwright() as p:
        b = launch(p)
        yield b
        b.close()


@pytest.fixture(scope="module")
def blocker(tmp_path_factory):
    return Blocker.load(untrained_agent_file(tmp_path_factory), make_play_env({}))


@pytest.fixture(scope="module")
def server(blocker, tmp_path_factory):
    """The page's server with every session in its own CSV under ``server.folder``."""
    folder = tmp_path_factory.mktemp("play") / "sessions"
    app = create_app(blocker, {}, SHOTS, Recorder(folder=folder), None, speed=4.0)
    with ServerThread(app) as srv:
        srv.folder = folder
        yield srv


def open_page(browser, url: str, **viewport):
    page = browser.new_page(viewport=viewport or {"width": 1000, "height": 800})
    page.errors = []
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    page.goto(url + "/")
    page.wait_for_function("window.lili && window.lili.ready", timeout=TIMEOUT)
    return page


def drag(page, start: tuple[float, float], end: tuple[float, float], steps: int = 6) -> None:
    box = page.locator("#table").bounding_box()
    page.mouse.move(*canvas_point(box, *start))
    page.mouse.down()
    page.mouse.move(*canvas_point(box, *end), steps=steps)
    page.mouse.up()


def shoot(page, target: tuple[float, float], shots_after: int) -> None:
    drag(page, (0.0, 0.6), target)
    page.wait_for_function(f"window.lili.shots === {shots_after}", timeout=TIMEOUT)


def session_rows(folder: Path, before: set[Path]) -> list[dict]:
    """The rows of the one session file written since ``before`` was listed."""
    new = sorted(set(folder.glob("session-*.csv")) - before)
    assert len(new) == 1, new
    return list(csv.DictReader(new[0].open()))


def listing(folder: Path) -> set[Path]:
    return set(folder.glob("session-*.csv")) if folder.is_dir() else set()


def test_five_shots_with_mouse_drags(browser, server):
    """Shots by mouse drags, recorded end to end: the page's score is the CSV's, and the end
    puts the game beside the paper's human study."""
    before = listing(server.folder)
    page = open_page(browser, server.url)
    assert page.locator("#bars").inner_html() == ""  # no belief before the first shot
    # Drag targets (table metres) and the aims they mean: from the puck at (0, 0.6).
    targets = [(-0.3, -0.4), (0.0, -0.5), (0.25, -0.3), (-0.1, -0.8), (0.4, 0.7)]
    expected = [math.atan2(x, 0.6 - y) for x, y in targets]
    for i, target in enumerate(targets):
        shoot(page, target, i + 1)
        if i + 1 < SHOTS:
            page.wait_for_function("window.lili.ready", timeout=TIMEOUT)
    page.wait_for_function("window.lili.over", timeout=TIMEOUT)
    assert page.locator("#shots").inner_text() == str(SHOTS)
    per_mode = [int(page.locator(f"tr[data-mode={m}] .s").inner_text())
                for m in ("left", "middle", "right")]
    blocks = int(page.locator("#blocks").inner_text())
    goals = int(page.locator("#goals").inner_text())
    assert blocks + goals == SHOTS
    assert "Game over: you scored" in page.locator("#status").inner_text()
    study = page.locator("#study").inner_text()
    assert f"{blocks}/{SHOTS}" in study and "SAC" in study and "18/40" in study
    assert "LILI (no influence)" in study and "29/40" in study
    assert "too brittle" in page.locator("#study-note").inner_text()
    assert page.errors == [] and page.evaluate("window.lili.errors") == []
    page.close()
    rows = session_rows(server.folder, before)
    assert len(rows) == SHOTS and [r["shot"] for r in rows] == ["1", "2", "3", "4", "5"]
    assert sum(int(r["blocked"]) for r in rows) == blocks
    # The last target lies above the puck's line: the page clamps it to the largest aim.
    expected[-1] = 0.8
    for row, aim in zip(rows, expected, strict=True):
        assert float(row["aim"]) == pytest.approx(aim, abs=0.01)
    assert [r["mode"] for r in rows] == ["left", "middle", "right", "middle", "right"]
    assert per_mode == [1, 2, 2]


def test_a_click_without_a_drag_does_not_shoot(browser, server):
    before = listing(server.folder)
    page = open_page(browser, server.url)
    box = page.locator("#table").bounding_box()
    page.mouse.click(*canvas_point(box, 0.0, 0.6))  # on the puck
    page.mouse.click(*canvas_point(box, 0.3, 0.9))  # above-right of it
    page.mouse.click(*canvas_point(box, -0.55, 0.0))  # in the margin
    drag(page, (0.1, -0.2), (0.12, -0.24), steps=2)  # a 4.5 cm slip
    page.wait_for_function("window.lili.cancelled === 4", timeout=TIMEOUT)
    page.wait_for_timeout(300)
    assert page.evaluate("window.lili.shots") == 0 and page.evaluate("window.lili.ready")
    assert "a click does not shoot" in page.locator("#status").inner_text()
    assert listing(server.folder) == before  # nothing was played, nothing recorded
    shoot(page, (0.0, -0.5), 1)  # a real drag still shoots
    page.close()
    assert len(session_rows(server.folder, before)) == 1


def test_the_game_goes_on_after_a_bad_message(browser, server):
    before = listing(server.folder)
    page = open_page(browser, server.url)
    page.evaluate("window.lili.ws.send('{\"type\": \"shoot\", \"aim\": 1' + '0'.repeat(309)"
                  " + '}')")
    page.wait_for_function("window.lili.errors.length === 1", timeout=TIMEOUT)
    assert "an integer of 310 digits) is invalid" in page.locator("#status").inner_text()
    page.evaluate("window.lili.ws.send('not json')")
    page.wait_for_function("window.lili.errors.length === 2", timeout=TIMEOUT)
    assert page.evaluate("window.lili.connected && window.lili.ready")
    shoot(page, (-0.3, -0.4), 1)
    page.wait_for_function("window.lili.ready", timeout=TIMEOUT)
    shoot(page, (0.0, -0.5), 2)
    assert page.errors == []
    page.close()
    assert [r["mode"] for r in session_rows(server.folder, before)] == ["left", "middle"]


def test_pages_of_other_origins_are_refused(browser, server, caplog, tmp_path):
    """Pages of other sites opening the server's WebSocket (what any page open in the demo
    browser could do) never get a connection, and nothing is played or recorded. A local site
    (another web app on this machine, a real server on another port) reaches the server, which
    refuses the upgrade with a log line; a public site's request to 127.0.0.1 is blocked by
    Chromium itself (Local Network Access) before the server sees it."""
    before = listing(server.folder)
    ws_url = server.url.replace("http", "ws") + "/ws"
    (tmp_path / "index.html").write_text(
        "<script>window.seen = [];\n"
        f"const s = new WebSocket('{ws_url}');\n"
        "s.onopen = () => { seen.push('open'); s.send(JSON.stringify({type: 'shoot', aim: 0.1}));"
        " };\ns.onmessage = () => seen.push('message');\n"
        "s.onclose = (e) => seen.push('close ' + e.code);</script>")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(tmp_path))
    handler.log_message = lambda *a: None
    other = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=other.serve_forever, daemon=True).start()
    local = f"http://127.0.0.1:{other.server_address[1]}"
    try:
        with caplog.at_level(logging.WARNING, "lili.play"):
            for site in (local, "http://evil.example"):
                page = browser.new_page()
                if site != local:
                    page.route(f"{site}/**", lambda route: route.fulfill(
                        path=str(tmp_path / "index.html"), content_type="text/html"))
                page.goto(f"{site}/index.html")
                page.wait_for_function("window.seen.length > 0", timeout=TIMEOUT)
                assert page.evaluate("window.seen") == ["close 1006"], site
                page.close()
    finally:
        other.shutdown()
    lines = [r.getMessage() for r in caplog.records if r.name == "lili.play"]
    assert len(lines) == 1 and lines[0].startswith("lili play: refused a WebSocket from "
                                                   "127.0.0.1:")
    assert lines[0].endswith(f"Origin '{local}' is not this page's (HTTP 403)")
    assert listing(server.folder) == before


def test_a_recording_failure_is_shown_and_nothing_recorded_is_lost(browser, blocker, tmp_path):
    """The sessions' folder is replaced by a file after two shots (the issue's `[Errno 17] File
    exists`): the third shot is not counted, the page says the recording failed and ends the
    game, the two rows already written are intact, and a new game can be started."""
    folder = tmp_path / "sessions"
    app = create_app(blocker, {}, SHOTS, Recorder(folder=folder), None, speed=4.0)
    with ServerThread(app) as srv:
        page = open_page(browser, srv.url)
        shoot(page, (-0.3, -0.4), 1)
        page.wait_for_function("window.lili.ready", timeout=TIMEOUT)
        shoot(page, (0.3, -0.4), 2)
        page.wait_for_function("window.lili.ready", timeout=TIMEOUT)
        kept = tmp_path / "kept"
        folder.rename(kept)
        folder.write_text("in the way\n")
        drag(page, (0.0, 0.6), (0.0, -0.5))
        page.wait_for_function("window.lili.over", timeout=TIMEOUT)
        status = page.locator("#status").inner_text()
        assert status.startswith("Recording failed: could not record shot 3 in ")
        assert "the 2 shots before it are recorded" in status
        assert page.evaluate("window.lili.shots") == 2
        assert page.locator("#shots").inner_text() == "2"
        assert not page.locator("#result").is_hidden()
        page.click("#new-game")
        page.wait_for_function("window.lili.ready && window.lili.shots === 0", timeout=TIMEOUT)
        assert page.locator("#shots").inner_text() == "0" and page.errors == []
        page.close()
    rows = list(csv.DictReader(next(kept.glob("session-*.csv")).open()))
    assert [(r["shot"], r["mode"]) for r in rows] == [("1", "left"), ("2", "right")]
    assert folder.read_text() == "in the way\n"


def test_phone_layout(browser, server):
    """On a 390 x 844 phone the table, the score and the belief fit without scrolling."""
    page = open_page(browser, server.url, width=390, height=844)
    for sel in ("#table", "#scoreline", "#belief-panel", "#score-panel", "#new-game"):
        box = page.locator(sel).bounding_box()
        assert box["x"] >= 0 and box["x"] + box["width"] <= 390, sel
        assert box["y"] >= 0 and box["y"] + box["height"] <= 844, sel
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    page.close()
