"""Command-line interface: ``granframe <command>``.

Commands
--------
plugins [--json]
    List every registered implementation per family with its source and a
    one-line description. The JSON form is documented in docs/plugins.md.
bench [--json] [--backend NAME] [--threads T] [--repeats R] [--precision P]
      [--config D:N[:N_RHO:M] ...] [--batch B ...]
    Time the fast operator against the FFT floor (docs/benchmarks.md); with --batch, on
    stacks of B distributions, per distribution.
run SOURCE --out STORE [--resume [--rollback]] [--overwrite] [--quick] [--only NAMES]
    [--progress]
    Run a description (a TOML file or a study module under studies/) into a zarr store;
    a study with several runs writes STORE/<name>.zarr each, then its report.
    Exit status 3 when a health check stopped the run, 130 when interrupted.
plot STORE --out DIR [--format png|pdf|svg] [--dpi DPI]
    Draw the figures of a run (PNG unless --format says otherwise).
info STORE
    Say what is in a store.
check STORE
    Read every committed chunk of a run (or sweep) store and list the missing or damaged
    ones; exit status 3 when there is any.
sweep SWEEP.toml --out STORE [--scheduler ADDRESS] [--workers N] [--overwrite]
      [--retry-failed] [--progress]
    Run every point of a parameter sweep on Dask into one zarr store (docs/scaling.md);
    running it again skips ended runs and resumes cut ones. Exit status 3 when a run failed.
advise SCENE.toml [--out DESCRIPTION.toml] [--json]
    Propose the cheapest configuration predicted to meet the scene's tolerance
    (docs/advise.md); --out writes it as a run description for ``granframe run``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

from granframe._version import __version__


def _plugins(args) -> int:
    from granframe.registry import FAMILIES, default_registries

    registries = default_registries()
    if args.json:
        json.dump(registries.to_json(), sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    for family in FAMILIES:
        entries = registries.entries(family)
        print(f"{family} ({len(entries)})")
        if not entries:
            print("    (none registered)")
        width = max((len(e.name) for e in entries), default=0)
        for e in entries:
            print(f"    {e.name:<{width}}  {e.description}  [{e.source}]")
    return 0


def _bench(args) -> int:
    from granframe.tools import bench

    from granframe.backends import AUTO, resolve_backend

    backend = resolve_backend(AUTO if args.backend is None else args.backend)
    configs = ([bench.parse_config(c) for c in args.config] if args.config
               else list(bench.DEFAULT_CONFIGS))
    records = bench.run(configs, backend, args.threads, args.repeats, args.precision,
                        batches=args.batch or (1,))
    if args.json:
        json.dump({"schema": "granframe.tools.bench/1", "granframe_version": __version__,
                   "records": records}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(f"fast_spectral, backend {backend}, {args.threads} threads, {args.precision}, "
              f"median of {args.repeats} evaluations after warm-up"
              + (", B distributions per evaluation (time and floor per distribution)"
                 if args.batch else ""))
        print(bench.table(records))
    return 0


def _run(args) -> int:
    from granframe.run import storage
    from granframe.run.runner import check_run_modes, load_study

    check_run_modes(args.resume, args.overwrite)   # before the study is loaded
    if args.rollback and not args.resume:
        raise ValueError("run: --rollback applies to --resume (it continues from the last "
                         "intact commit of a damaged store)")
    study = load_study(args.source, quick=args.quick)
    out = pathlib.Path(args.out)
    if list(study.runs) == [""]:
        if args.only:
            raise ValueError("run: --only applies to studies with several runs")
        return _run_one(study.runs[""], out, args)
    names = list(study.runs) if not args.only else args.only.split(",")
    unknown = [n for n in names if n not in study.runs]
    if unknown:
        raise ValueError(f"run: parameter 'only' = {args.only!r} is invalid; the study's runs "
                         f"are {', '.join(study.runs)}")
    kind = {"run": "run store", "sweep": "sweep store", "file": "file"}.get(
        storage.store_kind(out))
    if kind is not None:
        raise ValueError(f"run: parameter 'out' = '{out}' is invalid; a study with several "
                         f"runs writes a folder of stores (OUT/<name>.zarr), and '{out}' is a "
                         f"{kind}")
    out.mkdir(parents=True, exist_ok=True)
    status = 0
    for name in names:
        print(f"[{name}] {study.runs[name].title}")
        code = _run_one(study.runs[name], out / f"{name}.zarr", args)
        if code == 130:
            return code
        status = max(status, code)
    # the report reads finished runs and runs stopped by a health check (their moments up to
    # the stop are valid data); it waits for runs that are missing or interrupted
    ended = {}
    for name in study.runs:
        store = out / f"{name}.zarr"
        if storage.store_kind(store) == "run" and storage.RunStore.open(store).progress.get(
                "status") in ("finished", "failed"):
            ended[name] = store
    if study.report is not None and len(ended) == len(study.runs):
        report = out / "report"
        try:
            summary = study.report(ended, report)
            text = json.dumps(summary, indent=2) + "\n"
        except Exception as exc:   # the study's own code: say where it failed, keep the runs
            raise ValueError(f"run: the report of study '{args.source}' failed: "
                             f"{_where(exc, args.source)}; the runs' stores in '{out}' are "
                             "kept (fix the report, then run again with --resume)") from None
        (report / "summary.json").write_text(text)
        print(f"report: {report} (summary.json and figures)")
    elif study.report is not None:
        print(f"report: waiting for {len(study.runs) - len(ended)} of {len(study.runs)} runs "
              "(run again with --resume)")
    return status


def _where(exc: BaseException, source) -> str:
    """``Type: message (at file:line)``, the line being the innermost one in ``source``."""
    from granframe.run.runner import line_in

    line = line_in(exc, source)
    return f"{type(exc).__name__}: {exc}" + (f" (at {source}:{line})" if line else "")


def _run_one(description, out, args) -> int:
    from granframe.model.initial import projection_note
    from granframe.run.runner import HealthError, Simulation
    from granframe.run.storage import RunStore, check_replaceable, store_kind

    if args.overwrite:          # refused before the operator is built
        check_replaceable(out, protect=[args.source])
    if args.resume and store_kind(out) == "run":
        # an ended run is reported from its store, without building the operator
        progress = RunStore.open(out, complete=False).progress
        if progress.get("status") == "failed":   # resuming would fail again
            print(f"{out}: stopped earlier by a health check ({progress.get('message')}); "
                  "not resumed", file=sys.stderr)
            return 3
        if progress.get("status") == "finished":
            RunStore.resume(out, description.to_dict()).close()   # refuses another description
            print(f"{out}: the run is already finished (t = {progress['time']:g}, "
                  f"{progress['step']} steps, {progress.get('wall_seconds', 0.0):.1f} s)")
            return 0
    try:
        simulation = Simulation(description)
        note = projection_note(simulation.projection)
        if note:
            print(f"granframe: {note}", file=sys.stderr)
        result = simulation.run(out, resume=args.resume, overwrite=args.overwrite,
                                progress=args.progress, rollback=args.rollback,
                                protect=[args.source])
    except HealthError as exc:
        print(f"granframe: run stopped: {exc}\nThe store '{out}' keeps every snapshot "
              "before it and the moments up to it.", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("\ngranframe: interrupted; " + _interrupted(out), file=sys.stderr)
        return 130
    print(f"{out}: finished, {result.steps} steps to t = {result.time:g} in "
          f"{result.wall_seconds:.1f} s, {result.snapshots} snapshots")
    for warning in result.warnings:
        print(f"granframe: warning: f at t = {result.time:g} is under-resolved: {warning}",
              file=sys.stderr)
    return 0


def _interrupted(out) -> str:
    """What a Ctrl-C left at ``out``, in words."""
    from granframe.run.storage import RunStore, StoreError

    if not RunStore.exists(out):
        return f"nothing was written to '{out}'"
    try:
        status = RunStore.open(out, complete=False).progress.get("status")
    except StoreError as exc:
        return f"the store '{out}' cannot be read: {exc}"
    if status == "interrupted":
        return (f"the store '{out}' holds every complete snapshot: continue with "
                "--resume")
    return f"the store '{out}' is as it was before this run (status {status})"


def _check(args) -> int:
    from granframe.run.storage import check

    intact, lines = check(args.store)
    print("\n".join(lines))
    print("intact" if intact else "DAMAGED: the chunks above are missing or fail their "
          "checksum; granframe run --resume --rollback continues from the last intact commit")
    return 0 if intact else 3


def _plot(args) -> int:
    from granframe.tools.plotting import plot

    for path in plot(args.store, args.out, format=args.format, dpi=args.dpi):
        print(path)
    return 0


def _dpi(text: str) -> float:
    """``--dpi``: a finite number within the plotting module's DPI_RANGE."""
    from granframe.tools.plotting import DPI_RANGE

    low, high = DPI_RANGE
    try:
        value = float(text)
    except ValueError:
        value = None
    if value is None or not low <= value <= high:
        raise argparse.ArgumentTypeError(f"must be a number from {low} to {high}, got {text!r}")
    return value


