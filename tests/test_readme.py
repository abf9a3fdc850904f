"""The README's "Bring your own environment" example runs exactly as printed and learns."""

import contextlib
import io
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parent.parent / "README.md"


def _example() -> str:
    text = README.read_text()
    block = re.search(r"<!-- byoe-start -->\s*```python\n(.*?)```\s*<!-- byoe-end -->", text,
                      re.S)
    assert block, "README lost its bring-your-own-env example"
    return block.group(1)


def test_example_is_short():
    assert len(_example().strip().splitlines()) < 40


@pytest.mark.slow
def test_readme_example_trains_and_learns():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(_example(), "README.md", "exec"), {"__name__": "readme_example"})
    rate = float(re.search(r"success rate: ([0-9.]+)", out.getvalue()).group(1))
    # A policy that ignores the hider succeeds at most half the time.
    assert rate >= 0.8, out.getvalue()
