"""The cost model of ``lili reproduce --dry-run``: its arithmetic and how it reads records."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from lili.experiments import costs
from lili.experiments.plan import plan
from lili.experiments.presets import get_preset


def _spec(preset: str, env: str, algo: str, history: int = 1):
    for s in plan(get_preset(preset), "/nonexistent"):
        if (s.env, s.algo, int(s.config.get("history", 1))) == (env, algo, history):
            return s
    raise AssertionError("no such run")


def test_every_run_of_the_paper_has_a_measured_cost() -> None:
    specs = plan(get_preset("paper"), "/nonexistent")
    missing = {costs.cost_key(s) for s in specs} - set(costs.COSTS)
    assert not missing, f"benchmarks/costs.py has not measured {sorted(missing)}"


def test_estimate_is_the_fixed_part_plus_the_rate_after_the_warm_up(monkeypatch) -> None:
    spec = _spec("point-mass", "lili/PointMass-v0", "sac")
    monkeypatch.setattr(costs, "COSTS", {("lili/PointMass-v0", "sac", 1): (20.0, 0.5)})
    assert costs.estimate_seconds(spec) == pytest.approx(20.0 + 0.5 * (2000 - costs.WARM))
    # A resumed run pays its start again and the interactions it has left.
    assert costs.estimate_seconds(spec, 1500) == pytest.approx(20.0 + 0.5 * 500)
    assert costs.estimate_seconds(spec, 2000) == pytest.approx(20.0)


def test_an_unmeasured_history_borrows_the_nearest_measured_one(monkeypatch) -> None:
    monkeypatch.setattr(costs, "COSTS", {("lili/PointMass-v0", "lili", 1): (10.0, 0.1),
                                         ("lili/PointMass-v0", "lili", 9): (10.0, 0.9)})
    spec = _spec("history", "lili/PointMass-v0", "lili", 7)
    assert costs.estimate_seconds(spec) == pytest.approx(10.0 + 0.9 * (2000 - costs.WARM))


def test_measure_prefers_cpu_time_and_marks_wall_time(tmp_path: Path) -> None:
    for seed, summary in enumerate([{"cpu_time_s": 100.0, "wall_time_s": 400.0},
                                    {"cpu_time_s": None, "wall_time_s": 300.0}]):
        run = tmp_path / f"seed_{seed}"
        run.mkdir()
        (run / "config.yaml").write_text(yaml.safe_dump(
            {"env": "e", "env_kwargs": {"history": 3}, "algo": "lili", "seed": seed,
             "interactions": 100, "agent": {"history": 3}}))
        (run / "summary.json").write_text(json.dumps(
            {"env": "e", "algo": "lili", "interactions": 100, **summary}))
    rate, wall = costs.measure(tmp_path)[("e", "lili", 3)]
    assert rate == pytest.approx((1.0 + 3.0) / 2) and wall
