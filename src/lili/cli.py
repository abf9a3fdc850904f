# Over 400 lines: a parser and a handler per subcommand, each checking its input before writing.
"""Command line: ``lili train | eval | report | reproduce | results | check-env | play``.

Every bad input ends with one line ``lili: error: ...`` naming the value and what is allowed,
exit code 2, and nothing overwritten.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path
from typing import Any, NoReturn

from lili.errors import bounded, shown
from lili.limits import MAX_GROUP

__all__ = ["main"]


class UsageError(ValueError):
    """A bad command-line value."""


class _Parser(argparse.ArgumentParser):
    """argparse with its errors on one line (by default it prints the usage block first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, bounded(f"lili: error: {message} (see {self.prog} --help)") + "\n")


def _parse_kwargs(items: list[str], flag: str = "--env-kwarg") -> dict[str, Any]:
    """``--env-kwarg KEY=VALUE`` items as a dict; VALUE is YAML (0.2, 1e-3, true, [1, 2]) of
    bounded size (:mod:`lili.yaml_bounds`: at most 10,000 characters and 10,000 values).

    ``render_mode`` is refused: ``lili train`` renders nothing, and ``lili eval --video`` sets
    ``rgb_array`` itself.
    """
    import yaml

    from lili.config import yaml_value
    from lili.yaml_bounds import MAX_VALUE_CHARS, check_yaml

    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"{flag} {shown(item)} is invalid; allowed: KEY=VALUE")
        if key in out:
            raise UsageError(f"{flag} {key} is given twice ({key}={shown(out[key])}, "
                             f"{key}={shown(text)}); allowed: each KEY once")
        if key == "render_mode" and flag == "--env-kwarg":
            raise UsageError(f"--env-kwarg render_mode={text} is not allowed: lili train "
                             "renders nothing (lili eval --video records frames with "
                             "render_mode='rgb_array')")
        try:
            check_yaml(text, MAX_VALUE_CHARS)
            out[key] = yaml_value(text)
        except (ValueError, yaml.YAMLError) as e:
            raise UsageError(f"{flag} {shown(item)} is invalid: {e}") from None
    return out


def _check_config_size(path: str) -> None:
    """Refuse a ``--config`` file past the bounds of :mod:`lili.yaml_bounds` before it is
    loaded; every other problem of the file is ``load_config``'s to name."""
    from lili.yaml_bounds import MAX_YAML_CHARS, YAMLTooLarge, check_yaml

    p = Path(path)
    if not p.is_file():
        return
    try:
        with p.open("rb") as f:
            raw = f.read(MAX_YAML_CHARS * 4 + 1)  # UTF-8: at most 4 bytes a character
        if len(raw) > MAX_YAML_CHARS * 4:
            raise YAMLTooLarge(f"it is more than {MAX_YAML_CHARS} characters long; allowed: "
                               f"at most {MAX_YAML_CHARS}")
        check_yaml(raw.decode("utf-8"))
    except (OSError, UnicodeDecodeError):
        return
    except YAMLTooLarge as e:
        raise UsageError(f"config file {shown(path)} is refused: {e}") from None


def parse_overrides(items: list[str], flag: str = "--set") -> dict[str, Any]:
    """``FIELD=VALUE`` items (``lili reproduce --set``) as a dict of AgentConfig fields;
    UsageError naming ``flag`` and the bad item or field."""
    from lili.config import AgentConfig

    out = _parse_kwargs(items, flag)
    try:
        AgentConfig.from_dict(out)
    except ValueError as e:
        raise UsageError(f"{flag}: {e}") from None
    return out


def _check_interactions(n: int, flag: str = "--interactions") -> int:
    from lili.limits import MAX_INTERACTIONS, check_count

    try:
        return check_count(n, flag, MAX_INTERACTIONS)
    except ValueError as e:
        raise UsageError(str(e)) from None


def _check_seed(seed: int, flag: str = "--seed") -> int:
    """The one seed rule of the library (``lili.agents.check_seed``), for a flag."""
    from lili.agents import check_seed

    try:
        return check_seed(seed, flag)
    except ValueError as e:
        raise UsageError(str(e)) from None


