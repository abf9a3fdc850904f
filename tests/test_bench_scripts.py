"""Helpers of the benchmark scripts that decide what their result files keep."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"


def _script(name: str):
    spec = importlib.util.spec_from_file_location(f"bench_{name}", BENCH / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_influence_merge_keeps_earlier_rows_and_new_ones_win(tmp_path: Path) -> None:
    merged = _script("influence").merged
    path = tmp_path / "r.json"
    assert merged(path, {"e": {"a": 1}}) == {"e": {"a": 1}}  # nothing to merge with yet
    path.write_text(json.dumps({"e": {"scripted": {}, "learned": {"a": 0, "b": 2}},
                                "f": {"scripted": {}, "learned": {"c": 3}}}))
    assert merged(path, {"e": {"a": 1}, "g": {"d": 4}}) == {
        "e": {"a": 1, "b": 2}, "f": {"c": 3}, "g": {"d": 4}}
    path.write_text("[1, 2]")
    with pytest.raises(SystemExit, match="--merge: .* is not a report of this script"):
        merged(path, {})


@pytest.mark.parametrize("name", ["../x", "/tmp/x", ".hidden", ""])
def test_play_bot_name_must_be_a_plain_file_name(name: str, monkeypatch, capsys) -> None:
    play_bot = _script("play_bot")
    monkeypatch.setattr("sys.argv", ["play_bot.py", "a=scripted:greedy", "--name", name])
    with pytest.raises(SystemExit):
        play_bot.main()
    assert f"--name {name!r} is invalid; allowed: a plain file name" in capsys.readouterr().err
