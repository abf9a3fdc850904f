"""Bad input on the command line: one clear message, exit code 2, nothing overwritten."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lili import cli


def _err(capsys, argv):
    code = cli.main(argv)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("argv, match", [
    (["train", "pong"], "unknown env 'pong'; allowed: air-hockey, driving-2d"),
    (["train", "point-mass", "--algo", "ppo"], "unknown algo 'ppo'; allowed: random, sac, slac"),
    (["train", "point-mass", "--interactions", "-5"], "--interactions -5 is invalid"),
    (["train", "point-mass", "--seed", "-1"], "--seed=-1 is invalid"),
    (["train", "point-mass", "--config", "/nonexistent.yaml"], "does not exist"),
    (["train", "point-mass", "--env-kwarg", "step_noise"], "KEY=VALUE"),
    (["train", "point-mass", "--env-kwarg", "step_noise=-1"], "step_noise=-1"),
    (["train", "point-mass", "--env-kwarg", "colour=red"], "unknown env kwarg(s) 'colour'"),
    (["check-env", "nosuchmodule:Env"], "nosuchmodule"),
    (["eval", "/nonexistent"], "not a run folder"),
    (["report", "/nonexistent"], "/nonexistent"),
    (["report", "/nonexistent", "--upto", "0"], "--upto 0 is invalid"),
])
def test_bad_input_exits_2_with_one_message(capsys, tmp_path, argv, match):
    argv = [*argv, "--out", str(tmp_path)] if argv[0] in ("train",) else argv
    code, err = _err(capsys, argv)
    assert code == 2
    assert err.startswith("lili: error: ") and match in err
    assert len(err.strip().splitlines()) == 1


def test_malformed_config(capsys, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("gamma: 2.0\n")
    code, err = _err(capsys, ["train", "point-mass", "--config", str(bad), "--out",
                              str(tmp_path / "o")])
    assert code == 2 and "gamma=2.0" in err and "[0, 1)" in err
    assert not (tmp_path / "o").exists()


def test_existing_run_is_not_overwritten(capsys, tmp_path):
    run = tmp_path / "PointMass-v0" / "sac" / "seed_0"
    run.mkdir(parents=True)
    (run / "metrics.csv").write_text("precious\n")
    code, err = _err(capsys, ["train", "point-mass", "--algo", "sac", "--out", str(tmp_path)])
    assert code == 2 and "--resume" in err
    assert (run / "metrics.csv").read_text() == "precious\n"
    code, err = _err(capsys, ["train", "point-mass", "--algo", "lili", "--out", str(tmp_path),
                              "--resume"])
    assert code == 2 and "no run to resume" in err


def test_corrupt_checkpoint_on_resume(capsys, tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("warmup_interactions: 2\ncheckpoint_every: 2\nhidden: [16, 16]\n")
    base = ["train", "driving-2d", "--algo", "sac", "--interactions", "2", "--out",
            str(tmp_path), "--config", str(cfg), "--no-progress"]
    assert cli.main(base) == 0
    ck = tmp_path / "Driving2D-v0" / "sac" / "seed_0" / "checkpoints" / "ckpt_2"
    (ck / "agent.msgpack").write_bytes(b"garbage")
    before = (ck.parent.parent / "metrics.csv").read_text()
    code, err = _err(capsys, [*base, "--resume"])
    assert code == 2 and "corrupt" in err
    assert (ck.parent.parent / "metrics.csv").read_text() == before
    # A config that differs from the run's is refused too.
    cfg.write_text("warmup_interactions: 2\ncheckpoint_every: 2\nhidden: [32, 32]\n")
    code, err = _err(capsys, [*base, "--resume"])
    assert code == 2 and "agent differs" in err


def test_check_env_command_on_a_registered_env_and_a_broken_one(capsys, tmp_path):
    assert cli.main(["check-env", "lili/PointMass-v0"]) == 0
    assert "passes" in capsys.readouterr().out
    mod = tmp_path / "leaky_env.py"
    mod.write_text(
        "import numpy as np\n"
        "from lili.envs.point_mass import PointMassEnv\n"
        "class Leaky(PointMassEnv):\n"
        "    def __init__(self, **kw):\n"
        "        super().__init__(**kw)\n"
        "        from gymnasium import spaces\n"
        "        self.observation_space = spaces.Box(-1, 1, (4,), np.float32)\n"
        "    def _begin(self):\n"
        "        o = super()._begin()\n"
        "        return np.concatenate([o, self.partner.strategy()]).astype(np.float32)\n"
        "    def _step(self, a):\n"
        "        o, r, d = super()._step(a)\n"
        "        return np.concatenate([o, self.partner.strategy()]).astype(np.float32), r, d\n")
    sys.path.insert(0, str(tmp_path))
    try:
        code, err = _err(capsys, ["check-env", "leaky_env:Leaky"])
    finally:
        sys.path.remove(str(tmp_path))
    assert code == 2 and "observation" in err


def test_console_script_exit_code():
    exe = Path(sys.executable).parent / "lili"
    res = subprocess.run([str(exe), "train", "point-mass", "--algo", "dqn"], capture_output=True,
                         text=True)
    assert res.returncode == 2 and "unknown algo 'dqn'" in res.stderr


def test_eval_video_frames_carry_interaction_strategy_and_return(tmp_path):
    from PIL import Image

    assert cli.main(["train", "point-mass", "--algo", "random", "--interactions", "2", "--out",
                     str(tmp_path), "--no-progress"]) == 0
    run = tmp_path / "PointMass-v0" / "random" / "seed_0"
    gif = tmp_path / "clip.gif"
    assert cli.main(["eval", str(run), "--interactions", "2", "--video", str(gif)]) == 0
    with Image.open(gif) as img:
        frames = []
        for n in range(img.n_frames):
            img.seek(n)
            frames.append(np.asarray(img.convert("RGB")))
    assert len(frames) == 2 * 50 and frames[0].shape == (200 + 40, 200, 3)
    strips = [f[:40] for f in frames]
    assert strips[0].max() > 200  # white text on the black strip (the GIF palette rounds)
    # The return line changes from step to step, the interaction line between interactions.
    assert not np.array_equal(strips[1], strips[2])
    assert not np.array_equal(strips[0][:14], strips[50][:14])
    assert np.array_equal(strips[1][:14], strips[2][:14])


def test_labelled_frames_follow_the_env():
    import gymnasium as gym

    from lili.video import LabelledFrames, frame_label

    env = LabelledFrames(gym.make("lili/Driving2D-v0", render_mode="rgb_array"))
    _, info = env.reset(seed=3)
    total = 0.0
    for _ in range(10):
        _, r, term, trunc, info = env.step(np.array([1.0], np.float32))
        total += r
    assert env.label() == frame_label(0, info["strategy"], info["strategy_id"], total)
    assert env.render().shape == (250 + 40, 150, 3)
    env.reset()
    assert env.label()[0] == "interaction 1" and env.label()[2] == "return 0.00"
    assert frame_label(4, [0.05, -0.1], -1, -1.234) == ["interaction 4", "strategy [0.05 -0.1]",
                                                         "return -1.23"]
    assert frame_label(0, [1.0], 1, 0.0)[1] == "strategy [1] id 1"


def test_argparse_errors_are_one_line_and_help_exits_0(capsys):
    assert cli.main(["train", "point-mass", "--interactions", "1.5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--interactions: invalid int value: '1.5'" in err
    assert cli.main(["eval", "--help"]) == 0


def test_partner_history_that_the_encoder_does_not_read_is_noted(capsys, tmp_path):
    run = tmp_path / "PointMass-v0" / "lili" / "seed_0"
    run.mkdir(parents=True)
    (run / "metrics.csv").write_text("precious\n")
    argv = ["train", "point-mass", "--algo", "lili", "--env-kwarg", "history=5", "--out",
            str(tmp_path)]
    assert cli.main(argv) == 2  # the note comes before the run folder is checked
    out = capsys.readouterr().out
    assert "history=5" in out and "reads the last 1" in out and "history: 5" in out
    cfg = tmp_path / "h.yaml"
    cfg.write_text("history: 5\n")
    assert cli.main([*argv, "--config", str(cfg)]) == 2
    assert "note:" not in capsys.readouterr().out
    # SAC has no encoder: the partner's history is nothing it could match.
    sac = tmp_path / "PointMass-v0" / "sac" / "seed_0"
    sac.mkdir(parents=True)
    (sac / "metrics.csv").write_text("precious\n")
    assert cli.main(["train", "point-mass", "--algo", "sac", "--env-kwarg", "history=5",
                     "--out", str(tmp_path)]) == 2
    assert "note:" not in capsys.readouterr().out
