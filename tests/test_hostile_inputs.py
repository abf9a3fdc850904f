"""Hostile inputs of issue 35 (items 8-16), rerun: every one gives ONE line ``lili: error: ...``
of at most a few hundred characters, exit code 2 and nothing written; env failures inside a
loop name the env, the interaction and the step. The table of cases and outcomes is in
docs/bad-input.md.

The commands run in-process through ``lili.cli.main`` against real files, a real run folder, real
envs, a real Pendulum-v1 and real TensorBoard files read back with TensorBoard's own reader.
"""

from __future__ import annotations

import csv
import shutil
import socket
import time
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from _env_modules import importable

# The same record of a folder's files, and the same 2-interaction run of the random agent.
from test_bad_input import _snapshot, trained_run  # noqa: F401 - trained_run is a fixture

from lili import cli
from lili.agents.registry import config_for
from lili.errors import MAX_LINE_CHARS, bounded, shown
from lili.yaml_bounds import YAMLTooLarge, check_yaml, safe_load

ENVS = '''
"""Envs that fail in the middle of a run, each in its own way."""
import numpy as np

from lili.envs.point_mass import PointMassEnv

KILL_AT = None  # the interaction at which KilledAt stops the process (Ctrl-C)


class StepRaises(PointMassEnv):
    def _step(self, a):
        if self.interaction == 2 and self.t == 3:
            raise RuntimeError("the simulator diverged")
        return super()._step(a)


class ObsBecomesText(PointMassEnv):
    def _step(self, a):
        o, r, d = super()._step(a)
        return ("lost" if self.interaction == 2 else o), r, d


class ObsChangesShape(PointMassEnv):
    def _step(self, a):
        o, r, d = super()._step(a)
        return (np.append(o, 0.0) if self.interaction == 2 else o), r, d


class OwnValueError(PointMassEnv):
    def _step(self, a):
        if self.interaction == 2:
            raise ValueError("speed=-1 is invalid; allowed: a positive speed")
        return super()._step(a)


class KilledAt(PointMassEnv):
    def _step(self, a):
        if self.interaction == KILL_AT:
            raise KeyboardInterrupt
        return super()._step(a)
'''

# 342 bytes that name 9**9 values through nested aliases ("billion laughs").
LAUGHS = ('a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [" + ",".join([f"*{chr(97 + i)}"] * 9) + "]\n"
    for i in range(8)))
LAUGHS_VALUE = "[" + ", ".join([f"&a{i} [" + ",".join(
    ["*a" + str(i - 1) if i else "1"] * 9) + "]" for i in range(9)]) + "]"
HUGE = "x" * 10_000_000


@pytest.fixture(scope="module")
def envs(tmp_path_factory: pytest.TempPathFactory):
    with importable(tmp_path_factory.mktemp("envs"), "lili_hostile_envs", ENVS) as module:
        yield module


def _train(*flags: str) -> Callable[[Path, Path], list[str]]:
    return lambda tmp, run: ["train", "point-mass", "--algo", "random", "--interactions", "1",
                             "--no-progress", "--out", str(tmp / "out"), *flags]


def _reproduce(*flags: str) -> Callable[[Path, Path], list[str]]:
    return lambda tmp, run: ["reproduce", "quickstart", "--quick", "--no-progress", "--out",
                             str(tmp / "out"), *flags]


def _config(text: str) -> Callable[[Path, Path], list[str]]:
    def make(tmp: Path, run: Path) -> list[str]:
        (tmp / "c.yaml").write_text(text)
        return _train("--config", str(tmp / "c.yaml"))(tmp, run)
    return make


def _run_file(name: str, content: str | bytes, *argv: str) -> Callable[[Path, Path], list[str]]:
    """Replace a file of the run folder, then run ``argv`` (RUN: the run folder)."""
    def make(tmp: Path, run: Path) -> list[str]:
        path = run / name
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)
        return [str(run) if a == "RUN" else a for a in argv]
    return make


def _other_algo(tmp: Path, run: Path) -> list[str]:
    """A run whose config says sac while its checkpoint holds the random agent (what copying a
    SAC checkpoint into another run's folder gives)."""
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    (run / "config.yaml").write_text(yaml.safe_dump({**cfg, "algo": "sac"}, sort_keys=False))
    return ["eval", str(run), "--interactions", "1"]


