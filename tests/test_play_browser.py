"""The play page in a real browser: Debian's Chromium driven by Playwright plays 5 shots with mouse
drags against the real server; the scoreboard counts them and the CSV holds 5 rows.

Nothing downloads a browser: Chromium comes from ``apt-get install chromium`` (``.ci/run`` does
that). Without it the test is skipped on a developer's machine and FAILS under CI=true.
"""

from __future__ import annotations

import csv
import math
import os
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


def test_five_shots_with_mouse_drags(tmp_path_factory, tmp_path):
    chromium_or_fail()
    try:
        from playwright import sync_api
    except ImportError:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail("playwright is missing: CI installs it with the dev extras")
        pytest.skip("playwright is missing (pip install -e '.[dev]')")
    blocker = Blocker.load(untrained_agent_file(tmp_path_factory), make_play_env({}))
    record = tmp_path / "shots.csv"
    app = create_app(blocker, {}, SHOTS, Recorder(file=record), None)
    # Drag targets (table metres) and the aims they mean: from the puck at (0, 0.6).
    targets = [(-0.3, -0.4), (0.0, -0.5), (0.25, -0.3), (-0.1, -0.8), (0.4, 0.7)]
    expected = [math.atan2(x, 0.6 - y) for x, y in targets]
    with ServerThread(app) as srv, sync_api.sync_playwright() as p:
        browser = launch(p)
        page = browser.new_page(viewport={"width": 1000, "height": 800})
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(srv.url + "/")
        page.wait_for_function("window.lili && window.lili.ready", timeout=30_000)
        box = page.locator("#table").bounding_box()
        for i, (x, y) in enumerate(targets):
            page.mouse.move(*canvas_point(box, 0.0, 0.6))
            page.mouse.down()
            page.mouse.move(*canvas_point(box, x, y), steps=6)
            page.mouse.up()
            page.wait_for_function(f"window.lili.shots === {i + 1}", timeout=30_000)
            if i + 1 < SHOTS:
                page.wait_for_function("window.lili.ready", timeout=30_000)
        page.wait_for_function("window.lili.over", timeout=30_000)
        assert page.locator("#shots").inner_text() == str(SHOTS)
        per_mode = [int(page.locator(f"tr[data-mode={m}] .s").inner_text())
                    for m in ("left", "middle", "right")]
        assert sum(per_mode) == SHOTS
        blocks = int(page.locator("#blocks").inner_text())
        assert "game over" in page.locator("#status").inner_text()
        assert errors == [] and page.evaluate("window.lili.errors") == []
        browser.close()
    rows = list(csv.DictReader(record.open()))
    assert len(rows) == SHOTS
    assert sum(int(r["blocked"]) for r in rows) == blocks
    # The last target lies above the puck's line: the page clamps it to the largest aim.
    expected[-1] = 0.8
    for row, aim in zip(rows, expected, strict=True):
        assert float(row["aim"]) == pytest.approx(aim, abs=0.01)
    assert [r["mode"] for r in rows] == ["left", "middle", "right", "middle", "right"]
    assert per_mode == [1, 2, 2]