def _make_env(env_id: str, kwargs: dict[str, Any], render_mode: str | None = None):
    from lili.envs.spec import make_env

    return make_env(env_id, kwargs, render_mode)


def _resolve_env(spec: str) -> str:
    """The canonical name of an env spec: a registered id for an alias or id, else the
    ``MODULE:CLASS`` / ``module:namespace/Id-v0`` spec itself (checked by importing it)."""
    from lili.envs import ENV_ALIASES
    from lili.envs.spec import load_env_class

    load_env_class(spec)  # ValueError naming the spec when it is not an env
    return ENV_ALIASES.get(spec, spec)


def _strategy_dim(env: Any) -> int:
    space = getattr(env.unwrapped, "strategy_space", None)
    shape = getattr(space, "shape", None)
    return int(shape[0]) if shape and len(shape) == 1 else 0


def _parse_seeds(spec: str) -> list[int]:
    """``--seeds`` as a list: ``0-7`` (both ends included), ``0,3,5`` or a mix (``0-2,9``)."""
    seeds: list[int] = []
    bad = UsageError(f"--seeds {spec[:60]!r} is invalid; allowed: seeds and ranges such as "
                     f"0-7 or 0,3,5 (at most {MAX_GROUP} seeds, each in [0, 2**32 - 1])")
    for part in str(spec).split(","):
        lo, dash, hi = part.strip().partition("-")
        if not lo.isdigit() or (dash and not hi.isdigit()) or len(part) > 24:
            raise bad
        first, last = int(lo), int(hi) if dash else int(lo)
        if last < first or last - first + 1 + len(seeds) > MAX_GROUP:
            raise bad
        seeds += range(first, last + 1)
    if len(set(seeds)) != len(seeds):
        raise UsageError(f"--seeds {spec[:60]!r} names a seed twice; allowed: distinct seeds")
    for seed in seeds:
        _check_seed(seed, "--seeds")
    return seeds


def _check_run_folder(args: argparse.Namespace, env_id: str, env_kwargs: dict[str, Any],
                      config: Any, seed: int) -> tuple[Path, dict[str, Any]]:
    """One seed's run folder and resolved config, checked against ``--resume``; writes nothing."""
    from lili.runs import read_run_config, run_dir_for

    run_dir = run_dir_for(args.out, env_id, args.algo, seed)
    resolved = {"env": env_id, "env_kwargs": env_kwargs, "algo": args.algo, "seed": seed,
                "interactions": args.interactions, "agent": config.to_dict()}
    backend = getattr(args, "backend", "gym")
    if backend != "gym":  # the Gymnasium path's config.yaml stays as it was
        resolved["backend"] = backend
    exists = (run_dir / "metrics.csv").exists()
    if exists and not args.resume:
        raise UsageError(f"run folder {run_dir} already holds a run; pass --resume to continue "
                         "it or choose another --out")
    if args.resume and not exists:
        raise UsageError(f"--resume: there is no run to resume in {run_dir}")
    if args.resume:
        old = read_run_config(run_dir)
        if old.get("backend", "gym") != backend:
            raise UsageError(f"--resume: the run in {run_dir} was trained with --backend "
                             f"{old.get('backend', 'gym')}, not {backend}; its env's random "
                             "draws differ, so it resumes only on that backend")
        for key in ("env", "env_kwargs", "algo", "seed", "agent"):
            if old.get(key) != resolved[key]:
                raise UsageError(f"--resume: {key} differs from the run in {run_dir} "
                                 f"({old.get(key)!r} there, {resolved[key]!r} now)")
    return run_dir, resolved