# (case, argv maker, fragments the one line must contain)
CASES = [
    # 9: hostile YAML, refused before it is built; long values cut
    ("--config billion laughs", _config(LAUGHS + "gamma: *i\n"),
     ["c.yaml", "more than 10000 values", "allowed: at most 10000"]),
    ("--env-kwarg billion laughs", _train("--env-kwarg", f"step_noise={LAUGHS_VALUE}"),
     ["--env-kwarg", "more than 10000 values"]),
    ("reproduce --env-kwarg billion laughs", _reproduce("--env-kwarg", f"aim={LAUGHS_VALUE}"),
     ["--env-kwarg", "more than 10000 values"]),
    ("reproduce --set billion laughs", _reproduce("--set", f"gamma={LAUGHS_VALUE}"),
     ["--set", "more than 10000 values"]),
    ("--env-kwarg recursive alias", _train("--env-kwarg", "step_noise=&a [*a]"),
     ["recursive"]),
    ("--env-kwarg nested 200 deep", _train("--env-kwarg", "step_noise=" + "[" * 200 + "]" * 200),
     ["deeper than 50"]),
    ("--env-kwarg 10 MB value", _train("--env-kwarg", f"step_noise={HUGE}"),
     ["10000000 characters long", "allowed: at most 10000"]),
    ("--set 10 MB value", _reproduce("--set", f"gamma={HUGE}"),
     ["--set", "characters", "allowed: at most 10000"]),
    ("--set 9000-character value", _reproduce("--set", "gamma=" + "y" * 9000),
     ["gamma=", "characters in all", "allowed: a number in [0, 1)"]),
    ("--config 9000-character value", _config("gamma: " + "y" * 9000 + "\n"),
     ["gamma=", "allowed: a number in [0, 1)"]),
    ("10 MB unknown flag", lambda tmp, run: ["train", "point-mass", "--" + HUGE],
     ["unrecognized arguments", "allowed flags of lili train"]),
    # 10: unbounded sizes
    ("reproduce --seeds 10**9 --dry-run", _reproduce("--seeds", str(10**9), "--dry-run"),
     ["--seeds 1000000000", "[1, 1000]"]),
    ("reproduce --jobs 10**12 --dry-run", _reproduce("--jobs", str(10**12), "--dry-run"),
     ["--jobs 1000000000000", "[1, 1024]"]),
    ("reproduce --interactions 10**12", _reproduce("--interactions", str(10**12), "--dry-run"),
     ["--interactions 1000000000000", "[1, 10000000]"]),
    ("train --interactions 10**12", _train("--interactions", str(10**12)),
     ["--interactions 1000000000000", "[1, 10000000]"]),
    ("eval --interactions 10**12", lambda tmp, run: ["eval", str(run), "--interactions",
                                                     str(10**12)], ["[1, 10000000]"]),
    # 11: Ray addresses, checked before anything is written
    ("--ray 127.0.0.1:1", _reproduce("--ray", "127.0.0.1:1"),
     ["127.0.0.1:1", "nothing answers", "running `ray start --head`"]),
    ("--ray 'not an address'", _reproduce("--ray", "not an address"),
     ["'not an address' is invalid", "allowed: HOST:PORT"]),
    ("--ray 127.0.0.1:99999", _reproduce("--ray", "127.0.0.1:99999"), ["is invalid"]),
    # 12: eval of a checkpoint of another algo
    ("eval, checkpoint of another algo", _other_algo,
     ["holds a 'random' agent", "is 'sac'"]),
    # 15: unclear messages
    ("train --out /sys/x", lambda tmp, run: _train()(tmp, run)[:-1] + ["/sys/x"],
     ["--out '/sys/x'", "not writable", "allowed: a folder you can write to"]),
    ("report, malformed config.yaml", _run_file("config.yaml", "env: [a\nalgo: random\n",
                                                "report", "RUN"),
     ["config.yaml", "not valid YAML", "line 2"]),
    ("report, billion-laughs config.yaml", _run_file("config.yaml", LAUGHS, "report", "RUN"),
     ["config.yaml", "more than 10000 values"]),
    ("report, random bytes in metrics.csv",
     _run_file("metrics.csv", bytes(range(128, 256)) * 4, "report", "RUN"),
     ["metrics.csv", "not UTF-8"]),
    ("train --resume, random bytes in metrics.csv",
     _run_file("metrics.csv", bytes(range(128, 256)) * 4, "train", "point-mass", "--algo",
               "random", "--interactions", "3", "--out", "OUT", "--resume"),
     ["metrics.csv", "not UTF-8"]),
    ("reproduce --upto 5", _reproduce("--upto", "5"),
     ["unrecognized arguments: --upto 5", "allowed flags of lili reproduce", "--seeds",
      "lili reproduce --help"]),
]


