"""The Ray backend on a local Ray instance (127.0.0.1): same run folders as the local backend."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("ray")


def _numbers(run_dir: Path) -> list[list[str]]:
    with (run_dir / "metrics.csv").open() as f:
        rows = list(csv.reader(f))
    drop = rows[0].index("wall_time")
    return [r[:drop] + r[drop + 1:] for r in rows]


def _sweep(out: Path, algos: tuple[str, ...], *backend: str) -> str:
    cmd = [sys.executable, "-m", "lili.cli", "reproduce", "driving-2d", "--quick", "--algos",
           *algos, "--interactions", "4", "--out", str(out), "--no-progress", *backend]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stdout + res.stderr
    return res.stdout


# The default suite sweeps one algo; the two-algo sweep (two runs at once on each backend) is
# slow. Both compare every number of every run.
@pytest.mark.parametrize("algos", [("sac",), pytest.param(("sac", "lili"), marks=pytest.mark.slow)],
                         ids=["sac", "sac-lili"])
def test_ray_sweep_equals_local(tmp_path: Path, algos: tuple[str, ...]) -> None:
    log = _sweep(tmp_path / "ray", algos, "--ray", "--jobs", "2")
    assert "to run on Ray (local, 2 CPUs)" in log
    _sweep(tmp_path / "local", algos, "--jobs", "2")
    runs = sorted((tmp_path / "local").rglob("seed_*"))
    assert len(runs) == len(algos)
    for local in runs:
        ray = tmp_path / "ray" / local.relative_to(tmp_path / "local")
        assert (ray / "summary.json").is_file()
        assert _numbers(ray) == _numbers(local) and len(_numbers(local)) == 5
    assert (tmp_path / "ray" / "driving-2d" / "report" / "results.md").is_file()
