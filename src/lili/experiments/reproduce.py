"""``lili reproduce``: expand a preset, skip finished runs, resume started ones, run the rest
on local processes or Ray tasks (one process per job: one run, or ``--group`` seeds of one cell
trained together by :mod:`lili.many`), then write the preset's report."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from lili.errors import shown
from lili.experiments.costs import estimate_seconds
from lili.experiments.plan import RunSpec, jax_reason, plan, run_status
from lili.experiments.presets import get_preset
from lili.experiments.progress import SweepProgress
from lili.experiments.runner import (
    DEVICES,
    Job,
    group_runs,
    log_path,
    rows_logged,
    write_agent_configs,
)
from lili.limits import MAX_GROUP, MAX_JOBS, check_count
from lili.runs import check_out_dir

__all__ = ["reproduce", "LOCAL_JOBS"]

LOCAL_JOBS = 2
RAY_LOCAL = "local"
GPU_GROUP = 64
"""Runs per job on a GPU when ``--group`` is not given: one program serves a cell's seeds
(issue 33's H200 measurement: the update block's throughput grows up to K = 1024)."""


def default_group(device: str | None) -> int:
    """Runs per job when ``--group`` is not given: one on the CPU, where K runs in one
    process have not been measured cheaper than K processes on two cores
    (``benchmarks/many_runs.py --processes``), and :data:`GPU_GROUP` on a GPU."""
    return GPU_GROUP if device == "gpu" else 1


def check_device(device: str | None, here: bool = True) -> None:
    """ValueError unless ``device`` is None or one of :data:`DEVICES`; with ``here`` (the runs
    start on this machine, not a Ray cluster's nodes) also one that JAX sees here."""
    if device is None:
        return
    if device not in DEVICES:
        raise ValueError(f"--device {shown(device)} is invalid; allowed: {', '.join(DEVICES)}")
    if device == "gpu" and here:
        import jax

        try:
            jax.devices("gpu")
        except RuntimeError:
            raise ValueError("--device gpu: JAX sees no GPU on this machine; allowed: cpu, or "
                             "a machine with JAX's CUDA build (pip install 'jax[cuda12]')") \
                from None


def _backend_line(specs: list[RunSpec]) -> str:
    """What ``--backend jax`` does with ``specs``: how many runs take the JAX-native path, and
    why the others stay on the Gymnasium path (each reason with its count of runs)."""
    jax_runs = sum(s.backend == "jax" for s in specs)
    why: dict[str, int] = {}
    reasons: dict[tuple[str, str, str], str] = {}
    for s in specs:
        if s.backend != "jax":
            key = (s.env, s.algo, repr(sorted(s.env_kwargs.items())))
            if key not in reasons:
                reasons[key] = jax_reason(s) or "planned for the Gymnasium path"
            why[reasons[key]] = why.get(reasons[key], 0) + 1
    line = f"  --backend jax: {_runs(jax_runs)} on the JAX-native path"
    if why:
        line += (f", {len(specs) - jax_runs} on the Gymnasium path: "
                 + "; ".join(f"{reason} ({_runs(n)})" for reason, n in why.items()))
    return line


def _runs(n: int) -> str:
    return f"{n} run" + ("" if n == 1 else "s")


def _dry_run(name: str, specs: list[RunSpec], status: dict[RunSpec, str], jobs: int,
             say: Callable[[str], None], group: int = 1,
             backend: str = "gym") -> dict[str, Any]:
    todo = [s for s in specs if status[s] != "done"]
    estimates = {s: estimate_seconds(s, rows_logged(s) if status[s] == "resume" else 0)
                 for s in todo}
    seconds = sum(estimates.values())
    # Wall time: the runs spread over the jobs, but no faster than the longest run, and no
    # more jobs at work than runs to do.
    parallel = max(1, min(jobs, len(todo)))
    wall = max([seconds / parallel, *estimates.values()])
    for s in specs:
        say(f"{status[s]:6}  {s.run_dir}  ({s.interactions} interactions"
            + (f", {s.env_kwargs}" if s.env_kwargs else "")
            + (f", config {s.config}" if s.config else "")
            + (f", backend {s.backend}" if backend != "gym" else "") + ")")
    by_algo: dict[tuple[str, str], float] = {}
    for s, sec in estimates.items():
        by_algo[(s.preset, s.algo)] = by_algo.get((s.preset, s.algo), 0.0) + sec
    by_preset: dict[str, float] = {}
    for (preset, _), sec in by_algo.items():
        by_preset[preset] = by_preset.get(preset, 0.0) + sec
    for preset, sec in by_preset.items():
        algos = sorted(((v, a) for (p, a), v in by_algo.items() if p == preset), reverse=True)
        say(f"  {preset}: {sec / 3600:.1f} CPU-hours ("
            + ", ".join(f"{a} {v / 3600:.1f}" for v, a in algos) + ")")
    if backend == "jax":
        say(_backend_line(todo))
    if group > 1:
        say(f"  {len(group_runs(todo, group))} jobs with --group {group} (the estimate is "
            "per run, one process each: runs trained together may cost less)")
    say(f"{name}: {len(specs)} runs ({len(todo)} to run, {len(specs) - len(todo)} done); "
        f"estimated {seconds / 3600:.1f} CPU-hours, about {wall / 3600:.1f} h of "
        f"wall time with {jobs} jobs (from measured per-run costs, lili.experiments.costs)")
    return {"runs": len(specs), "to_run": len(todo), "cpu_hours": seconds / 3600,
            "by_preset": {k: v / 3600 for k, v in by_preset.items()}}


def _make_backend(ray: str | None, jobs: int | None, out: Path, device: str | None):
    if ray is None:
        from lili.experiments.local import LocalBackend

        return LocalBackend(jobs or LOCAL_JOBS, device)
    from lili.experiments.ray_backend import RayBackend

    return RayBackend(None if ray == RAY_LOCAL else ray, jobs, out, device)


def _start_backend(ray: str | None, jobs: int | None, out: Path, device: str | None = None):
    """The backend, with ``out`` created for it; when it cannot start, the folders this made
    are removed again (a refused cluster leaves no empty ``--out``)."""
    missing = [p for p in (out, *out.parents) if not p.exists()]
    out.mkdir(parents=True, exist_ok=True)
    try:
        return _make_backend(ray, jobs, out, device)
    except BaseException:
        for folder in missing:  # deepest first; only while empty
            try:
                folder.rmdir()
            except OSError:
                break
        raise


def _check_ray_importable() -> None:
    from lili.experiments.ray_backend import _import_ray

    _import_ray()


def reproduce(name: str, out: str | Path = "runs/reproduce", seeds: int | None = None,
              interactions: int | None = None, jobs: int | None = None,
              ray: str | None = None, quick: bool = False, dry_run: bool = False,
              algos: tuple[str, ...] | None = None, progress: bool | None = None,
              overrides: dict[str, Any] | None = None, envs: tuple[str, ...] | None = None,
              report_only: bool = False, env_kwargs: dict[str, Any] | None = None,
              check_only: bool = False, sources: str | Path | None = None,
              group: int | None = None, device: str | None = None,
              paper_settings: bool = False, backend: str = "gym",
              say: Callable[[str], None] = print) -> dict[str, Any]:
    """Run preset ``name`` into ``out`` and write ``out/<name>/report/``; see the module doc.

    ``ray``: None (local processes), ``"local"`` (start Ray on this machine) or a cluster
    address. ``overrides``: agent-config fields set in every run, ``env_kwargs``: env options
    set in every run, ``algos`` / ``envs``: only those of the preset (:func:`plan`).
    ``report_only``: start nothing and write an interim report from the runs that are
    finished (a long sweep's table so far). ``check_only``: start and write nothing; check the
    preset's claims (:mod:`lili.experiments.claims`) against the finished runs under ``out``
    (the preset layout) or, with ``sources``, the run folders a sources file names
    (``benchmarks/results/claims_sources.yaml``). ``group``: runs of one cell (same env, algo,
    budget and config; their seeds differ) trained together in one process, at most this many
    (:func:`default_group` when None); ``device``: ``"cpu"`` or ``"gpu"`` for the runs'
    processes (None: JAX's default). ``paper_settings``: the paper's literal setting where the
    preset departs from it (:meth:`~lili.experiments.presets.Preset.departs`, printed in the
    report's header otherwise). ``backend``: ``"jax"`` trains the runs whose env and algo the
    JAX-native path supports on it (``lili train --backend jax``), the others on the
    Gymnasium envs, as the plan (and ``dry_run``) says. Every other report ends with the same claims
    table, also written to ``out/<name>/report/claims.md``. Every value is checked and every
    existing run folder compared with the run it would become before anything is written; a bad one
    raises ValueError naming it. Runs that fail are listed (with their logs) in a ValueError
    after the others have finished.
    """
    preset = get_preset(name)
    if check_only:
        if dry_run or report_only:
            raise ValueError("--check-only is invalid with --dry-run or --report-only; "
                             "allowed: one of them")
        return _check_only(preset, out, sources, say)
    if sources is not None:
        raise ValueError(f"--sources {sources} is only read with --check-only; allowed: "
                         "--check-only --sources FILE")
    if jobs is not None:
        check_count(jobs, "--jobs", MAX_JOBS)
    if group is not None:
        check_count(group, "--group", MAX_GROUP)
    check_device(device, here=ray is None)
    group = group if group is not None else default_group(device)
    out = Path(out)
    check_out_dir(out)
    if ray is not None and ray != RAY_LOCAL:
        from lili.experiments.ray_backend import check_address

        check_address(ray)
    specs = plan(preset, out, seeds=seeds, interactions=interactions, algos=algos, quick=quick,
                 overrides=overrides, envs=envs, env_kwargs=env_kwargs,
                 paper_settings=paper_settings, backend=backend)
    status = {s: run_status(s) for s in specs}
    if dry_run and report_only:
        raise ValueError("--dry-run and --report-only are invalid together; allowed: one of them")
    if dry_run:
        return _dry_run(name, specs, status, jobs or LOCAL_JOBS, say, group, backend)
    changes = _changes(overrides, env_kwargs)
    if report_only:
        return _report_only(name, preset, specs, status, out, say, changes, paper_settings)
    if ray is not None:
        _check_ray_importable()
    todo = [s for s in specs if status[s] != "done"]
    t0 = time.time()
    if todo:
        jobs_todo = group_runs(todo, group)
        runner = _start_backend(ray, jobs, out, device)
        together = (f" as {len(jobs_todo)} jobs (up to {group} seeds of a cell in one process)"
                    if len(jobs_todo) < len(todo) else "")
        say(f"{name}: {len(specs)} runs, {len(specs) - len(todo)} done, {len(todo)} to run on "
            f"{runner.description}{together}")
        if backend == "jax":
            say(_backend_line(todo))
        failed = _run_all(runner, jobs_todo, len(specs) - len(todo), progress)
        if failed:
            lines = "\n".join(f"  {s.run_dir} (exit {c}; log {log_path(j)})"
                              for j, c in failed for s in j)
            count = sum(len(j) for j, _ in failed)
            raise ValueError(f"{count} of {len(todo)} runs failed:\n{lines}")
    else:
        say(f"{name}: all {len(specs)} runs are done")
    report = _write_report(preset, specs, out, say, changes=changes,
                           paper_settings=paper_settings)
    claims = _claims_table(preset, out, say)
    say(f"report: {report['dir']} ({time.time() - t0:.0f} s)")
    return {"runs": len(specs), "ran": len(todo), "report": report, "claims": claims}


def _check_only(preset, out: str | Path, sources: str | Path | None,
                say: Callable[[str], None]) -> dict[str, Any]:
    from lili.experiments.claims import check_claims, claims_markdown, load_sources, out_layout
    from lili.experiments.why import load_why, why_beside, why_markdown

    if sources is None and not Path(out).is_dir():
        raise ValueError(f"--check-only: --out {out} is not a folder; allowed: a folder of "
                         "runs in the preset layout, or --sources FILE")
    locate = load_sources(sources) if sources is not None else out_layout(out)
    # The explanations of the FAILs of the records a sources file names sit beside it; an
    # --out folder is the user's own runs, which they do not explain.
    why_file = None if sources is None else why_beside(sources)
    whys = load_why(why_file) if why_file is not None and why_file.is_file() else None
    results = check_claims(preset, locate)
    if not results:
        say(f"{preset.name}: states no claim of the paper (not a paper item); nothing to check")
        return {"claims": results}
    say(f"## Claims of `{preset.name}`, checked against "
        f"{sources if sources is not None else out} (nothing trained)\n")
    say(claims_markdown(results))
    why = why_markdown(results, whys, with_part=bool(preset.includes))
    if why:
        say(why)
    return {"claims": results}


def _claims_table(preset, out: Path, say: Callable[[str], None]) -> list:
    """Check the preset's claims against the finished runs under ``out``; print the table and
    write it to ``out/<name>/report/claims.md`` (a FAIL is printed like a PASS, never left
    out)."""
    from lili.experiments.claims import check_claims, claims_markdown, out_layout

    results = check_claims(preset, out_layout(out))
    if results:
        text = f"## Claims of `{preset.name}`\n\n{claims_markdown(results)}"
        (out / preset.name / "report" / "claims.md").write_text(text, encoding="utf-8")
        say(text)
    return results


def _changes(overrides: dict[str, Any] | None, env_kwargs: dict[str, Any] | None) -> str:
    """The flags that made every run differ from the preset's, as a report names them."""
    parts = [f"{flag} {key}={value}" for flag, given in (("--set", overrides),
                                                         ("--env-kwarg", env_kwargs))
             for key, value in (given or {}).items()]
    return " ".join(f"`{p}`" for p in parts)


def _write_report(preset, specs: list[RunSpec], out: Path, say: Callable[[str], None],
                  planned: list[RunSpec] | None = None, changes: str = "",
                  paper_settings: bool = False) -> dict[str, Any]:
    """Write the preset's report from ``specs`` and print its markdown."""
    from lili.experiments.results import write_preset_report

    report = write_preset_report(preset, specs, out, planned=planned, changes=changes,
                                 paper_settings=paper_settings)
    say(report["markdown"])
    return report


def _report_only(name: str, preset, specs: list[RunSpec], status: dict[RunSpec, str],
                 out: Path, say: Callable[[str], None], changes: str,
                 paper_settings: bool = False) -> dict[str, Any]:
    done = [s for s in specs if status[s] == "done"]
    if not done:
        raise ValueError(f"--report-only: no run of preset {name!r} is finished under {out}; "
                         f"allowed: an --out that holds finished runs of it")
    say(f"{name}: interim report from {len(done)} of {len(specs)} runs (the rest are not "
        f"finished; nothing is started)")
    report = _write_report(preset, done, out, say, planned=specs, changes=changes,
                           paper_settings=paper_settings)
    claims = _claims_table(preset, out, say)
    say(f"report: {report['dir']}")
    return {"runs": len(specs), "ran": 0, "report": report, "claims": claims}


def _run_all(backend, todo: list[Job], done: int,
             progress: bool | None) -> list[tuple[Job, int]]:
    runs = [s for job in todo for s in job]
    write_agent_configs(runs)
    bar = SweepProgress(runs, done, live=progress)
    queue, failed, running = list(todo), [], 0
    try:
        while queue or running:
            while queue and running < backend.capacity:
                job = queue.pop(0)
                for spec in job:
                    bar.started(spec)
                backend.submit(job)
                running += 1
            for job, code in backend.poll():
                running -= 1
                for spec in job:
                    bar.ended(spec, code, backend.capacity)
                if code != 0:
                    failed.append((job, code))
            bar.refresh(backend.capacity)
            time.sleep(0.5)
    finally:
        bar.stop()
        backend.close()
    return failed
