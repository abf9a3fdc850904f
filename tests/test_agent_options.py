"""What each agent takes: the AgentConfig fields an algo reads (its entry in the registry) and
its own options in ``extra[<algo>]``. A field an algo does not read, set away from its default,
is one clear error (not silently ignored); ``lili reproduce --set`` reaches only the algos
that read the field; run folders of earlier releases, which took any field for any algo,
still load for their algo. (A ``--config`` with such a field, exit 2 and nothing written:
tests/test_bad_input.py.)"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import gymnasium as gym
import jax
import numpy as np
import pytest
import yaml

import lili.envs  # noqa: F401  (registers the envs)
from lili.agents import SAC, make_agent
from lili.agents.registry import (
    ALGOS,
    OPTIONS,
    TABLE,
    agent_options,
    check_config,
    config_for,
    reads,
    stored_config,
)
from lili.cli import main
from lili.config import LATENT_FIELDS, LOOP_FIELDS, SAC_FIELDS, AgentConfig
from lili.experiments import get_preset, plan
from lili.runs import read_run_config

FIELDS = {f.name for f in dataclasses.fields(AgentConfig)} - {"extra"}
RUNS = Path(__file__).resolve().parent.parent / "benchmarks" / "results" / "runs"


def test_every_algo_declares_what_it_reads_and_takes_the_defaults() -> None:
    assert [a.name for a in TABLE] == list(ALGOS)
    for algo in ALGOS:
        assert LOOP_FIELDS <= reads(algo) <= FIELDS, algo
        check_config(algo, AgentConfig())  # the defaults are a config of every algo
        options = agent_options(algo, AgentConfig())
        assert (options is None) == (algo not in OPTIONS), algo
        if options is not None:  # a frozen dataclass, as for every algo with options
            assert dataclasses.is_dataclass(options), algo
            assert type(options).__dataclass_params__.frozen, algo
    # Every field is read by some algo; the groups nest as the agents do.
    assert set().union(*(reads(a) for a in ALGOS)) == FIELDS == LATENT_FIELDS
    assert LOOP_FIELDS < SAC_FIELDS < LATENT_FIELDS
    assert reads("random") == LOOP_FIELDS and reads("sac") == SAC_FIELDS == reads("slac")
    assert {"slac", "lilac", "oracle-last"} <= set(OPTIONS)


@pytest.mark.parametrize("algo, field, value", [
    ("sac", "latent_dim", 3),
    ("oracle", "enc_hidden", (8,)),
    ("slac", "history", 2),
    ("random", "gamma", 0.9),
    ("lilac", "history", 3),
    ("lili-prediction-critic", "critic_to_encoder", 0.5),
])
def test_a_field_the_algo_does_not_read_is_one_error_naming_it(algo, field, value) -> None:
    config = AgentConfig(**{field: value})
    shown = list(value) if isinstance(value, tuple) else value
    expected = (f"config {field}={shown!r} is not read by {algo} (it would be ignored); "
                f"allowed: {algo} reads {', '.join(sorted(reads(algo)))}")
    with pytest.raises(ValueError) as excinfo:
        make_agent(algo, "lili/PointMass-v0", config)
    message = str(excinfo.value)
    assert message.startswith(expected) and "\n" not in message, message
    # At its default the field is no departure: the same config is fine.
    check_config(algo, AgentConfig(**{field: getattr(AgentConfig(), field)}))


def test_the_facades_check_too_and_extra_holds_only_the_algos_own_options() -> None:
    env = gym.make("lili/PointMass-v0")
    with pytest.raises(ValueError, match="latent_dim=3 is not read by sac"):
        SAC(env, AgentConfig(latent_dim=3))
    with pytest.raises(ValueError, match=r"extra.slac is invalid: it is not read by lili "
                                         r"\(it would be ignored\); allowed: lili reads "):
        check_config("lili", AgentConfig(extra={"slac": {"model_every": 2}}))
    with pytest.raises(ValueError, match="extra.sac is invalid: sac has no options"):
        check_config("sac", AgentConfig(extra={"sac": {}}))
    with pytest.raises(ValueError, match=r"unknown slac option\(s\) 'bogus' in config "
                                         r"extra.slac; allowed: z1_dim, z2_dim"):
        check_config("slac", AgentConfig(extra={"slac": {"bogus": 1}}))
    slac = agent_options("slac", AgentConfig(extra={"slac": {"model_hidden": [8, 8]}}))
    assert slac.model_hidden == (8, 8) and slac.z1_dim == 32
    with pytest.raises(ValueError, match="boundary='influence' is invalid for SLAC"):
        check_config("slac", AgentConfig(boundary="influence"))


def test_config_for_keeps_what_an_algo_reads() -> None:
    shared = {"latent_dim": 3, "gamma": 0.9, "warmup_interactions": 5,
              "extra": {"slac": {"model_every": 2}, "lilac": {"kl_weight": 0.5}}}
    assert config_for("random", shared) == {"warmup_interactions": 5}
    assert config_for("sac", shared) == {"gamma": 0.9, "warmup_interactions": 5}
    assert config_for("slac", shared)["extra"] == {"slac": {"model_every": 2}}
    assert config_for("lili", shared) == {"latent_dim": 3, "gamma": 0.9,
                                          "warmup_interactions": 5}
    sac = config_for("sac", AgentConfig.from_dict(shared))
    assert sac == AgentConfig(gamma=0.9, warmup_interactions=5)
    for algo in ALGOS:
        check_config(algo, config_for(algo, AgentConfig.from_dict(shared)))


def test_set_on_a_preset_reaches_only_the_algos_that_read_the_field(tmp_path: Path) -> None:
    specs = plan(get_preset("point-mass"), tmp_path, quick=True,
                 overrides={"latent_dim": 3, "gamma": 0.9, "extra": {"slac": {"model_every": 2}}})
    by_algo = {s.algo: s.config for s in specs}
    assert set(by_algo) == {"sac", "slac", "lili-no-influence", "lili", "lilac", "oracle"}
    for algo, config in by_algo.items():
        assert config["gamma"] == 0.9 and config["warmup_interactions"] == 3, algo
        assert ("latent_dim" in config) == (algo in ("lili-no-influence", "lili", "lilac")), algo
        assert ("extra" in config) == (algo == "slac"), algo
    assert by_algo["slac"]["extra"] == {"slac": {"model_every": 2}}
    hockey = plan(get_preset("air-hockey"), tmp_path, overrides={"gamma": 0.9})
    assert {s.algo: "gamma" in s.config for s in hockey}["random"] is False


@pytest.mark.parametrize("argv, message", [
    (["--algos", "sac", "oracle", "--set", "latent_dim=3"],
     "--set latent_dim=3 is read by no algo of this plan (sac, oracle); allowed: "
     "batch_interactions, boundary,"),
    (["--algos", "lili", "--set", "extra={slac: {model_every: 2}}"],
     "--set extra.slac is read by no algo of this plan (lili); allowed: extra.<one of them>"),
])
def test_set_that_no_algo_of_the_plan_reads_is_one_error(argv, message, tmp_path: Path,
                                                         capsys) -> None:
    out = tmp_path / "out"
    assert main(["reproduce", "point-mass", *argv, "--out", str(out), "--dry-run"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_a_run_folder_of_an_earlier_release_loads_for_its_algo(tmp_path: Path) -> None:
    """Earlier releases took any field for any algo, and config.yaml holds every field: a SAC
    run with the latent fields a preset set for all reads as the config it ran with."""
    old = AgentConfig(latent_dim=3, enc_hidden=(8,), gamma=0.9,
                      extra={"slac": {"model_every": 2}}).to_dict()
    assert stored_config("sac", old) == AgentConfig(gamma=0.9).to_dict()
    assert stored_config("lili", old) == AgentConfig(latent_dim=3, enc_hidden=(8,),
                                                     gamma=0.9).to_dict()
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.yaml").write_text(yaml.safe_dump({
        "env": "lili/PointMass-v0", "env_kwargs": {}, "algo": "sac", "seed": 0,
        "interactions": 10, "agent": old}))
    assert read_run_config(run)["agent"] == AgentConfig(gamma=0.9).to_dict()


def test_every_committed_run_folder_reads_as_a_config_of_its_algo() -> None:
    folders = sorted(p.parent for p in RUNS.rglob("config.yaml"))
    assert len(folders) > 100
    moved = 0
    for folder in folders:
        try:
            cfg = read_run_config(folder)
        except ValueError as e:  # a variant now in lili.contrib: the message names its algo
            assert "lili.contrib" in str(e) or "no longer supported" in str(e), (folder, e)
            moved += 1
            continue
        check_config(cfg["algo"], AgentConfig.from_dict(cfg["agent"]))
    assert moved < len(folders) // 4


# A valid value away from the default for every field (LOOP_FIELDS aside: every algo reads them).
AWAY = {"gamma": 0.5, "boundary_discount": "horizon", "tau": 0.5, "lr_actor": 1e-2,
        "lr_critic": 1e-2, "lr_alpha": 1e-2, "hidden": (8,), "batch_interactions": 3,
        "per_interaction": 3, "updates_per_step": 2.0, "target_entropy": -0.5,
        "init_alpha": 0.5, "phase_feature": False, "normalize": False, "boundary": "cut",
        "lr_encoder": 1e-2, "lr_decoder": 1e-2, "enc_hidden": (8,), "latent_dim": 3,
        "history": 2, "encoder_transitions": 2, "target_encoder": False,
        "critic_to_encoder": 0.3, "rep_weight": 5.0}


@pytest.mark.slow
@pytest.mark.parametrize("algo", ["random", "sac", "slac", "lilac", "oracle-last",
                                  "lili-prediction-critic"])  # every other algo reads them all
def test_the_fields_an_algo_does_not_read_change_none_of_its_numbers(algo) -> None:
    """What ``reads`` leaves out is what the algo ignores: an agent built past the check with
    every such field away from its default trains to the same numbers. (A run folder of an
    earlier release is read with those fields back at their defaults, so this is what keeps
    its resume exact.)"""
    from test_contract import CONFIG, Asymmetric, _numbers

    from lili.train import Stream, train

    assert set(AWAY) == FIELDS - LOOP_FIELDS
    config = config_for(algo, CONFIG)
    unread = {k: v for k, v in AWAY.items() if k not in reads(algo)}
    assert unread, algo
    numbers = []
    for changed in (config, config.replace(**unread)):
        agent = make_agent(algo, Asymmetric(), config, seed=4)
        agent.config = changed  # past check_config, which refuses it
        agent.core = agent._make_core()
        agent.state = agent.core.init(jax.random.PRNGKey(4))
        numbers.append(_numbers(train(agent, Stream.for_agent(agent, agent.env), 5)))
    if algo != "random":  # the last interactions ran updates: their losses are compared too
        assert np.isfinite(numbers[0][-1][1]), numbers[0][-1]
    np.testing.assert_array_equal(numbers[0], numbers[1])