def _note_history(algo: str, env_kwargs: dict[str, Any], config: Any) -> None:
    """A note when the partner reacts to more or fewer interactions (``--env-kwarg history``)
    than ``algo``'s encoder reads (its config's ``history``): the env option does not reach
    the agent, and a mismatch is easy to miss, though it may be meant (an ablation)."""
    from lili.agents.registry import reads

    partner = env_kwargs.get("history")
    if partner is None or "history" not in reads(algo) or partner == config.history:
        return
    print(f"note: the partner reacts to the last {partner} interactions (--env-kwarg "
          f"history={partner}) but {algo}'s encoder reads the last {config.history} (config "
          f"history: {config.history}); give a --config with history: {partner} to match them, "
          "as the paper's history table does")


def cmd_train(args: argparse.Namespace) -> int:
    from lili.agents import ALGOS, check_config, make_agent
    from lili.config import AgentConfig, load_config
    from lili.runs import RunLogger, check_out_dir, resume_run
    from lili.train import Stream, train

    env_id = _resolve_env(args.env)
    if args.algo not in ALGOS:
        raise UsageError(f"unknown algo {args.algo!r}; allowed: {', '.join(ALGOS)}")
    _check_interactions(args.interactions)
    seeds = _parse_seeds(args.seeds) if args.seeds is not None else [_check_seed(args.seed)]
    check_out_dir(args.out, "--out")
    if args.backend == "jax":  # an algo or env the JAX path lacks, before its config is read
        from lili.jax_train import check_jax_run

        try:
            check_jax_run(args.algo, env_id)
        except ValueError as e:
            raise UsageError(str(e)) from None
    if args.config:
        _check_config_size(args.config)
    config = load_config(args.config) if args.config else AgentConfig()
    try:
        check_config(args.algo, config)
    except ValueError as e:
        raise UsageError(f"config file {str(args.config)!r}: {e}" if args.config
                         else str(e)) from None
    env_kwargs = _parse_kwargs(args.env_kwarg)
    _note_history(args.algo, env_kwargs, config)
    if args.backend == "jax":
        return _train_jax(args, env_id, seeds, config, env_kwargs)
    if len(seeds) > 1:  # an algo that cannot share a program, before any agent is built
        from lili.many import check_group_algo

        try:
            check_group_algo(args.algo)
        except ValueError as e:
            raise UsageError(f"--seeds: {e}") from None
    folders = [_check_run_folder(args, env_id, env_kwargs, config, seed) for seed in seeds]
    envs = [_make_env(env_id, env_kwargs) for _ in seeds]
    agents = [make_agent(args.algo, env, config, seed) for env, seed in zip(envs, seeds,
                                                                            strict=True)]
    if len(agents) > 1:
        from lili.many import group_streams

        try:  # before any buffer is allocated: a group too big for memory fails here
            streams = group_streams(agents)
        except ValueError as e:
            raise UsageError(f"--seeds: {e}") from None
    else:
        streams = [Stream.for_agent(agents[0], agents[0].env)]
    dim = _strategy_dim(envs[0])
    runs = []
    for (run_dir, resolved), agent, stream in zip(folders, agents, streams, strict=True):
        start = resume_run(run_dir, agent, stream, dim) if args.resume else 0
        if args.interactions < start:
            raise UsageError(f"--interactions {args.interactions} is below the {start} the run "
                             f"in {run_dir} has already done")
        runs.append((agent, stream, run_dir, resolved, dim, start))
    # Everything is read and checked before a run folder is touched.
    loggers = [RunLogger(run_dir, resolved, dim, config.checkpoint_every, start)
               for _, _, run_dir, resolved, dim, start in runs]
    for (agent, _, run_dir, _, _, start) in runs:
        print(f"training {args.algo} on {env_id} (seed {agent.seed}) -> {run_dir}"
              + (f" (resumed at interaction {start})" if start else ""))
    if runs[0][4] == 0:
        print(f"note: {env_id} reports no partner strategy (no strategy_space / "
              "info['strategy']): metrics.csv and reports will hold no strategy columns")
    try:
        if len(runs) == 1:
            train(agents[0], streams[0], args.interactions - runs[0][5],
                  progress=not args.no_progress, logger=loggers[0])
        else:
            from lili.many import train_many

            # Runs resumed at different points catch up alone first (train_many).
            train_many(agents, streams, args.interactions - max(r[5] for r in runs),
                       loggers, progress=not args.no_progress)
    except KeyboardInterrupt:
        for logger in loggers:
            logger.close()
        done = min(s.count for s in streams)
        print(f"interrupted; resume with the same command and --resume (from interaction "
              f"{done // config.checkpoint_every * config.checkpoint_every})")
        return 130
    except ValueError:
        for logger in loggers:
            logger.close()
        raise
    _finish(agents, streams, loggers, [run[3] for run in runs])
    return 0