def _info(args) -> int:
    from granframe.run.storage import describe, store_kind
    from granframe.run.sweep import describe_sweep

    print(describe_sweep(args.store) if store_kind(args.store) == "sweep"
          else describe(args.store))
    return 0


def _sweep(args) -> int:
    from granframe.run.sweep import Sweep, run_sweep

    path = pathlib.Path(args.sweep)
    if not path.is_file():
        raise ValueError(f"sweep: parameter 'sweep' = '{args.sweep}' is invalid; no such file")
    try:
        result = run_sweep(Sweep.from_toml(path.read_text()), args.out,
                           scheduler=args.scheduler, workers=args.workers,
                           progress=args.progress, overwrite=args.overwrite,
                           retry_failed=args.retry_failed, protect=(path,))
    except KeyboardInterrupt:
        print(f"\ngranframe: interrupted; the sweep store '{args.out}' keeps every ended run "
              "and every snapshot of the others: run the same sweep again to continue",
              file=sys.stderr)
        return 130
    print(f"{result.store}: {result.finished} finished, {result.failed} failed "
          f"({result.skipped} ended before, {result.refused} refused before) in "
          f"{result.wall_seconds:.1f} s; results: "
          f"granframe.open_sweep('{result.store}')")
    return 3 if result.failed else 0


