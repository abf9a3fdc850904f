"""``lili play air-hockey``: check the command line, load the blocker, serve the page or bot.

Every bad value fails with one ValueError naming it and what is allowed, before anything is
written (the CLI turns it into ``lili: error: ...``).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path
from typing import Any

from lili.play.origin import LOOPBACK

__all__ = ["add_arguments", "run_play", "LOOPBACK"]

MAX_SHOTS = 1000


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``play`` subcommand's arguments."""
    p.add_argument("env", help="the game: air-hockey (lili/AirHockey-v0)")
    p.add_argument("--run", help="run folder of a trained agent (default: the shipped agent)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=8000, help="port (default 8000; 0 = any free)")
    p.add_argument("--allow-origin", action="append", default=[], metavar="ORIGIN",
                   help="also accept the page's WebSocket from this origin, e.g. "
                   "http://192.168.1.5:8000 for a demo on a LAN (repeatable; default: only "
                   "http://127.0.0.1|localhost|[::1]:PORT)")
    p.add_argument("--shots", type=int, default=40, help="shots per game (default 40, as the "
                   "paper's human study)")
    p.add_argument("--record", metavar="FILE", help="write every session's shots to this new "
                   "CSV file (default: RUN/play/session-*.csv, or ./play-sessions/)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--bot", action="store_true", help="play one headless game with the "
                   "human-like bot striker and print blocks/shots")
    p.add_argument("--bot-aim-noise", type=float, default=0.05, metavar="RAD",
                   help="bot's aim error, standard deviation in radians (default 0.05)")
    p.add_argument("--bot-lapse", type=float, default=0.1, metavar="P",
                   help="probability that a bot shot ignores the rule (default 0.1)")
    p.add_argument("--bot-reaction", type=float, default=1.0, metavar="P",
                   help="probability that the bot reacts to the last block (default 1)")


def _agent_source(run: str | None) -> tuple[Path, dict[str, Any]]:
    from lili.play.policy import SHIPPED_AGENT, agent_file_for_run

    if run is not None:
        path, cfg = agent_file_for_run(run)
        if cfg.get("env") != "lili/AirHockey-v0":
            raise ValueError(f"--run {run!r} is a run of {cfg.get('env')!r}; allowed: a run of "
                             "lili/AirHockey-v0")
        return path, dict(cfg.get("env_kwargs") or {})
    if not SHIPPED_AGENT.is_file():
        raise ValueError(f"no trained agent ships with this installation ({SHIPPED_AGENT} is "
                         "missing); pass --run RUN with a run folder of `lili train air-hockey`, "
                         "or make the file with `python -m lili.play.ship`")
    meta_path = SHIPPED_AGENT.with_suffix(".json")
    meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    return SHIPPED_AGENT, dict(meta.get("env_kwargs") or {})


def _check_args(args: argparse.Namespace) -> None:
    from lili.envs import resolve_env_id

    if resolve_env_id(args.env) != "lili/AirHockey-v0":
        raise ValueError(f"lili play does not have a page for {args.env!r}; allowed: air-hockey")
    if not 1 <= args.shots <= MAX_SHOTS:
        raise ValueError(f"--shots {args.shots} is invalid; allowed: an integer in 1..{MAX_SHOTS}")
    if args.seed < 0:
        raise ValueError(f"--seed {args.seed} is invalid; allowed: an integer >= 0")
    if not 0 <= args.port <= 65535:
        raise ValueError(f"--port {args.port} is invalid; allowed: an integer in 0..65535")
    from lili.play.origin import check_origin

    args.allow_origin = [check_origin(o) for o in args.allow_origin]


def run_play(args: argparse.Namespace) -> int:
    """Run ``lili play`` with parsed ``args``; return the exit code."""
    from lili.play.record import Recorder
    from lili.play.striker import BotConfig

    _check_args(args)
    bot_config = BotConfig(args.bot_aim_noise, args.bot_lapse, args.bot_reaction)
    path, env_kwargs = _agent_source(args.run)
    if args.record:
        recorder = Recorder(file=args.record)
    else:
        recorder = Recorder(folder=Path(args.run) / "play" if args.run else Path("play-sessions"))
    sock = None
    if not args.bot:
        from lili.play.server import bind

        # Bound (the port is checked) but not listening: a visitor who comes before the page is
        # ready is refused at once instead of waiting on a connection nobody answers.
        sock = bind(args.host, args.port)
    try:
        return _play(args, path, env_kwargs, recorder, bot_config, sock)
    finally:
        if sock is not None:
            sock.close()


def _play(args: argparse.Namespace, path: Path, env_kwargs: dict[str, Any], recorder: Any,
          bot_config: Any, sock: Any) -> int:
    from lili.play.policy import Blocker
    from lili.play.session import make_play_env

    template = make_play_env(env_kwargs)
    blocker = Blocker.load(path, template)
    template.close()
    if args.bot:
        from lili.play.bot import bot_report, run_bot

        result = run_bot(blocker, env_kwargs, args.shots, bot_config, args.seed,
                         recorder.session())
        print(bot_report(blocker.algo, result, bot_config))
        print(f"shots recorded in {recorder.where}")
        return 0

    from lili.play.probe import ModeProbe
    from lili.play.server import create_app, listen, serve

    _log_to_stderr()
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    print(f"lili play: {blocker.algo} from {path}; getting ready (the page opens at "
          f"http://{shown}:{port}/ once ready)", flush=True)
    probe = ModeProbe.for_blocker(blocker, env_kwargs, seed=args.seed)
    _warm_up(blocker, env_kwargs)
    app = create_app(blocker, env_kwargs, args.shots, recorder, probe, args.seed,
                     allow_origins=tuple(args.allow_origin))
    if args.host not in LOOPBACK:
        print(f"warning: --host {args.host} makes the page reachable from other machines; the "
              "server has no authentication", file=sys.stderr)
    listen(sock)
    print(f"  ready: open http://{shown}:{port}/ "
          f"(Ctrl-C to stop); sessions are recorded in {recorder.where}", flush=True)
    try:
        serve(app, sock)
    except KeyboardInterrupt:
        pass
    return 0


def _warm_up(blocker: Any, env_kwargs: dict[str, Any]) -> None:
    """Play one unrecorded shot, so the first visitor's shot does not wait for compilation."""
    from lili.play.session import GameSession

    session = GameSession(blocker, env_kwargs, 1)
    try:
        session.play(0.0)
    finally:
        session.close()


def _log_to_stderr() -> None:
    """The server's log lines (refused connections, recording failures) as lines on stderr."""
    logger = logging.getLogger("lili.play")
    if not logger.handlers:
        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("%(message)s"))
        logger.addHandler(handler)
        logger.setLevel(logging.INFO)
