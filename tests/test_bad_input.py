"""Every bad input on the command line, in configs and in check-env: exit code 2, ONE line
``lili: error: ...`` naming the bad value and what is allowed, and nothing on disk created or
changed (issue 11; the table of cases before and after is in docs/bad-input.md).

The commands run in-process through ``lili.cli.main`` against real files, a real run folder
(trained once with the random agent) and real envs; a few run the installed ``lili`` script.
"""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from _env_modules import importable

from lili import cli
from lili.config import AgentConfig, load_config
from lili.envs.checker import EnvContractError, check_env

BAD_ENVS = '''
"""Envs that break the contract in ways a quick check misses."""
import numpy as np
from gymnasium import spaces

from lili.envs.point_mass import PointMassEnv


class HugeHorizon(PointMassEnv):
    def __init__(self, **kw):
        super().__init__(**kw)
        self.horizon = 10**9


class NaNAfter30(PointMassEnv):
    def _step(self, a):
        o, r, d = super()._step(a)
        return (np.full_like(o, np.nan) if self.interaction >= 30 else o), r, d


class NaNRewardAfter30(PointMassEnv):
    def _step(self, a):
        o, r, d = super()._step(a)
        return o, (float("nan") if self.interaction >= 30 else r), d


class Leak2x(PointMassEnv):
    def __init__(self, **kw):
        super().__init__(**kw)
        self.observation_space = spaces.Box(-1, 1, (3,), np.float32)

    def _begin(self):
        return np.append(super()._begin(), 2 * self.partner.strategy()[0]).astype(np.float32)

    def _step(self, a):
        o, r, d = super()._step(a)
        return np.append(o, 2 * self.partner.strategy()[0]).astype(np.float32), r, d
'''


@pytest.fixture(scope="module")
def trained_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("base")
    assert cli.main(["train", "point-mass", "--algo", "random", "--interactions", "2",
                     "--out", str(out), "--no-progress"]) == 0
    return out / "PointMass-v0" / "random" / "seed_0"


@pytest.fixture(scope="module")
def bad_envs(tmp_path_factory: pytest.TempPathFactory) -> str:
    with importable(tmp_path_factory.mktemp("envs"), "lili_bad_envs", BAD_ENVS):
        yield "lili_bad_envs"


def _snapshot(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.md5(p.read_bytes()).hexdigest()
            if p.is_file() else "folder" for p in sorted(root.rglob("*"))}


def _train(*flags: str) -> Callable[[Path, Path], list[str]]:
    def make(tmp: Path, run: Path) -> list[str]:
        return ["train", "point-mass", "--algo", "random", "--interactions", "1",
                "--no-progress", "--out", str(tmp / "out"), *flags]
    return make


def _config(text: str | bytes, algo: str = "random") -> Callable[[Path, Path], list[str]]:
    def make(tmp: Path, run: Path) -> list[str]:
        path = tmp / "c.yaml"
        path.write_bytes(text) if isinstance(text, bytes) else path.write_text(text)
        return ["train", "point-mass", "--algo", algo, "--interactions", "1", "--no-progress",
                "--config", str(path), "--out", str(tmp / "out")]
    return make


def _eval(*flags: str, files: dict[str, str] | None = None) -> Callable[[Path, Path], list[str]]:
    def make(tmp: Path, run: Path) -> list[str]:
        for name, text in (files or {}).items():
            (run / name).write_text(text)
        return ["eval", str(run), "--interactions", "1", *flags]
    return make


def _file_at(name: str, *then: str) -> Callable[[Path, Path], list[str]]:
    def make(tmp: Path, run: Path) -> list[str]:
        (tmp / name).write_text("a file, not a folder\n")
        return ["train", "point-mass", "--algo", "random", "--interactions", "1",
                "--no-progress", "--out", str(tmp.joinpath(name, *then))]
    return make


def _video_into_folder(tmp: Path, run: Path) -> list[str]:
    (tmp / "v.gif").mkdir()
    return ["eval", str(run), "--interactions", "1", "--video", str(tmp / "v.gif")]


def _check_env(cls: str, *flags: str) -> Callable[[Path, Path], list[str]]:
    return lambda tmp, run: ["check-env", f"lili_bad_envs:{cls}", *flags]


MAX_SEED = "4294967295"