def _finish(agents: list[Any], streams: list[Any], loggers: list[Any],
            configs: list[dict[str, Any]]) -> None:
    """Each run's final checkpoint and summary.json, and its line on the terminal."""
    for agent, stream, logger, config in zip(agents, streams, loggers, configs, strict=True):
        summary = logger.finish(agent, stream, config)
        line = (f"seed {agent.seed}: " if len(agents) > 1 else "") + \
            f"final return (last 10%): {summary['final_return']:.3f}"
        if summary["final_success"] is not None:
            line += f", success {summary['final_success']:.2f}"
        if summary.get("final_return_policy") is not None:
            line += f" (the policy's own interactions: {summary['final_return_policy']:.3f}"
            if summary["final_success_policy"] is not None:
                line += f", success {summary['final_success_policy']:.2f}"
            line += ")"
        print(line + f"; wall time {summary['wall_time_s']:.0f} s")


def _train_jax(args: argparse.Namespace, env_id: str, seeds: list[int], config: Any,
               env_kwargs: dict[str, Any]) -> int:
    """``lili train --backend jax``: the seeds as one :class:`lili.jax_train.JaxRuns`, each
    with its own run folder. Everything is checked before a folder is written."""
    import jax

    from lili.jax_train import JaxRuns
    from lili.runs import RunLogger

    folders = [_check_run_folder(args, env_id, env_kwargs, config, seed) for seed in seeds]
    try:
        runs = JaxRuns(args.algo, env_id, seeds, config, env_kwargs)
    except ValueError as e:
        raise UsageError(f"--backend jax: {e}") from None
    dim = _strategy_dim(runs.agent.env)
    start = runs.resume([run_dir for run_dir, _ in folders], dim) if args.resume else 0
    if args.interactions < start:
        raise UsageError(f"--interactions {args.interactions} is below the {start} the runs "
                         "have already done")
    # Everything is read and checked before a run folder is touched.
    loggers = [RunLogger(run_dir, resolved, dim, config.checkpoint_every, start)
               for run_dir, resolved in folders]
    for seed, (run_dir, _) in zip(seeds, folders, strict=True):
        print(f"training {args.algo} on {env_id} (seed {seed}, JAX) -> {run_dir}"
              + (f" (resumed at interaction {start})" if start else ""))
    if len(seeds) == 1 and jax.default_backend() == "cpu":
        print("note: on a CPU the JAX path maps a lone seed twice (its numbers then match any "
              "group's) and runs at half speed; the Gymnasium path (no --backend) trains one "
              "seed at full speed")
    try:
        runs.train(args.interactions - start, loggers, progress=not args.no_progress,
                   keep_rows=False)
    except (KeyboardInterrupt, ValueError) as e:
        for logger in loggers:
            logger.close()
        if isinstance(e, KeyboardInterrupt):
            every = config.checkpoint_every
            print("interrupted; resume with the same command and --resume (from interaction "
                  f"{runs.count // every * every})")
            return 130
        raise
    _finish(runs.agents(), runs.streams(), loggers, [resolved for _, resolved in folders])
    return 0


