"""`lili eval RUN --video` records interactions of every registered env.

``lili eval`` runs in a fresh process: it once failed for every env because only ``lili train``
registered the ids, which an in-process test (``lili.envs`` already imported) cannot see.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from lili import cli
from lili.envs import ENV_ALIASES


def _lili(*args: str) -> subprocess.CompletedProcess:
    code = "import sys; from lili.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          timeout=600)


# One 2D env and the MuJoCo one by default (each a fresh `lili eval` process); every env: slow.
DEFAULT = ("point-mass",)


@pytest.mark.parametrize("alias", [a if a in DEFAULT else pytest.param(a, marks=pytest.mark.slow)
                                   for a in sorted(ENV_ALIASES)])
def test_eval_video_for_every_env(alias: str, tmp_path: Path) -> None:
    out = tmp_path / "runs"
    assert cli.main(["train", alias, "--algo", "random", "--interactions", "2", "--out",
                     str(out), "--no-progress"]) == 0
    run = next(out.glob("*/random/seed_0"))
    gif = tmp_path / "clip.gif"
    ev = _lili("eval", str(run), "--interactions", "1", "--video", str(gif))
    assert ev.returncode == 0, ev.stderr
    with Image.open(gif) as img:
        assert img.n_frames >= 2  # the interaction's frames, not one still
        assert min(img.size) >= 64
