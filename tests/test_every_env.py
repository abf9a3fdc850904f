"""Every agent trains on every registered env through ``lili train`` (small networks, a few
interactions, updates included) and writes a complete run folder.

Slow: one JIT compile per (agent, env) pair, about 6 minutes of CPU in all. Run with -m slow.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
import yaml

from lili import cli
from lili.agents.registry import CORE_ALGOS as ALGOS  # the contrib algos: tests/test_contrib.py
from lili.agents.registry import config_for
from lili.envs import ENV_ALIASES

SMALL = {
    "hidden": [16, 16], "enc_hidden": [16, 16], "latent_dim": 2, "warmup_interactions": 3,
    "batch_interactions": 4, "per_interaction": 4, "checkpoint_every": 2,
    "extra": {"slac": {"z1_dim": 4, "z2_dim": 8, "feature_dim": 8, "model_hidden": [16],
                       "model_batch": 4, "pretrain_steps": 5}},
}


@pytest.mark.slow
@pytest.mark.parametrize("algo", ALGOS)
@pytest.mark.parametrize("alias", sorted(ENV_ALIASES))
def test_every_algo_trains_on_every_env(alias: str, algo: str, tmp_path: Path) -> None:
    cfg = tmp_path / "small.yaml"
    cfg.write_text(yaml.safe_dump(config_for(algo, SMALL)))  # a --config is for one algo
    out = tmp_path / "runs"
    assert cli.main(["train", alias, "--algo", algo, "--interactions", "5", "--out", str(out),
                     "--config", str(cfg), "--no-progress"]) == 0
    (run,) = out.glob(f"*/{algo}/seed_0")
    with open(run / "metrics.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["interaction"]) for r in rows] == [0, 1, 2, 3, 4]
    if algo != "random":  # updates ran after the warm-up and logged finite losses
        assert rows[-1]["critic_loss"] not in ("", "nan")
    assert json.loads((run / "summary.json").read_text())["interactions"] == 5