def cmd_eval(args: argparse.Namespace) -> int:
    from lili.evaluate import evaluate
    from lili.runs import load_trained

    _check_interactions(args.interactions)
    _check_seed(args.seed)
    if args.video:
        from lili.video import LabelledFrames, check_video_path

        check_video_path(args.video)
    run_dir = Path(args.run)
    agent, env, cfg, _ = load_trained(run_dir, "rgb_array" if args.video else None)
    frames: list | None = [] if args.video else None
    res = evaluate(agent, LabelledFrames(env) if args.video else None, args.interactions,
                   seed=args.seed, frames=frames)
    msg = f"{cfg['algo']} on {cfg['env']}: mean return {res['mean_return']:.3f} over " \
          f"{args.interactions} interactions"
    if res["success_rate"] is not None:
        msg += f", success rate {res['success_rate']:.2f}"
    print(msg)
    if args.video and frames:
        from lili.video import write_video

        print(f"video: {write_video(frames, args.video)}")
    out = run_dir / "eval.json"
    out.write_text(json.dumps({k: v for k, v in res.items()}, indent=1))
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from lili.report import markdown_table, write_report

    if args.upto is not None and args.upto < 1:
        raise UsageError(f"--upto {args.upto} is invalid; allowed: an integer >= 1")
    out = Path(args.out) if args.out else Path(args.runs[0]) / "report"
    summary = write_report(args.runs, out, upto=args.upto, policy_only=args.policy_only)
    print(markdown_table(summary))
    print(f"figures and tables in {out}")
    return 0


def cmd_reproduce(args: argparse.Namespace) -> int:
    from lili.experiments import reproduce

    reproduce(args.name, out=args.out or ("runs/reproduce-quick" if args.quick
                                          else "runs/reproduce"),
              seeds=args.seeds, interactions=args.interactions, jobs=args.jobs, ray=args.ray,
              quick=args.quick, dry_run=args.dry_run, report_only=args.report_only,
              algos=tuple(args.algos) if args.algos else None,
              envs=tuple(args.envs) if args.envs else None,
              progress=False if args.no_progress else None,
              overrides=parse_overrides(args.set),
              env_kwargs=_parse_kwargs(args.env_kwarg),
              check_only=args.check_only, sources=args.sources, group=args.group,
              device=args.device, paper_settings=args.paper_settings, backend=args.backend)
    return 0


def cmd_results(args: argparse.Namespace) -> int:
    from lili.experiments.page import (
        DEFAULT_OUT,
        DEFAULT_README,
        QUICKSTART_BEGIN,
        write_results_page,
    )

    readme = args.readme
    if readme is None and args.out == DEFAULT_OUT:
        # The repo's page and its README go together; a README without the block (another
        # project's, where the page is made from its own --sources) is not this repo's.
        try:
            ours = QUICKSTART_BEGIN in Path(DEFAULT_README).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            ours = False
        readme = DEFAULT_README if ours else None
    elif readme == "none":
        readme = None
    path = write_results_page(args.sources, args.out, readme)
    print(f"results page: {path}" + (f"; quick-start table in {readme}" if readme else ""))
    return 0


def cmd_check_env(args: argparse.Namespace) -> int:
    from lili.envs.checker import MAX_INTERACTIONS, check_env
    from lili.envs.spec import load_env_class

    if not 2 <= args.interactions <= MAX_INTERACTIONS:
        raise UsageError(f"--interactions {args.interactions} is invalid; allowed: an integer in "
                         f"[2, {MAX_INTERACTIONS}]")
    _check_seed(args.seed)
    factory = load_env_class(args.env)
    # Gymnasium's warnings on the way (an observation outside its space, ...) are shown only
    # when the check passes: a failure is its one line, which says more.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(factory, n_interactions=args.interactions, seed=args.seed)
    for w in caught:
        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    print(f"{args.env}: passes Gymnasium's checker and the repeated-interaction contract")
    return 0


def cmd_play(args: argparse.Namespace) -> int:
    from lili.play.command import run_play

    return run_play(args)