# (case, argv maker, fragments the one line must contain)
CASES = [
    # tracebacks before
    ("train --out FILE", _file_at("f"), ["--out", "is a file", "allowed: a folder"]),
    ("eval --seed -3", _eval("--seed", "-3"), ["--seed=-3", MAX_SEED]),
    ("train --seed 2**70", _train("--seed", "1180591620717411303424"),
     ["--seed=1180591620717411303424", MAX_SEED]),
    ("eval, corrupt config.yaml", _eval(files={"config.yaml": "env: [lili/PointMass-v0\n"}),
     ["config.yaml", "not valid YAML", "line 2, column"]),
    ("check-env, horizon 10**9", _check_env("HugeHorizon"),
     ["horizon=1000000000", "GiB", "allowed: a smaller horizon"]),
    # unclear before
    ("eval, garbage latest.json", _eval(files={"checkpoints/latest.json": "garbage"}),
     ["latest.json", "corrupt", "expected"]),
    ("--env-kwarg step_noise=abc", _train("--env-kwarg", "step_noise=abc"),
     ["step_noise='abc'", "allowed: a finite number >= 0"]),
    ("--env-kwarg colour=red", _train("--env-kwarg", "colour=red"),
     ["'colour'", "allowed: step_noise, history, horizon"]),
    ("--config DIR", lambda tmp, run: ["train", "point-mass", "--config", str(tmp), "--out",
                                       str(tmp / "out")], ["is a folder", "a YAML file"]),
    ("malformed YAML config", _config("gamma: 0.9\nhidden: [256, 256\nlatent_dim: 8\n"),
     ["c.yaml", "not valid YAML", "line 3, column 11"]),
    # accepted silently before
    ("--env-kwarg render_mode=human", _train("--env-kwarg", "render_mode=human"),
     ["render_mode=human", "renders nothing", "--video"]),
    ("lr_actor: .inf", _config("lr_actor: .inf\n"), ["lr_actor=inf", "a finite number > 0"]),
    ("gamma: false", _config("gamma: false\n"), ["gamma=False", "a number in [0, 1)"]),
    ("target_entropy: .nan", _config("target_entropy: .nan\n"),
     ["target_entropy=nan", "a finite number or null"]),
    ("target_entropy: nan", _config("target_entropy: nan\n"),
     ["target_entropy='nan'", "a finite number or null"]),
    ("extra: {slac: {bogus: 1}} --algo lili", _config("extra: {slac: {bogus: 1}}\n", "lili"),
     ["extra.slac", "not read by lili", "allowed: lili reads"]),
    ("extra: {slac: {bogus: 1}} --algo slac", _config("extra: {slac: {bogus: 1}}\n", "slac"),
     ["'bogus'", "extra.slac", "allowed: z1_dim"]),
    ("latent_dim: 3 --algo sac", _config("latent_dim: 3\n", "sac"),
     ["latent_dim=3", "not read by sac", "allowed: sac reads batch_interactions"]),
    ("extra: 5", _config("extra: 5\n", "lili"), ["extra=5", "allowed: a mapping"]),
    ("buffer_capacity: 2", _config("buffer_capacity: 2\n"),
     ["buffer_capacity=2", "an integer >= 20", "warmup_interactions=20"]),
    ("--video /missing/dir/x.gif", lambda tmp, run: _eval(
        "--video", str(tmp / "missing" / "dir" / "x.gif"))(tmp, run),
     ["missing/dir", "does not exist", "allowed: a .gif file in an existing folder"]),
    ("--video x.mp4", lambda tmp, run: _eval("--video", str(tmp / "x.mp4"))(tmp, run),
     ["x.mp4", "allowed: a .gif file"]),
    ("check-env, NaN observation after interaction 30", _check_env("NaNAfter30"),
     ["interaction 30", "not finite", "NaN in dimension(s) [0, 1]", "finite observations"]),
    ("check-env, observation = 2 x strategy", _check_env("Leak2x"),
     ["observation dimension 2", "2 * strategy[0]", "leaks"]),
    # a hostile tester's own
    ("train --seed 2**32", _train("--seed", str(2**32)), [f"--seed={2**32}", MAX_SEED]),
    ("train --seed abc", _train("--seed", "abc"), ["--seed", "'abc'"]),
    ("eval --seed 2**70", _eval("--seed", str(2**70)), [f"--seed={2**70}", MAX_SEED]),
    ("check-env --seed -1", lambda tmp, run: ["check-env", "point-mass", "--seed", "-1"],
     ["--seed=-1", MAX_SEED]),
    ("check-env --interactions 10**9", lambda tmp, run: ["check-env", "point-mass",
                                                          "--interactions", str(10**9)],
     ["--interactions 1000000000", "[2, 10000]"]),
    ("check-env, NaN reward after interaction 30", _check_env("NaNRewardAfter30"),
     ["interaction 30", "reward is nan", "finite"]),
    ("train --out FILE/sub", _file_at("f", "sub"), ["f/sub", "is a file"]),
    ("--video DIR.gif (a folder)", _video_into_folder, ["v.gif", "is a folder"]),
    ("eval, config.yaml a list", _eval(files={"config.yaml": "- 1\n- 2\n"}),
     ["config.yaml", "not a lili run config"]),
    ("eval, config.yaml without env", _eval(files={"config.yaml": "algo: random\n"}),
     ["config.yaml", "not a lili run config", "env"]),
    ("eval, latest.json -> ../../x",
     _eval(files={"checkpoints/latest.json": '{"checkpoint": "../../x", "interactions": 2}'}),
     ["latest.json", "corrupt"]),
    ("eval, latest.json a list", _eval(files={"checkpoints/latest.json": "[1]"}),
     ["latest.json", "corrupt"]),
    ("config key given twice", _config("gamma: 0.9\ngamma: 0.5\n"),
     ["'gamma' is given twice", "line 2, column 1"]),
    ("config not UTF-8", _config(b"\xff\xfe\x00gamma"), ["c.yaml", "not UTF-8"]),
    ("critic_to_encoder: .inf", _config("critic_to_encoder: .inf\n"),
     ["critic_to_encoder=inf", "finite"]),
    ("buffer_capacity 30 < warmup_interactions 50",
     _config("warmup_interactions: 50\nbuffer_capacity: 30\n"),
     ["buffer_capacity=30", "an integer >= 50"]),
    ("extra: {slac: 5}", _config("extra: {slac: 5}\n", "lili"), ["extra.slac=5", "a mapping"]),
    ("extra: {sac: {x: 1}}", _config("extra: {sac: {x: 1}}\n", "sac"),
     ["extra.sac", "sac has no options", "allowed: sac reads"]),
    ("extra: {oracle-last: {outcome: 1}}", _config("extra: {oracle-last: {outcome: 1}}\n",
                                                   "oracle-last"),
     ["extra.oracle-last.outcome=1", "allowed: true or false"]),
    ("extra: {lilac: {kl_weight: .inf}}", _config("extra: {lilac: {kl_weight: .inf}}\n",
                                                  "lilac"),
     ["extra.lilac.kl_weight=inf", "finite"]),
    ("--env-kwarg history twice", _train("--env-kwarg", "history=2", "--env-kwarg", "history=3"),
     ["history is given twice", "each KEY once"]),
    ("--env-kwarg =3", _train("--env-kwarg", "=3"), ["'=3'", "KEY=VALUE"]),
    ("--env-kwarg max_episode_steps=5 (gym.make's, not the env's)",
     _train("--env-kwarg", "max_episode_steps=5"), ["'max_episode_steps'", "allowed: step_noise"]),
    ("--env-kwarg history=[1", _train("--env-kwarg", "history=[1"),
     ["history=[1", "not a valid YAML value"]),
]