def _advise(args) -> int:
    import tomllib

    from granframe.tools.advise import Scene, advise

    path = pathlib.Path(args.scene)
    if not path.is_file():
        raise ValueError(f"advise: parameter 'scene' = '{args.scene}' is invalid; no such file")
    try:
        scene = Scene.from_dict(tomllib.loads(path.read_text()))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"advise: the TOML text of '{path}' is invalid: {exc}") from None
    advice = advise(scene)
    if args.json:
        json.dump({"schema": "granframe.advice/1", "closed_form": advice.closed_form,
                   "errors": advice.errors, "predicted_seconds": advice.predicted_seconds,
                   "evaluation_seconds": advice.evaluation_seconds,
                   "evaluations": advice.evaluations, "reasons": list(advice.reasons),
                   "description": None if advice.description is None
                   else advice.description.to_dict()}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(advice.report())
    if args.out and advice.description is not None:
        pathlib.Path(args.out).write_text(advice.description.to_toml())
        if not args.json:
            print(f"description: {args.out} (granframe run {args.out} --out STORE)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="granframe",
        description="Fourier spectral solvers for the inelastic Boltzmann equation.")
    parser.add_argument("--version", action="version", version=f"granframe {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    plugins = commands.add_parser("plugins", help="list registered implementations per family")
    plugins.add_argument("--json", action="store_true", help="machine-readable output")
    plugins.set_defaults(handler=_plugins)
    bench = commands.add_parser("bench", help="time the fast operator against the FFT floor")
    bench.add_argument("--json", action="store_true", help="machine-readable output")
    bench.add_argument("--backend", default=None, help="array backend (default: pyfftw if "
                       "installed, else numpy)")
    bench.add_argument("--threads", type=int, default=2, help="threads (default 2)")
    bench.add_argument("--repeats", type=int, default=7, help="timed evaluations (default 7)")
    bench.add_argument("--precision", default="float64", choices=["float64", "float32"],
                       help="arithmetic of the operator and of the floor (default float64)")
    bench.add_argument("--config", action="extend", nargs="+", metavar="D:N[:N_RHO:M]",
                       help="configurations (one or more, repeatable); default: the review's "
                            "five")
    bench.add_argument("--batch", action="extend", nargs="+", type=int, metavar="B",
                       help="stack sizes: evaluate B distributions at once and report the "
                            "time and FFT floor per distribution (e.g. --batch 1 8 64); "
                            "default: one distribution")
    bench.set_defaults(handler=_bench)
    run = commands.add_parser("run", help="run a description (TOML or study module) into a store")
    run.add_argument("source", metavar="STUDY_OR_TOML",
                     help="a .toml run description or a .py study defining description(quick)")
    run.add_argument("--out", required=True, metavar="STORE",
                     help="zarr store to write (a folder of stores for a study with several "
                          "runs, plus report/)")
    run.add_argument("--only", metavar="NAMES", help="comma-separated runs of a study to run")
    run.add_argument("--resume", action="store_true",
                     help="continue the run in STORE from its last complete snapshot")
    run.add_argument("--overwrite", action="store_true",
                     help="replace an existing granframe store STORE (nothing else)")
    run.add_argument("--rollback", action="store_true",
                     help="with --resume: continue a damaged store from its last intact "
                          "commit")
    run.add_argument("--quick", action="store_true",
                     help="the study's reduced variant (smaller grid or time)")
    run.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="progress bar (default: only on a terminal)")
    run.set_defaults(handler=_run)
    plot = commands.add_parser("plot", help="draw the figures of a run store (PNG, PDF or SVG)")
    plot.add_argument("store", metavar="STORE")
    plot.add_argument("--out", required=True, metavar="DIR", help="folder for the figures")
    plot.add_argument("--format", default="png", choices=["png", "pdf", "svg"],
                      help="file format of the figures (default png)")
    plot.add_argument("--dpi", type=_dpi, default=110,
                      help="resolution of the raster parts in dots per inch, 10 to 600 "
                           "(default 110)")
    plot.set_defaults(handler=_plot)
    info = commands.add_parser("info", help="say what is in a run store")
    info.add_argument("store", metavar="STORE")
    info.set_defaults(handler=_info)
    check = commands.add_parser("check", help="read every committed chunk of a store and "
                                "report missing or damaged ones (exit 3 if any)")
    check.add_argument("store", metavar="STORE")
    check.set_defaults(handler=_check)
    sweep = commands.add_parser("sweep", help="run a parameter sweep on Dask into one store")
    sweep.add_argument("sweep", metavar="SWEEP.toml",
                       help="a base description ([base]) and axes ([product], [zip])")
    sweep.add_argument("--out", required=True, metavar="STORE", help="the sweep's zarr store")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler (default: a LocalCluster here)")
    sweep.add_argument("--workers", type=int, default=None,
                       help="worker processes of the LocalCluster (default: one per core)")
    sweep.add_argument("--overwrite", action="store_true",
                       help="replace an existing granframe store STORE (nothing else)")
    sweep.add_argument("--retry-failed", action="store_true",
                       help="run again the points refused for their parameters and the runs "
                            "stopped by a health check (default: keep them failed)")
    sweep.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                       help="progress bar (default: only on a terminal)")
    sweep.set_defaults(handler=_sweep)
    advise = commands.add_parser("advise", help="the cheapest configuration for a scene and "
                                 "tolerance")
    advise.add_argument("scene", metavar="SCENE.toml",
                        help="physics, quantity (temperature or distribution) and tolerance")
    advise.add_argument("--out", metavar="DESCRIPTION.toml",
                        help="write the proposed run description")
    advise.add_argument("--json", action="store_true", help="machine-readable output")
    advise.set_defaults(handler=_advise)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:   # Ctrl-C outside a run (start-up, a report, a sweep)
        print("\ngranframe: interrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError, OSError) as exc:
        print(f"granframe: error: {exc}", file=sys.stderr)
        return 2


def _interrupt(signum, frame):
    """Ctrl-C as KeyboardInterrupt, but never inside the import machinery: raised in one of
    importlib's lock callbacks it would be printed as "Exception ignored" and lost (the run
    would go on), so there it is sent again 10 ms later, once the import has returned."""
    if frame is not None and frame.f_code.co_filename.startswith("<frozen importlib"):
        import os
        import threading

        threading.Timer(0.01, os.kill, (os.getpid(), signum)).start()
        return
    raise KeyboardInterrupt


def entry() -> None:
    """The ``granframe`` command: :func:`main`'s status as the process's exit status.

    Ctrl-C is delivered outside the import machinery (:func:`_interrupt`). After it the
    process leaves with status 130 through ``os._exit`` (stdout and stderr flushed first;
    the run has already marked and released its store): CPython would otherwise end it by
    SIGINT whenever the KeyboardInterrupt passed through code run by ``PyRun_*``, such as
    the initialisation of a compiled module being imported, even though :func:`main`
    handled it.
    """
    import signal

    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:   # not ignored
        signal.signal(signal.SIGINT, _interrupt)
    code = main()
    if code == 130:
        import os

        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(code)


if __name__ == "__main__":
    entry()
