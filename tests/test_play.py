"""lili play: the person's aim as the striker, the adapter's latent updates, the session's record,
the probe, the bot and the command line (real env, real agent, real files)."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

import lili.envs  # noqa: F401 - registers the ids
from lili import cli
from lili.envs.air_hockey.env import NEXT_MODE, TARGET_X
from lili.play.origin import OriginPolicy, check_origin
from lili.play.policy import Blocker, interaction_steps
from lili.play.probe import ModeProbe, collect_latents
from lili.play.protocol import ProtocolError, RateLimiter, parse_message
from lili.play.record import Recorder, RecordError
from lili.play.session import GameSession, make_play_env
from lili.play.striker import (
    AIM_LIMIT,
    MODE_NAMES,
    AimedStriker,
    BotConfig,
    BotStriker,
    mode_aims,
)

# Small networks keep the (untrained) test agent quick to build; the page treats it like any.
SMALL = {"hidden": [32, 32], "enc_hidden": [32, 32]}


def untrained_agent_file(factory: pytest.TempPathFactory) -> Path:
    """An untrained LILI saved with ``agent.save`` (made once per test session)."""
    path = factory.getbasetemp() / "play_agent" / "lili_air_hockey.msgpack"
    if not path.is_file():
        from lili.agents import make_agent

        agent = make_agent("lili", gym.make("lili/AirHockey-v0"), SMALL, seed=0)
        agent.save(path)
    return path


def make_run_folder(root: Path, agent_file: Path, env: str = "lili/AirHockey-v0",
                    algo: str = "lili") -> Path:
    """A run folder in the layout of ``lili train`` holding ``agent_file`` as its checkpoint."""
    run = root / "run"
    ck = run / "checkpoints" / "ckpt_0"
    ck.mkdir(parents=True)
    shutil.copy(agent_file, ck / "agent.msgpack")
    (run / "checkpoints" / "latest.json").write_text(json.dumps({"checkpoint": "ckpt_0",
                                                                "interactions": 0}))
    (run / "config.yaml").write_text(yaml.safe_dump({"env": env, "env_kwargs": {},
                                                     "algo": algo, "seed": 0,
                                                     "interactions": 0, "agent": {}}))
    return run


@pytest.fixture(scope="module")
def agent_file(tmp_path_factory):
    return untrained_agent_file(tmp_path_factory)


@pytest.fixture(scope="module")
def blocker(agent_file):
    return Blocker.load(agent_file, make_play_env({}))


def _arrival_x(aim: float) -> float:
    """Where a shot aimed at ``aim`` crosses the ego's line, with the ego's paddle held still."""
    env = make_play_env({})
    striker = AimedStriker()
    env.unwrapped.partner = striker
    striker.aim(aim)
    env.reset(seed=0)
    done = False
    while not done:
        _, _, term, trunc, _ = env.step(np.zeros(1, np.float32))
        done = term or trunc
    return float(env.unwrapped.puck[0])


def test_a_persons_aim_is_the_envs_shot():
    aims = mode_aims()
    assert aims[1] == 0.0 and aims[0] == pytest.approx(-aims[2]) and aims[0] < -0.3
    # A mode's own aim is the robot striker's noise-free shot: it lands on the mode's target.
    for mode in range(3):
        assert _arrival_x(aims[mode]) == pytest.approx(TARGET_X[mode], abs=0.02)
    # Any other aim is the same physics: a direct shot crosses 1.5 m further at 1.5 tan(aim).
    for aim in (-0.15, 0.1):
        assert _arrival_x(aim) == pytest.approx(1.5 * np.tan(aim), abs=0.01)
    s = AimedStriker()
    assert [s.aim(a) for a in (-0.5, -0.25, -0.15, 0.0, 0.15, 0.25, AIM_LIMIT)] == \
        [0, 0, 1, 1, 1, 2, 2]
    for bad in (AIM_LIMIT + 0.01, float("nan")):
        with pytest.raises(ValueError, match="aim="):
            s.aim(bad)


def test_session_replays_evaluate_exactly(blocker):
    """Shots aimed where the robot striker aimed give evaluate()'s returns: same physics, same
    acting, same latent updates z^{i+1} = E(tau^i)."""
    from lili.evaluate import evaluate

    n, seed = 6, 3
    ref = evaluate(blocker.agent, gym.make("lili/AirHockey-v0"), n_interactions=n, seed=seed)
    env, game = make_play_env({}), blocker.new_game()
    obs, _ = env.reset(seed=seed)
    aims, latents = [], []
    for _ in range(n):
        robot = env.unwrapped.partner
        aims.append(mode_aims()[robot.mode] + robot.aim_offset)
        latents.append(game.latent)
        for _step in interaction_steps(env, game, obs):
            pass
        obs, _ = env.reset()
        game.end_interaction(obs)
    session = GameSession(blocker, {}, n)
    results = [session.play(aim) for aim in aims]
    np.testing.assert_allclose([r["reward"] for r in results], ref["returns"], atol=1e-4)
    assert [r["mode"] for r in results] == [MODE_NAMES[m] for m in ref["strategy_ids"]]
    assert np.all(latents[0] == 0) and not np.allclose(latents[1], 0)
    assert np.allclose(session.game.latent, game.latent)


def test_session_scores_and_records(blocker, tmp_path):
    rec = Recorder(folder=tmp_path / "sessions").session()
    session = GameSession(blocker, {}, 3, rec)
    frames = list(session.shoot(-0.4))
    assert frames[0]["type"] == "frame" and frames[0]["t"] == 0
    assert frames[0]["puck"] == pytest.approx([0.0, 0.6])
    result = frames[-1]
    assert result["type"] == "result" and result["mode"] == "left"
    assert len(frames) == result["steps"] + 2
    session.play(0.0)
    last = session.play(0.4)
    assert last["done"] and session.over
    assert last["score"]["shots"] == 3
    assert [last["score"]["by_mode"][m][1] for m in ("left", "middle", "right")] == [1, 1, 1]
    with pytest.raises(ValueError, match="game is over"):
        session.play(0.0)
    rows = list(csv.DictReader(rec.path.open()))
    assert [r["mode"] for r in rows] == ["left", "middle", "right"]
    assert [float(r["aim"]) for r in rows] == [-0.4, 0.0, 0.4]
    assert sum(int(r["blocked"]) for r in rows) == last["score"]["blocks"]
    assert list(rows[0]) == ["session", "shot", "aim", "mode", "blocked", "reward", "puck_x",
                             "paddle_x"]


def test_a_shot_counts_only_once_recorded(blocker, tmp_path):
    """A row that cannot be written ends the game there: the shot is not counted, and the rows
    before it stay as they were (here the session's folder is replaced by a file mid-game)."""
    folder = tmp_path / "sessions"
    session = GameSession(blocker, {}, 5, Recorder(folder=folder).session())
    assert session.belief() is None  # nothing to believe before the first shot
    session.play(-0.4)
    session.play(0.4)
    kept = tmp_path / "kept"
    folder.rename(kept)
    folder.write_text("not a folder\n")
    with pytest.raises(RecordError, match="could not record shot 3 in .*sessions"):
        session.play(0.0)
    assert session.over and session.shot == 2 and "could not record shot 3" in session.ended
    assert session.score()["shots"] == 2 and session.score()["goals"] == \
        2 - session.score()["blocks"]
    rows = list(csv.DictReader(next(kept.glob("session-*.csv")).open()))
    assert [r["shot"] for r in rows] == ["1", "2"]
    with pytest.raises(ValueError, match="game is over \\(2 of 5 shots played\\)"):
        session.play(0.0)
    session.close()


def test_recorder_never_overwrites_and_checks_the_folder_at_start(tmp_path):
    existing = tmp_path / "taken.csv"
    existing.write_text("x\n")
    with pytest.raises(ValueError, match="already exists"):
        Recorder(file=existing)
    with pytest.raises(ValueError, match="does not exist"):
        Recorder(file=tmp_path / "nope" / "a.csv")
    for folder in (existing, existing / "below"):  # a file where the folder should be
        with pytest.raises(ValueError, match="the recording folder .*taken.csv.* is a file"):
            Recorder(folder=folder)
    assert existing.read_text() == "x\n"
    Recorder(folder=tmp_path / "new" / "sessions")  # made at the first shot, not before
    assert not (tmp_path / "new").exists()


def test_probe_reads_modes_off_latents():
    rng = np.random.default_rng(0)
    modes = rng.integers(0, 3, 300)
    centres = rng.normal(0, 1, (3, 8))
    zs = (centres[modes] + 0.3 * rng.normal(0, 1, (300, 8))).astype(np.float32)
    probe = ModeProbe(zs, modes)
    assert probe.accuracy > 0.95
    b = probe.belief(centres[2])
    assert np.argmax(b["probs"]) == 2 and sum(b["probs"]) == pytest.approx(1, abs=0.01)
    # Latents that carry nothing about the mode give a probe near chance, not a good one.
    assert ModeProbe(rng.normal(0, 1, (300, 8)), modes).accuracy < 0.55
    assert len(probe.summary()["points"]) == 300


def test_probe_on_the_blocker(blocker):
    probe = ModeProbe.for_blocker(blocker, {}, n=40, seed=1)
    assert probe is not None and probe.n_fit == 28 and probe.n_test == 12
    # Fitted on the blocker's own latents, each paired with the mode of its interaction, and
    # scored on the 12 it was not fitted on: the share of them whose mode it predicts.
    zs, modes = collect_latents(blocker, {}, 40, seed=1)
    assert [p["mode"] for p in probe.points] == modes.tolist()
    predicted = [int(np.argmax(probe.belief(z)["probs"])) for z in zs[28:]]
    assert probe.accuracy == np.mean(np.array(predicted) == modes[28:])


def test_bot_aims_away_from_the_last_block():
    bot = BotStriker(BotConfig(aim_noise=0.0, lapse=0.0), seed=1)
    for mode, side in [(0, -1), (1, 1), (2, -1), (2, 1)]:
        bot.mode = mode
        bot.observe(mode, side)
        assert bot.mode == NEXT_MODE[(mode, side)]
        assert bot.next_aim() == mode_aims()[bot.mode]
    still = BotStriker(BotConfig(lapse=0.0, reaction=0.0), seed=1)
    still.observe(2, -1)
    assert still.mode == 2
    noisy = BotStriker(BotConfig(aim_noise=0.05), seed=2)
    noisy.mode = 1
    assert np.std([noisy.next_aim() for _ in range(400)]) == pytest.approx(0.05, rel=0.15)
    for bad in ({"aim_noise": -0.1}, {"lapse": 2.0}, {"reaction": float("nan")},
                {"aim_noise": True}):
        with pytest.raises(ValueError, match="bot "):
            BotConfig(**bad)


def test_bot_session_is_deterministic_and_follows_the_rule(blocker, tmp_path):
    from lili.play.bot import run_bot

    cfg = BotConfig(aim_noise=0.03, lapse=0.0)
    rec = Recorder(folder=tmp_path).session()
    a = run_bot(blocker, {}, 12, cfg, seed=4, record=rec)
    b = run_bot(blocker, {}, 12, cfg, seed=4)
    assert [r["reward"] for r in a["rows"]] == [r["reward"] for r in b["rows"]]
    assert a["shots"] == 12 and len(list(csv.DictReader(rec.path.open()))) == 12
    names = ["left", "middle", "right"]
    for prev, nxt in zip(a["rows"], a["rows"][1:], strict=False):
        assert names.index(nxt["mode"]) == NEXT_MODE[(names.index(prev["mode"]), prev["side"])]


def test_scripted_blockers_give_the_bots_ceiling():
    """Told the shot's mode, the greedy blocker blocks every noise-free shot of the bot and
    misses only through aim noise; the middle one (not told) blocks middle shots only."""
    from lili.play.bot import run_bot
    from lili.play.policy import ScriptedBlocker

    exact = run_bot(ScriptedBlocker("greedy"), {}, 20, BotConfig(aim_noise=0.0, lapse=0.3))
    assert exact["blocks"] == 20 and {r["mode"] for r in exact["rows"]} == set(MODE_NAMES)
    noisy = run_bot(ScriptedBlocker("greedy"), {}, 20, BotConfig(aim_noise=0.1, lapse=0.0))
    assert noisy["blocks"] < 18
    middle = run_bot(ScriptedBlocker("middle"), {}, 20, BotConfig(aim_noise=0.0, lapse=0.3))
    assert middle["blocks"] == middle["by_mode"]["middle"][1] > 0
    with pytest.raises(ValueError, match="scripted blocker 'oracle' is unknown; allowed: "):
        ScriptedBlocker("oracle")


def test_the_predictor_plays_on_the_last_shot_through_the_session():
    """Told only the last shot's mode and side (the session wraps its env for it), the
    predictor blocks every noise-free bot shot it can predict: all but the first (it holds the
    middle with nothing to go on), and fewer when the bot lapses."""
    from lili.play.bot import run_bot
    from lili.play.policy import ScriptedBlocker

    exact = run_bot(ScriptedBlocker("predictor"), {}, 20, BotConfig(aim_noise=0.0, lapse=0.0))
    assert [r["blocked"] for r in exact["rows"][1:]] == [1] * 19
    lapsing = run_bot(ScriptedBlocker("predictor"), {}, 40, BotConfig(aim_noise=0.0, lapse=0.5))
    assert 20 <= lapsing["blocks"] <= 36


def test_a_blocker_trained_with_the_side_revealed_plays_on_its_own_game(tmp_path):
    """The session builds the run's env (here ``reveal_side=True``), so the encoder reads the
    side in each shot's last observation as in training; the plain game does not fit it."""
    from lili.agents import CheckpointError, make_agent
    from lili.play.bot import run_bot

    kwargs = {"reveal_side": True}
    make_agent("lili", gym.make("lili/AirHockey-v0", **kwargs), SMALL, seed=0).save(
        tmp_path / "a.msgpack")
    blocker = Blocker.load(tmp_path / "a.msgpack", make_play_env(kwargs))
    session = GameSession(blocker, kwargs, 2)
    assert session.env.observation_space.shape == (3,) == (blocker.agent.obs_dim,)
    first = session.play(0.0)
    assert first["side"] in (-1, 1) and not np.allclose(session.game.latent, 0)
    result = run_bot(blocker, kwargs, 3, BotConfig(aim_noise=0.03, lapse=0.0), seed=1)
    assert result["shots"] == 3
    with pytest.raises(CheckpointError):
        Blocker.load(tmp_path / "a.msgpack", make_play_env({}))


def test_lagged_agents_play_and_the_oracle_is_refused(tmp_path):
    """The last-interaction Oracle acts on the session's env wrapped as in training (the last
    shot appended); the Oracle, told each shot's mode before it is played, is refused."""
    from lili.agents import make_agent
    from lili.agents.registry import config_for
    from lili.play.bot import run_bot

    env = gym.make("lili/AirHockey-v0")
    for algo, config in (("oracle-last", {**SMALL, "extra": {"oracle-last": {"outcome": True}}}),
                         ("oracle", SMALL)):
        make_agent(algo, env, config_for(algo, config), seed=0).save(tmp_path / f"{algo}.msgpack")
    lagged = Blocker.load(tmp_path / "oracle-last.msgpack", make_play_env({}))
    session = GameSession(lagged, {}, 3)
    assert session.env.observation_space.shape == (9,) and lagged.latent_dim == 0
    result = run_bot(lagged, {}, 4, BotConfig(aim_noise=0.03, lapse=0.0), seed=1)
    assert result["shots"] == 4 and len(result["rows"]) == 4
    with pytest.raises(ValueError, match="'oracle' agent, told each shot's mode before it is "
                                         "played.*allowed: every algo but oracle"):
        Blocker.load(tmp_path / "oracle.msgpack", make_play_env({}))


@pytest.mark.parametrize("raw, match", [
    (b"\x00\x01", "binary"),
    ("x" * 1025, "too long"),
    ("{nope", "not valid JSON"),
    ("[" * 500 + "]" * 500, "JSON list"),
    ('{"type": "shoot", "aim": NaN}', "NaN is not allowed"),
    ('[1, 2]', "JSON list"),
    ('{"aim": 0.1}', "lacks type"),
    ('{"type": 3, "aim": 0.1}', "type '3' is unknown"),
    ('{"type": "jump"}', "'jump' is unknown"),
    ('{"type": "shoot"}', "lacks aim"),
    ('{"type": "shoot", "aim": 0.1, "power": 3}', "unknown fields \\['power'\\]"),
    ('{"type": "shoot", "aim": "0.1"}', "aim 0.1 is invalid"),
    ('{"type": "shoot", "aim": true}', "aim True is invalid"),
    ('{"type": "shoot", "aim": 0.9}', "aim 0.9 is invalid; allowed: a number of radians"),
    ('{"type": "shoot", "aim": 1e400}', "aim inf is invalid"),
    ('{"type": "shoot", "aim": 1' + "0" * 309 + "}", "aim \\(an integer of 310 digits\\) is "
     "invalid"),
    ('{"type": "shoot", "aim": -1' + "0" * 900 + "}", "an integer of 901 digits"),
    ('{"type": "shoot", "aim": 1}', "aim 1 is invalid"),
    ('{"type": 1' + "0" * 500 + "}", "type '\\(an integer of 501 digits\\)' is unknown"),
])
def test_protocol_rejects_with_a_message(raw, match):
    with pytest.raises(ProtocolError, match=match):
        parse_message(raw)


@pytest.mark.parametrize("origin, host, refused", [
    ("http://127.0.0.1:8000", "127.0.0.1:8000", None),
    ("http://localhost:8000", "localhost:8000", None),
    ("http://[::1]:8000", "[::1]:8000", None),
    ("http://LOCALHOST:8000", "localhost:8000", None),
    ("http://evil.example", "127.0.0.1:8000", "Origin 'http://evil.example' is not this page's"),
    ("http://127.0.0.1:8001", "127.0.0.1:8000", "is not this page's"),
    ("https://127.0.0.1:8000", "127.0.0.1:8000", "is not this page's"),
    ("null", "127.0.0.1:8000", "Origin 'null'"),
    (None, "127.0.0.1:8000", "no Origin header"),
    ("http://127.0.0.1:8000", "evil.example:8000", "Host 'evil.example:8000' is not this "
     "server's"),  # DNS rebinding: the page's own origin under another name
    ("http://127.0.0.1:8000", None, "Host '' is not"),
    ("http://192.168.1.5:8000", "192.168.1.5:8000", None),  # --allow-origin
])
def test_origin_policy(origin, host, refused):
    headers = [(k.encode(), v.encode()) for k, v in (("origin", origin), ("host", host)) if v]
    scope = {"headers": headers, "server": ("127.0.0.1", 8000)}
    got = OriginPolicy(["http://192.168.1.5:8000/"]).refusal(scope)
    assert got is None if refused is None else refused in got


@pytest.mark.parametrize("value", ["*", "192.168.1.5:8000", "http://h:8000/page", "ftp://h",
                                   "http://user@h", "http://h:99999", "http://h?x=1", ""])
def test_allow_origin_refuses_what_is_not_an_origin(value):
    with pytest.raises(ValueError, match="--allow-origin .* is invalid; allowed: an origin "
                                         "such as http://192.168.1.5:8000"):
        check_origin(value)


def test_protocol_accepts_a_shot_and_limits_rate():
    assert parse_message('{"type": "shoot", "aim": -0.25}') == {"type": "shoot", "aim": -0.25}
    assert parse_message('{"aim": 0, "type": "shoot"}')["aim"] == 0.0
    limiter = RateLimiter(rate=1.0, burst=3)
    assert [limiter.allow() for _ in range(5)] == [True, True, True, False, False]


# -- the command line ------------------------------------------------------------------------

def _cli(capsys, argv):
    code = cli.main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_bot_on_a_run_folder(capsys, tmp_path, agent_file):
    run = make_run_folder(tmp_path, agent_file)
    code, out, err = _cli(capsys, ["play", "air-hockey", "--run", str(run), "--bot",
                                   "--shots", "40", "--bot-aim-noise", "0.04"])
    assert code == 0, err
    assert "lili: blocked " in out and "/40 shots of the human-like bot (aim noise 0.04" in out
    assert "sac 18/40, lili-no-influence 29/40" in out
    files = list((run / "play").glob("session-*.csv"))
    assert len(files) == 1 and len(list(csv.DictReader(files[0].open()))) == 40


def test_cli_uses_the_shipped_agent(capsys, tmp_path, agent_file, monkeypatch):
    import lili.play.policy as policy

    monkeypatch.setattr(policy, "SHIPPED_AGENT", tmp_path / "missing.msgpack")
    code, _, err = _cli(capsys, ["play", "air-hockey", "--bot"])
    assert code == 2 and "no trained agent ships with this installation" in err
    assert "--run RUN" in err and len(err.strip().splitlines()) == 1
    monkeypatch.setattr(policy, "SHIPPED_AGENT", agent_file)
    record = tmp_path / "shots.csv"
    code, out, err = _cli(capsys, ["play", "air-hockey", "--bot", "--shots", "5",
                                   "--record", str(record)])
    assert code == 0, err
    assert "/5 shots" in out and len(list(csv.DictReader(record.open()))) == 5


@pytest.mark.parametrize("argv, match", [
    (["play", "point-mass"], "does not have a page for 'point-mass'; allowed: air-hockey"),
    (["play", "pong"], "unknown env 'pong'"),
    (["play", "air-hockey", "--shots", "0"], "--shots 0 is invalid"),
    (["play", "air-hockey", "--port", "70000"], "--port 70000 is invalid"),
    (["play", "air-hockey", "--seed", "-2"], "--seed -2 is invalid"),
    (["play", "air-hockey", "--run", "/nonexistent"], "is not a run folder"),
    (["play", "air-hockey", "--bot-lapse", "1.5"], "bot lapse=1.5 is invalid"),
    (["play", "air-hockey", "--host", "203.0.113.1", "--port", "0"], "cannot listen on"),
    (["play", "air-hockey", "--allow-origin", "evil.example"], "--allow-origin 'evil.example' "
     "is invalid"),
])
def test_cli_bad_input_one_message(capsys, argv, match, agent_file, monkeypatch):
    import lili.play.policy as policy

    monkeypatch.setattr(policy, "SHIPPED_AGENT", agent_file)
    code, _, err = _cli(capsys, argv)
    assert code == 2 and err.startswith("lili: error: ") and match in err, err
    assert len(err.strip().splitlines()) == 1


def test_cli_bad_run_and_record(capsys, tmp_path, agent_file):
    other = make_run_folder(tmp_path / "pm", agent_file, env="lili/PointMass-v0")
    code, _, err = _cli(capsys, ["play", "air-hockey", "--run", str(other), "--bot"])
    assert code == 2 and "is a run of 'lili/PointMass-v0'" in err
    run = make_run_folder(tmp_path, agent_file)
    taken = tmp_path / "taken.csv"
    taken.write_text("keep\n")
    code, _, err = _cli(capsys, ["play", "air-hockey", "--run", str(run), "--bot",
                                 "--record", str(taken)])
    assert code == 2 and "already exists" in err and taken.read_text() == "keep\n"
    assert not (run / "play").exists()
    (run / "checkpoints" / "ckpt_0" / "agent.msgpack").write_bytes(b"garbage")
    code, _, err = _cli(capsys, ["play", "air-hockey", "--run", str(run), "--bot"])
    assert code == 2 and "corrupt" in err and not (run / "play").exists()


def test_cli_refuses_a_recording_folder_it_cannot_write(capsys, tmp_path, agent_file,
                                                         monkeypatch):
    """`./play-sessions` a file (the issue's "[Errno 17] File exists" at the first shot): one
    line and exit 2 at start-up, before a port is taken or anything is written."""
    import lili.play.policy as policy

    monkeypatch.setattr(policy, "SHIPPED_AGENT", agent_file)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "play-sessions").write_text("in the way\n")
    code, out, err = _cli(capsys, ["play", "air-hockey", "--port", "0"])
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "the recording folder 'play-sessions' is invalid: 'play-sessions' is a file" in err
    assert (tmp_path / "play-sessions").read_text() == "in the way\n"