@pytest.mark.parametrize(("make", "fragments"), [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_one_line_exit_2_nothing_written(
        make: Callable[[Path, Path], list[str]], fragments: list[str], tmp_path: Path,
        trained_run: Path, bad_envs: str, capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "run"
    shutil.copytree(trained_run, run)
    argv = make(tmp_path, run)
    before = _snapshot(tmp_path)
    capsys.readouterr()
    code = cli.main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lili: error: "), err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    assert _snapshot(tmp_path) == before


def test_unknown_env_kwarg_is_named_once(capsys: pytest.CaptureFixture[str],
                                         tmp_path: Path) -> None:
    assert cli.main(_train("--env-kwarg", "colour=red")(tmp_path, tmp_path)) == 2
    err = capsys.readouterr().err
    assert err.count("colour") == 1 and "render_mode" not in err


def test_numbers_in_exponent_form_are_numbers(tmp_path: Path) -> None:
    """YAML 1.1 (PyYAML) reads 1e-3 as a string; configs and --env-kwarg read it as a number."""
    path = tmp_path / "c.yaml"
    path.write_text("lr_actor: 1e-3\nlr_critic: 2E-4\ngamma: 0.9\n")
    config = load_config(path)
    assert (config.lr_actor, config.lr_critic, config.gamma) == (1e-3, 2e-4, 0.9)
    assert cli._parse_kwargs(["step_noise=1e-1", "history=3", "end_on_contact=true"]) == {
        "step_noise": 0.1, "history": 3, "end_on_contact": True}


@pytest.mark.parametrize(("field", "value", "allowed"), [
    ("gamma", False, "a number in [0, 1)"),
    ("gamma", "0.9", "a number in [0, 1)"),
    ("tau", float("nan"), "(0, 1]"),
    ("lr_actor", float("inf"), "a finite number > 0"),
    ("init_alpha", True, "a finite number > 0"),
    ("rep_weight", -1.0, ">= 0"),
    ("latent_dim", 8.0, "an integer >= 1"),
    ("latent_dim", True, "an integer >= 1"),
    ("history", 0, "an integer >= 1"),
    ("hidden", (256.5,), "positive integers"),
    ("hidden", "256", "positive integers"),
    ("phase_feature", 1, "true or false"),
    ("encoder_transitions", 0, "null (= all)"),
    ("target_entropy", float("-inf"), "a finite number or null"),
    ("boundary", 5, "bootstrap, influence"),
    ("buffer_capacity", 10, "an integer >= 20"),
    ("extra", [1], "a mapping of agent name"),
])
def test_agent_config_names_field_and_value(field: str, value: object, allowed: str) -> None:
    with pytest.raises(ValueError) as excinfo:
        AgentConfig(**{field: value})
    message = str(excinfo.value)
    assert f"{field}={value!r}" in message and allowed in message, message


def test_agent_config_names_a_bad_extra_entry() -> None:
    with pytest.raises(ValueError, match=r"extra\.slac=\[1\] is invalid; allowed: a mapping"):
        AgentConfig(extra={"slac": [1]})


def test_agent_config_takes_numpy_numbers_as_python_ones() -> None:
    np = pytest.importorskip("numpy")
    config = AgentConfig(gamma=np.float64(0.9), latent_dim=np.int64(4), hidden=[np.int64(16)])
    assert type(config.gamma) is float and type(config.latent_dim) is int
    assert config.hidden == (16,) and AgentConfig.from_dict(config.to_dict()) == config


def test_check_extra_checks_every_entry_whatever_the_algo() -> None:
    from lili.agents import check_extra

    check_extra(AgentConfig(extra={"slac": {"model_every": 2}, "lilac": {"kl_weight": 0.5}}))
    with pytest.raises(ValueError, match="'bogus'"):
        check_extra(AgentConfig(extra={"slac": {"bogus": 1}}))
    with pytest.raises(ValueError, match="'sac' is not an algo with options; allowed: slac, "
                                         "lilac, oracle-last, lili-categorical"):
        check_extra(AgentConfig(extra={"sac": {}}))
    with pytest.raises(ValueError, match="prior_window=0"):
        check_extra(AgentConfig(extra={"lilac": {"prior_window": 0}}))


def test_check_env_refuses_a_huge_horizon_before_allocating(bad_envs: str) -> None:
    # Before the fix the check drew all actions up front: 89 GiB for this env.
    with pytest.raises(EnvContractError, match="horizon=1000000000 is too long to train on"):
        check_env(f"{bad_envs}:HugeHorizon")


def _lili(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).parent / "lili"
    return subprocess.run([str(exe), *args], capture_output=True, text=True, cwd=cwd,
                          timeout=300)


def test_installed_command_one_line_and_nothing_written(tmp_path: Path,
                                                        trained_run: Path) -> None:
    """The real ``lili`` script (a fresh process, nothing imported yet) on three cases."""
    run = tmp_path / "run"
    shutil.copytree(trained_run, run)
    (run / "checkpoints" / "latest.json").write_text("garbage")
    (tmp_path / "bad.yaml").write_text("gamma: false\n")
    before = _snapshot(tmp_path)
    results = [
        _lili("train", "point-mass", "--seed", "1180591620717411303424", "--out",
              str(tmp_path / "out"), cwd=tmp_path),
        _lili("eval", str(run), cwd=tmp_path),
        _lili("train", "point-mass", "--config", str(tmp_path / "bad.yaml"), "--out",
              str(tmp_path / "out"), cwd=tmp_path),
    ]
    for res, fragment in zip(results, ["--seed=1180591620717411303424", "latest.json is corrupt",
                                       "gamma=False"], strict=True):
        assert res.returncode == 2, res.stderr
        lines = [line for line in res.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("lili: error: ") and fragment in lines[0]
    assert _snapshot(tmp_path) == before