@pytest.mark.parametrize(("make", "fragments"), [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_hostile_input_one_short_line_exit_2_nothing_written(
        make: Callable[[Path, Path], list[str]], fragments: list[str], tmp_path: Path,
        trained_run: Path, envs,  # noqa: F811 - the fixture imported above
        capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "base" / "PointMass-v0" / "random" / "seed_0"
    shutil.copytree(trained_run, run)
    argv = make(tmp_path, run)
    argv = [str(tmp_path / "base") if a == "OUT" else a for a in argv]
    before = _snapshot(tmp_path)
    capsys.readouterr()
    code = cli.main(argv)
    err = capsys.readouterr().err
    assert code == 2, err[:1000]
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lili: error: "), err[:1000]
    assert len(lines[0]) <= MAX_LINE_CHARS, lines[0]
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    assert _snapshot(tmp_path) == before


SMALL_SAC = "warmup_interactions: 2\nhidden: [8]\nbatch_interactions: 2\nper_interaction: 2\n"


@pytest.mark.parametrize(("cls", "algo", "fragments"), [
    ("StepRaises", "random", ["interaction 2, step 3", "step() raised RuntimeError: the "
                              "simulator diverged"]),
    ("ObsBecomesText", "random", ["interaction 2, step 0", "'lost'", "not an array of numbers"]),
    # SAC acts on its own from interaction 2: without the check, JAX's broadcasting error.
    ("ObsChangesShape", "sac", ["interaction 2, step 0", "shape (3,)", "has shape (2,)"]),
    ("OwnValueError", "random", ["interaction 2, step 0", "raised ValueError: speed=-1 is "
                                 "invalid"]),
])
def test_an_env_failing_in_training_is_one_line_naming_env_interaction_and_step(
        cls: str, algo: str, fragments: list[str], tmp_path: Path, envs,
        capsys: pytest.CaptureFixture[str]) -> None:
    spec = f"lili_hostile_envs:{cls}"
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(config_for(algo, yaml.safe_load(SMALL_SAC))))
    code = cli.main(["train", spec, "--algo", algo, "--interactions", "4", "--no-progress",
                     "--out", str(tmp_path), "--config", str(tmp_path / "c.yaml")])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"lili: error: env {spec}, "), err
    assert len(lines[0]) <= MAX_LINE_CHARS
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    # The interactions before the failure stay logged.
    with (tmp_path / f"lili_hostile_envs_{cls}" / algo / "seed_0" / "metrics.csv").open() as f:
        assert len(list(csv.reader(f))) == 3


def test_an_env_failing_in_eval_is_the_same_one_line(tmp_path: Path, envs,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    spec = "lili_hostile_envs:StepRaises"
    assert cli.main(["train", spec, "--algo", "random", "--interactions", "2", "--no-progress",
                     "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    code = cli.main(["eval", str(tmp_path / "lili_hostile_envs_StepRaises" / "random" /
                                 "seed_0"), "--interactions", "4"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert f"env {spec}, interaction 2, step 3: step() raised RuntimeError" in err


def test_report_of_an_env_without_a_strategy(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    """Item 8: the README's Pendulum-v1, trained and reported."""
    out = tmp_path / "pend"
    assert cli.main(["train", "Pendulum-v1", "--algo", "sac", "--interactions", "3",
                     "--no-progress", "--out", str(out)]) == 0
    with (out / "Pendulum-v1" / "sac" / "seed_0" / "metrics.csv").open() as f:
        assert not any(c.startswith("strategy_") and c != "strategy_id"
                       for c in next(csv.reader(f)))
    capsys.readouterr()
    assert cli.main(["report", str(out)]) == 0, capsys.readouterr().err
    assert "| SAC | 1 |" in capsys.readouterr().out
    assert (out / "report" / "results.md").is_file()


def _tb_returns(run: Path) -> list[tuple[int, float]]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    acc = EventAccumulator(str(run / "tb"), purge_orphaned_data=False)
    acc.Reload()
    return [(e.step, e.value) for e in acc.Scalars("interaction/return")]


def _csv_returns(run: Path) -> list[tuple[int, float]]:
    with (run / "metrics.csv").open() as f:
        return [(int(r["interaction"]), float(r["return"])) for r in csv.DictReader(f)]


@pytest.mark.parametrize(("kill_at", "every", "resumed_at"), [(1, 100, None), (3, 2, 2)])
def test_tensorboard_after_a_resume_holds_what_metrics_csv_holds(
        kill_at: int, every: int, resumed_at: int | None, tmp_path: Path, envs,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Item 14: a run killed (before its first checkpoint, or after one) and resumed leaves one
    TensorBoard point per interaction, in order, each the return metrics.csv logged; read with
    TensorBoard's reader with purging off, so stale events would count."""
    (tmp_path / "c.yaml").write_text(f"checkpoint_every: {every}\n")
    argv = ["train", "lili_hostile_envs:KilledAt", "--algo", "random", "--interactions", "5",
            "--no-progress", "--out", str(tmp_path), "--config", str(tmp_path / "c.yaml")]
    envs.KILL_AT = kill_at
    try:
        assert cli.main(argv) == 130
    finally:
        envs.KILL_AT = None
    run = tmp_path / "lili_hostile_envs_KilledAt" / "random" / "seed_0"
    assert [s for s, _ in _tb_returns(run)] == list(range(kill_at))
    assert cli.main([*argv, "--resume"]) == 0
    out = capsys.readouterr().out
    assert (f"resumed at interaction {resumed_at}" in out) == (resumed_at is not None)
    tb, logged = _tb_returns(run), _csv_returns(run)
    assert [s for s, _ in tb] == list(range(5)) == [s for s, _ in logged]
    assert [v for _, v in tb] == pytest.approx([v for _, v in logged], rel=1e-5)


def test_a_callback_returning_false_stops_training() -> None:
    """Item 16: as in Stable-Baselines3; None (a callback that returns nothing) goes on."""
    from lili.agents import make_agent
    from lili.config import AgentConfig
    from lili.envs.point_mass import PointMassEnv
    from lili.train import Stream, train

    agent = make_agent("random", PointMassEnv(), AgentConfig(), 0)
    stream = Stream.for_agent(agent, agent.env)
    seen: list[int] = []
    rows = train(agent, stream, 10, callback=lambda row: seen.append(row["interaction"])
                 or row["interaction"] < 2)
    assert seen == [0, 1, 2] and len(rows) == 3 and stream.count == 3
    rows = train(agent, stream, 2, callback=lambda row: None)
    assert stream.count == 5
    # The same through the facade's learn().
    agent.learn(10, callback=lambda row: row["interaction"] < 6)
    assert agent.stream.count == 7


def test_strategies_are_named_by_the_env() -> None:
    """Item 16: strategies.png's bars carry the env's own strategy names."""
    from lili.report.stats import strategy_names

    assert strategy_names("lili/Driving2D-v0", 2) == ["left lane", "right lane"]
    assert strategy_names("lili/LunarLander-v0", 2) == ["left pad", "right pad"]
    assert strategy_names("lili/AirHockey-v0", 3) == ["left", "middle", "right"]
    assert strategy_names("lili/InfluenceSwitch-v0", 2) == ["id 0", "id 1"]
    assert strategy_names("no_such_module:Env", 2) == ["id 0", "id 1"]


def test_the_bounded_formatters() -> None:
    nested: list = [1] * 9
    for _ in range(9):
        nested = [nested] * 9  # 9**10 values: a full repr would not end
    assert len(shown(nested)) <= 130 and len(shown(HUGE)) <= 130
    assert "(10000000 characters)" in shown(HUGE)
    line = bounded(f"gamma={HUGE} is invalid; allowed: a number in [0, 1)")
    assert len(line) == MAX_LINE_CHARS and line.endswith("allowed: a number in [0, 1)")
    assert bounded("a\nb") == "a\nb"


def test_yaml_bounds_refuse_before_building_and_keep_small_aliases() -> None:
    t0 = time.perf_counter()
    with pytest.raises(YAMLTooLarge, match="more than 10000 values"):
        safe_load(LAUGHS)
    with pytest.raises(YAMLTooLarge, match="more than 10000 values"):
        check_yaml(LAUGHS_VALUE)
    assert time.perf_counter() - t0 < 5
    assert safe_load("a: &x [1, 2]\nb: *x\n") == {"a": [1, 2], "b": [1, 2]}
    check_yaml("gamma: 0.9\n")
    check_yaml("[1, 2")  # malformed YAML is the loader's to report, with its line


def test_a_listening_address_passes_the_ray_check() -> None:
    """Item 11: the check only opens a TCP connection (a real Ray head answers the same way);
    a closed port fails at once."""
    from lili.experiments.ray_backend import check_address

    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        check_address(f"127.0.0.1:{port}")
        check_address(f"ray://localhost:{port}")
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="nothing answers"):
        check_address(f"127.0.0.1:{port}")
    assert time.perf_counter() - t0 < 5
