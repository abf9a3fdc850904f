"""Resume and training fail with one clear message and leave the run folder as it was (issue 11
cases on the training side), and the Python API refuses bad arguments clearly."""

from __future__ import annotations

import hashlib
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml
from _old_configs import add_retired_fields, drop_new_agent_fields
from gymnasium import spaces

from lili import cli
from lili.agents import LILI, SAC
from lili.config import AgentConfig
from lili.envs import RepeatedInteractionEnv
from lili.train import NonFiniteError

SMALL = {"hidden": [16, 16], "enc_hidden": [8, 8], "latent_dim": 2, "warmup_interactions": 2,
         "checkpoint_every": 2, "batch_interactions": 4, "per_interaction": 4,
         "updates_per_step": 0.1}


def _snapshot(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha1(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A 6-interaction Point Mass run (checkpoint at 6) to break in different ways."""
    root = tmp_path_factory.mktemp("resume")
    cfg = root / "small.yaml"
    cfg.write_text(yaml.safe_dump(SMALL))
    args = ["train", "point-mass", "--algo", "lili", "--interactions", "6", "--out",
            str(root / "runs"), "--config", str(cfg), "--no-progress"]
    assert cli.main(args) == 0
    return root / "runs" / "PointMass-v0" / "lili" / "seed_0", args


def _broken_copy(run, tmp_path, edit):
    import shutil

    folder, args = run
    copy = tmp_path / "runs" / "PointMass-v0" / "lili" / "seed_0"
    shutil.copytree(folder, copy)
    edit(copy)
    out_index = args.index("--out") + 1
    args = [*args[:out_index], str(tmp_path / "runs"), *args[out_index + 1:]]
    args[args.index("--interactions") + 1] = "8"
    return copy, [*args, "--resume"]


def _edit_metrics(change):
    def edit(folder):
        path = folder / "metrics.csv"
        lines = path.read_text().splitlines(keepends=True)
        path.write_text("".join(change(lines)))
    return edit


def _cell(lines):
    cells = lines[3].split(",")
    cells[1] = "abc"
    lines[3] = ",".join(cells)
    return lines


def _value(lines):
    cells = lines[3].split(",")
    cells[1] = "123.5"
    lines[3] = ",".join(cells)
    return lines


CASES = [
    ("abc in a metrics.csv cell", _edit_metrics(_cell), ["metrics.csv line 4", "not a number"]),
    ("rows deleted from metrics.csv", _edit_metrics(lambda ls: ls[:1] + ls[4:]),
     ["metrics.csv", "rows were deleted"]),
    ("a return edited in metrics.csv", _edit_metrics(_value), ["metrics.csv line 4",
                                                               "was edited"]),
    ("a column deleted from metrics.csv",
     _edit_metrics(lambda ls: [",".join(x.split(",")[:-1]) + "\n" for x in ls]),
     ["metrics.csv has columns", "expected"]),
    ("corrupt config.yaml", lambda f: (f / "config.yaml").write_text("env: [unclosed\n"),
     ["config.yaml is not valid YAML at line"]),
    ("garbage latest.json", lambda f: (f / "checkpoints" / "latest.json").write_text("{x"),
     ["latest.json is corrupt"]),
    ("corrupt stream part", lambda f: next((f / "checkpoints").glob("ckpt_*/stream.npz"))
     .write_bytes(b"junk"), ["stream.npz is missing or corrupt"]),
    ("corrupt agent part", lambda f: next((f / "checkpoints").glob("ckpt_*/agent.msgpack"))
     .write_bytes(b"junk"), ["is corrupt or not a lili agent file"]),
]


@pytest.mark.parametrize("edit, fragments", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_broken_run_folder_is_one_error_and_stays_as_it_was(run, tmp_path, capsys, edit,
                                                              fragments):
    folder, args = _broken_copy(run, tmp_path, edit)
    before = _snapshot(folder)
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("lili: error: ") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, err
    assert _snapshot(folder) == before  # no config rewrite, no new TensorBoard file


def test_the_intact_copy_resumes(run, tmp_path, capsys):
    folder, args = _broken_copy(run, tmp_path, lambda f: None)
    assert cli.main(args) == 0
    assert "resumed at interaction 6" in capsys.readouterr().out
    assert len((folder / "metrics.csv").read_text().splitlines()) == 9


def _drop_new_agent_fields(folder):
    """config.yaml as a release before the newer agent fields wrote it."""
    path = folder / "config.yaml"
    path.write_text(yaml.safe_dump(drop_new_agent_fields(yaml.safe_load(path.read_text()))))


def test_a_run_written_before_new_config_fields_resumes(run, tmp_path, capsys):
    folder, args = _broken_copy(run, tmp_path, _drop_new_agent_fields)
    assert cli.main(args) == 0
    assert "resumed at interaction 6" in capsys.readouterr().out
    # A field that the stored config sets otherwise is still a difference.
    _, args = _broken_copy(run, tmp_path / "other", lambda f: None)
    path = Path(args[args.index("--config") + 1])
    other = tmp_path / "other.yaml"
    other.write_text(yaml.safe_dump({**yaml.safe_load(path.read_text()), "rep_weight": 0.5}))
    args[args.index("--config") + 1] = str(other)
    assert cli.main(args) == 2
    assert "agent differs" in capsys.readouterr().err


def _add_retired_fields(folder, **values):
    path = folder / "config.yaml"
    path.write_text(yaml.safe_dump(add_retired_fields(yaml.safe_load(path.read_text()),
                                                      **values)))


def test_a_run_with_the_fields_now_in_contrib_resumes_or_names_the_algo(run, tmp_path, capsys):
    """s20-s24 wrote latent_kind etc.: at their defaults the run resumes; a variant's value
    stops with one line naming the contrib algo, before anything is written."""
    folder, args = _broken_copy(run, tmp_path, _add_retired_fields)
    assert cli.main(args) == 0
    assert "resumed at interaction 6" in capsys.readouterr().out
    folder, args = _broken_copy(run, tmp_path / "categorical",
                                lambda f: _add_retired_fields(f, latent_kind="categorical"))
    before = (folder / "metrics.csv").read_bytes()
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert "latent_kind='categorical' moved to lili.contrib: use --algo lili-categorical" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert (folder / "metrics.csv").read_bytes() == before


class _Still:
    """A partner that never changes its mind (the test is about the observation)."""

    strategy_space = spaces.Box(-1, 1, (1,), np.float32)

    def reset(self, rng):
        pass

    def strategy(self):
        return np.zeros(1, np.float32)

    def strategy_id(self):
        return 0

    def update(self, outcome, rng):
        pass


class _Poisoned(RepeatedInteractionEnv):
    """Finite for 3 interactions, then a NaN observation mid-interaction."""

    def __init__(self, render_mode=None):
        super().__init__(render_mode)
        self.horizon, self.partner = 3, _Still()
        self.observation_space = spaces.Box(-1, 1, (1,), np.float32)
        self.action_space = spaces.Box(-1, 1, (1,), np.float32)

    def _begin(self):
        self.x = 0.0
        return np.array([0.0], np.float32)

    def _step(self, action):
        self.x += 0.1 * float(action[0])
        bad = self.interaction >= 3 and self.t == 1
        return np.array([np.nan if bad else self.x], np.float32), -abs(self.x), False

    def _outcome(self):
        return self.x


def test_training_stops_at_the_first_non_finite_observation_keeping_the_checkpoint(tmp_path):
    from lili.runs import RunLogger, latest_checkpoint
    from lili.train import Stream, train

    agent = LILI(_Poisoned(), AgentConfig.from_dict(SMALL))
    stream = Stream.for_agent(agent, agent.env)
    logger = RunLogger(tmp_path, {"algo": "lili"}, 1, 2)
    with pytest.raises(NonFiniteError, match="interaction 3, step 1: the env returned a "
                                             "non-finite observation; training stopped"):
        train(agent, stream, 6, logger=logger)
    logger.close()
    assert latest_checkpoint(tmp_path)[1] == 2
    assert len((tmp_path / "metrics.csv").read_text().splitlines()) == 1 + 3
    assert all(np.all(np.isfinite(x)) for x in __import__("jax").tree_util.tree_leaves(
        agent.state.actor))


@pytest.mark.parametrize("make, fragment", [
    (lambda: LILI(gym.make("lili/PointMass-v0"), "fast"),
     "config='fast' is invalid; allowed: an AgentConfig"),
    (lambda: SAC(gym.make("lili/PointMass-v0"), seed=2**70),
     f"seed={2**70} is invalid; allowed: an integer in [0, 4294967295]"),
    (lambda: SAC(gym.make("lili/PointMass-v0"), seed=-1), "seed=-1 is invalid"),
    (lambda: SAC(42), "env=42 is invalid; allowed: a gymnasium.Env or a registered env id"),
    (lambda: SAC("lili/NoSuch-v0"), "env 'lili/NoSuch-v0' could not be made"),
    (lambda: LILI(gym.make("lili/PointMass-v0"), influence="yes"), "influence='yes' is invalid"),
])
def test_the_python_api_refuses_bad_arguments_clearly(make, fragment):
    with pytest.raises(ValueError) as err:
        make()
    assert fragment in str(err.value)


def test_an_env_id_is_accepted_like_stable_baselines3():
    agent = LILI("lili/PointMass-v0", AgentConfig.from_dict(SMALL), seed=3)
    assert agent.env.spec.id == "lili/PointMass-v0" and agent.seed == 3