def build_parser() -> argparse.ArgumentParser:
    from lili.agents import ALGOS
    from lili.experiments.plan import BACKENDS

    p = _Parser(prog="lili", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    t = sub.add_parser("train", help="train an agent and write a run folder")
    t.add_argument("env", help="registered id (lili/PointMass-v0) or alias (point-mass)")
    t.add_argument("--algo", default="lili", help=f"one of {', '.join(ALGOS)} (default lili)")
    seed = t.add_mutually_exclusive_group()
    seed.add_argument("--seed", type=int, default=0)
    seed.add_argument("--seeds", metavar="SEEDS",
                      help="train several seeds together in one program, e.g. 0-7 or 0,3,5 "
                           "(one run folder each; see README 'Many seeds')")
    t.add_argument("--interactions", type=int, default=2000, help="budget (default 2000)")
    t.add_argument("--out", default="runs/default", help="experiment folder (default runs/default)")
    t.add_argument("--config", help="YAML file with AgentConfig fields to change")
    t.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE",
                   help="env option, e.g. step_noise=0.2 or history=3 (repeatable)")
    t.add_argument("--resume", action="store_true", help="continue the run in the folder")
    t.add_argument("--backend", choices=BACKENDS, default="gym",
                   help="gym: the Gymnasium env (default); jax: its JAX twin, all seeds as one "
                        "jitted program per interaction (sac, lili, lili-no-influence, oracle, "
                        "oracle-last on point-mass, driving-2d and the influence envs)")
    t.add_argument("--no-progress", action="store_true", help="no progress bar")
    t.set_defaults(func=cmd_train)

    e = sub.add_parser("eval", help="evaluate a run's latest checkpoint without learning")
    e.add_argument("run", help="run folder")
    e.add_argument("--interactions", type=int, default=100)
    e.add_argument("--seed", type=int, default=12345, help="seed of the env sequence")
    e.add_argument("--video", help="write the interactions to this animated .gif")
    e.set_defaults(func=cmd_eval)

    r = sub.add_parser("report", help="curves, tables and heatmaps from run folders")
    r.add_argument("runs", nargs="+", help="run folders or folders containing them")
    r.add_argument("--out", help="output folder (default RUN/report)")
    r.add_argument("--upto", type=int, metavar="N",
                   help="compare at one budget: use only each run's first N interactions")
    r.add_argument("--policy-only", action="store_true",
                   help="leave out the interactions training played at random after the "
                        "warm-up (random_interactions), so runs are compared on their policies")
    r.set_defaults(func=cmd_report)

    from lili.experiments.presets import PRESETS

    x = sub.add_parser("reproduce", help="rerun a figure or table of the paper and report it")
    x.add_argument("name", help=f"preset: {', '.join(PRESETS)}")
    x.add_argument("--seeds", type=int, help="seeds per run group (default: the preset's, 3)")
    x.add_argument("--interactions", type=int, help="budget per run (default: the preset's)")
    x.add_argument("--jobs", type=int, help="runs at a time (default 2 locally, all CPUs on Ray)")
    x.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                   help="run on Ray: alone, a local instance; with ADDRESS, join that cluster")
    x.add_argument("--quick", action="store_true",
                   help="tiny budget, 1 seed: the whole pipeline in minutes")
    x.add_argument("--algos", nargs="+", help="only these algos of the preset")
    x.add_argument("--envs", nargs="+", help="only these envs of the preset (ids or aliases)")
    x.add_argument("--out", help="folder of every preset's runs (default runs/reproduce, "
                   "runs/reproduce-quick with --quick)")
    x.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                   help="agent-config field for every run, e.g. gamma=0.999 (repeatable; an "
                        "ablation: give it its own --out)")
    x.add_argument("--env-kwarg", action="append", default=[], metavar="KEY=VALUE",
                   help="env option for every run, e.g. aim_noise=0.02 (repeatable; every env "
                        "of the plan must take it: choose them with --envs; give it its own "
                        "--out)")
    x.add_argument("--group", type=int, metavar="K",
                   help="train up to K seeds of a cell (same env, algo and config) together in "
                        "one process (lili.many; default 1 on a CPU, 64 on a GPU)")
    x.add_argument("--device", metavar="{cpu,gpu}",
                   help="JAX platform of the runs' processes (default: JAX's choice); with "
                        "gpu, several processes share the GPU (no memory preallocation)")
    x.add_argument("--backend", choices=BACKENDS, default="gym",
                   help="jax: the runs whose env and algo the JAX-native path supports train "
                        "there (lili train --backend jax), the others on the Gymnasium envs "
                        "(--dry-run lists which)")
    x.add_argument("--paper-settings", action="store_true",
                   help="the paper's literal setting where a preset departs from it (air "
                        "hockey: 1000 interactions, no random interactions; Lunar Lander: the "
                        "per-step discount at the boundary)")
    x.add_argument("--dry-run", action="store_true", help="list the runs and the CPU-hours")
    x.add_argument("--report-only", action="store_true",
                   help="start nothing; write an interim report from the finished runs")
    x.add_argument("--no-progress", action="store_true", help="plain lines, no bars")
    x.add_argument("--check-only", action="store_true",
                   help="train nothing: check the preset's claims against the finished runs "
                        "under --out (or --sources)")
    x.add_argument("--sources", metavar="FILE",
                   help="with --check-only: the run folders of each group, e.g. "
                        "benchmarks/results/claims_sources.yaml (the committed records)")
    x.set_defaults(func=cmd_reproduce)

    from lili.experiments.page import DEFAULT_OUT, DEFAULT_README, DEFAULT_SOURCES

    res = sub.add_parser("results", help="write the results page (docs/results.md) from the "
                         "committed records")
    res.add_argument("--sources", default=DEFAULT_SOURCES,
                     help=f"run folders per preset group (default {DEFAULT_SOURCES})")
    res.add_argument("--out", default=DEFAULT_OUT, help=f"the page (default {DEFAULT_OUT}; "
                     "figures in results/ beside it)")
    res.add_argument("--readme", default=None,
                     help=f"a README whose quick-start table block is rewritten from the "
                     f"quickstart records too (default: {DEFAULT_README} when it holds that "
                     f"block and --out is {DEFAULT_OUT}; none: only the page)")
    res.set_defaults(func=cmd_results)

    c = sub.add_parser("check-env", help="check an env against the repeated-interaction contract")
    c.add_argument("env", help="MODULE:CLASS, or a registered id")
    from lili.envs.checker import DEFAULT_INTERACTIONS

    c.add_argument("--interactions", type=int, default=DEFAULT_INTERACTIONS,
                   help=f"interactions per run of the check (default {DEFAULT_INTERACTIONS})")
    c.add_argument("--seed", type=int, default=0)
    c.set_defaults(func=cmd_check_env)

    from lili.play.command import add_arguments as play_arguments

    p_play = sub.add_parser("play", help="play against a trained agent in a browser (or a bot)")
    play_arguments(p_play)
    p_play.set_defaults(func=cmd_play)
    return p


def _echo(text: str) -> str:
    """A command-line word as typed, or bounded (:func:`lili.errors.shown`) when long."""
    return text if len(text) <= 40 else shown(text)


def _unknown_arguments(parser: argparse.ArgumentParser, command: str,
                       extra: list[str]) -> NoReturn:
    """Exit 2 naming the arguments ``lili COMMAND`` does not take and the flags it does (the
    top-level parser would point at ``lili --help``)."""
    sub = next(a for a in parser._actions
               if isinstance(a, argparse._SubParsersAction)).choices[command]
    flags = [o for a in sub._actions for o in a.option_strings
             if o.startswith("--") and o != "--help"]
    sub.error(f"unrecognized arguments: {' '.join(map(_echo, extra))}; allowed flags of "
              f"{sub.prog}: "
              + ", ".join(flags))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``lili`` command."""
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:
            _unknown_arguments(parser, args.command, extra)
    except SystemExit as e:  # argparse's one-line errors (exit 2) and --help (exit 0)
        return e.code if isinstance(e.code, int) else 2
    try:
        return int(args.func(args))
    except (ValueError, OSError) as e:  # UsageError, CheckpointError, EnvContractError, I/O
        print(bounded(f"lili: error: {e}"), file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