@pytest.mark.slow
def test_ship_script_at_a_tiny_budget_and_from_a_run(tmp_path, capsys):
    """The script that makes the shipped agent, rerun just past the warm-up; `lili train` runs
    the same loop, so the run's final agent file is byte for byte the script's, and
    --from-run ships it unchanged (or refuses, before writing anything, a run that does not fit).
    """
    from lili.play import ship

    cfg = tmp_path / "small.yaml"
    cfg.write_text(yaml.safe_dump({**SMALL, "warmup_interactions": 3}))
    common = ["--seed", "1", "--interactions", "5", "--config", str(cfg),
              "--env-kwarg", "aim_noise=0.03"]
    out = tmp_path / "agents" / "air_hockey.msgpack"
    proc = subprocess.run([sys.executable, "-m", "lili.play.ship", *common, "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert out.is_file() and out.stat().st_size < 5 * 2**20
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["interactions"] == 5 and meta["env_kwargs"] == {"aim_noise": 0.03}
    blocker = Blocker.load(out, make_play_env(meta["env_kwargs"]))
    assert blocker.agent.num_interactions == 5

    assert cli.main(["train", "lili/AirHockey-v0", "--algo", "lili", *common, "--out",
                     str(tmp_path / "runs"), "--no-progress"]) == 0
    run = tmp_path / "runs" / "AirHockey-v0" / "lili" / "seed_1"
    shipped = tmp_path / "from_run" / "air_hockey.msgpack"
    assert ship.main(["--from-run", str(run), "--out", str(shipped)]) == 0
    assert shipped.read_bytes() == out.read_bytes()
    meta = json.loads(shipped.with_suffix(".json").read_text())
    assert meta["interactions"] == 5 and meta["env_kwargs"] == {"aim_noise": 0.03}
    assert "--interactions 5 --env-kwarg aim_noise=0.03 --config FILE  # FILE: " in \
        meta["trained_by"] and "warmup_interactions: 3" in meta["trained_by"]

    cfg_file = run / "config.yaml"
    cfg_file.write_text(yaml.safe_dump({**yaml.safe_load(cfg_file.read_text()),
                                        "interactions": 9}))
    other = tmp_path / "other.msgpack"
    capsys.readouterr()
    assert ship.main(["--from-run", str(run), "--out", str(other)]) == 2
    assert "is not finished (5 of 9 interactions); allowed: a finished run" in \
        capsys.readouterr().err
    assert ship.main(["--from-run", str(tmp_path), "--out", str(other)]) == 2
    assert "is not a run folder (config.yaml is missing)" in capsys.readouterr().err
    assert not other.exists()
