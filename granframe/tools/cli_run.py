"""The commands of ``granframe`` that run: ``run`` (a description, or a study's runs into a
folder of stores and then its report) and ``sweep`` (a parameter sweep on Dask); and
the processes a launcher started, of which one speaks and draws the report.
"""

from __future__ import annotations

import contextlib
import json
import pathlib
import sys

import attrs

from granframe.tools.cli_inputs import load_study, read_text, read_toml, with_settings


def run_command(args) -> int:
    """``granframe run``: one run into its store, or a study's runs into a folder of stores
    and then its report; the exit status (3 after a health stop, 130 when interrupted)."""
    from granframe.registry import did_you_mean
    from granframe.run import storage
    from granframe.run.runner import check_run_modes

    check_run_modes(args.resume, args.overwrite)   # before the study is loaded
    if args.rollback and not args.resume:
        raise ValueError("run: --rollback applies to --resume (it continues from the last "
                         "intact commit of a damaged store)")
    study = load_study(args.source, args.quick)
    if args.only and list(study.runs) != [""]:
        unknown = [n for n in args.only.split(",") if n not in study.runs]
        if unknown:
            raise ValueError(f"run: parameter 'only' = {args.only!r} is invalid; the study's "
                             f"runs are {', '.join(study.runs)}"
                             f"{did_you_mean(unknown[0], study.runs)}")
    if args.set:
        study = attrs.evolve(study, runs={name: with_settings(description, args.set)
                                          for name, description in study.runs.items()})
    out = pathlib.Path(args.out)
    if list(study.runs) == [""]:
        if args.only:
            raise ValueError("run: --only applies to studies with several runs")
        return _run_one(study.runs[""], out, args)
    names = list(study.runs) if not args.only else args.only.split(",")
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
    if study.report is not None and processes()[1] == 0:   # one process draws the report
        _report(study, out, args.source)
    return status


def _report(study, out: pathlib.Path, source) -> None:
    """Write the study's report to ``out/report`` from the runs in ``out`` that ended.

    Runs that finished and runs stopped by a health check (their moments up to the stop
    are valid data) have ended; missing or interrupted ones have not. The report gets
    the stores of those that ended, so after ``--only`` it covers the runs made so far;
    a report that looks up a run that has not ended (a KeyError naming it) waits for it.
    """
    from granframe.run import storage

    ended = {}
    for name in study.runs:
        store = out / f"{name}.zarr"
        if storage.store_kind(store) == "run" and storage.RunStore.open(store).progress.get(
                "status") in ("finished", "failed"):
            ended[name] = store
    waiting = [name for name in study.runs if name not in ended]
    if not ended:
        print(f"report: waiting for the runs ({len(waiting)} have not ended; run again "
              "with --resume)")
        return
    report = out / "report"
    try:
        summary = study.report(ended, report)
        text = json.dumps(summary, indent=2) + "\n"
    except KeyError as exc:
        if not (exc.args and exc.args[0] in waiting):
            raise _report_failed(exc, source, out) from None
        print(f"report: waiting for {len(waiting)} of {len(study.runs)} runs (it reads "
              f"'{exc.args[0]}', which has not ended): run them with --only "
              f"{','.join(waiting)}, or run again with --resume")
        return
    except Exception as exc:   # the study's own code: say where it failed, keep the runs
        raise _report_failed(exc, source, out) from None
    (report / "summary.json").write_text(text)
    print(f"report: {report} (summary.json and figures)"
          + (f", from {len(ended)} of {len(study.runs)} runs: {', '.join(ended)}"
             if waiting else ""))


def _report_failed(exc, source, out) -> ValueError:
    """The refusal of a study whose report raised ``exc``, keeping its runs' stores."""
    return ValueError(f"run: the report of study '{source}' failed: {_where(exc, source)}; "
                      f"the runs' stores in '{out}' are kept (fix the report, then run again "
                      "with --resume)")


def _where(exc: BaseException, source) -> str:
    """``Type: message (at file:line)``, the line being the innermost one in ``source``."""
    from granframe.run.runner import line_in

    line = line_in(exc, source)
    return f"{type(exc).__name__}: {exc}" + (f" (at {source}:{line})" if line else "")


def _run_one(description, out, args) -> int:
    """One run of ``description`` into the store ``out``, with ``run``'s options ``args``;
    the exit status (3 after a health stop, 130 when interrupted)."""
    from granframe.model.initial import projection_note
    from granframe.run.monitors import cooling_hint
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
        if progress.get("status") == "finished" and not args.rollback:
            if processes()[1] == 0:   # the lock is one process's
                RunStore.resume(out, description.to_dict()).close()   # refuses another description
            print(f"{out}: the run is already finished (t = {progress['time']:g}, "
                  f"{progress['step']} steps, {progress.get('wall_seconds', 0.0):.1f} s)")
            return 0
    try:
        simulation = Simulation(description, partition=args.partition)
        # a space run keeps no projection record (None): nothing to note
        projection = simulation.problem.projection
        note = projection_note(projection) if projection else None
        if note:
            print(f"granframe: {note}", file=sys.stderr)
        hint = cooling_hint(description)
        if hint:
            print(f"granframe: hint: {hint}", file=sys.stderr)
        with together(simulation.communicator):
            print(f"granframe: {_cost(simulation.problem, out if args.resume else None)}",
                  flush=True)
            result = simulation.run(out, resume=args.resume, overwrite=args.overwrite,
                                    progress=args.progress, rollback=args.rollback,
                                    protect=[args.source])
    except HealthError as exc:
        print(f"granframe: run stopped: {exc}\nThe store '{out}' keeps every snapshot "
              "before it and the moments up to it.", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        quiet_teardown()
        print("\ngranframe: interrupted; " + _interrupted(out), file=sys.stderr)
        return 130
    if result.status == "already finished":      # --rollback found nothing to take back
        print(f"{out}: the run is already finished (t = {result.time:g}, {result.steps} "
              "steps) and every chunk is intact: nothing to roll back")
        return 0
    print(f"{out}: finished, {result.steps} steps to t = {result.time:g} in "
          f"{result.wall_seconds:.1f} s, {result.snapshots} snapshots")
    if args.rollback:
        from granframe.run.storage import dropped_note

        note = dropped_note(RunStore.open(out, complete=False).metadata)
        if note:
            print(f"granframe: the rollback {note}", file=sys.stderr)
    for warning in result.warnings:
        print(f"granframe: warning: f at t = {result.time:g} is under-resolved: {warning}",
              file=sys.stderr)
    for warning in result.accuracy_warnings:
        print(f"granframe: warning: at t = {result.time:g}: {warning}", file=sys.stderr)
    print(verdict(result))
    return 0


def verdict(result) -> str:
    """The one line that ends a run: whether its last output point passed every resolution
    and accuracy check, or which of them warned (the warnings above say what to raise)."""
    warned = [w.split(":")[0] for w in (*result.warnings, *result.accuracy_warnings)]
    if not warned:
        return (f"verdict: resolved at t = {result.time:g}: no resolution or accuracy "
                "indicator above its tolerance (docs/runner.md, \"Health checks\")")
    topics = ", ".join(dict.fromkeys(warned))
    return (f"verdict: not resolved at t = {result.time:g}: {len(warned)} warning"
            f"{'s' if len(warned) > 1 else ''} ({topics}); numbers from this run carry the "
            "errors they estimate: follow the warnings, or measure the error bars with "
            "granframe refine")


@contextlib.contextmanager
def together(communicator):
    """Around the part of a run that its processes make together (the cost estimate's step
    and the run): an error in one process is printed with its number and ends them all
    (:meth:`~granframe.abc.Communicator.abort`, status 2 for granframe's refusals, 1 for
    anything else), since the others would wait for it for ever. A health stop, a Ctrl-C
    and an error raised in every process at the same point (a refusal of the store,
    :data:`granframe.parallel.RAISED_EVERYWHERE`) reach every process and pass through:
    process 0 says it once."""
    from granframe.run.runner import HealthError

    try:
        yield
    except (HealthError, KeyboardInterrupt):
        raise
    except BaseException as exc:
        from granframe.parallel import RAISED_EVERYWHERE

        if communicator.size == 1 or getattr(exc, RAISED_EVERYWHERE, False):
            raise         # every process stops here: process 0 says why, once
        print(f"granframe: error in process {communicator.rank} of {communicator.size}: "
              f"{type(exc).__name__}: {exc}", file=sys.__stderr__, flush=True)
        communicator.abort(2 if isinstance(exc, (ValueError, TypeError, OSError)) else 1)
        raise         # an abort that returned: the process must not go on either


def _cost(problem, resumed=None) -> str:
    """The run's estimated cost in one line (:func:`~granframe.run.problems.run_cost`);
    ``resumed``: the store a resumed run continues, whose steps done are left out."""
    from granframe.run.problems import run_cost
    from granframe.run.storage import RunStore, store_kind

    cost = run_cost(problem)
    if resumed is not None and cost.steps is not None and store_kind(resumed) == "run":
        done = int(RunStore.open(resumed, complete=False).progress.get("step", 0))
        cost = attrs.evolve(cost, steps=max(cost.steps - done, 0))
        return cost.text() + f" (the {done} steps done are not counted)"
    return cost.text()


def quiet_teardown() -> None:
    """After Ctrl-C the process only exits: objects the interrupt left half built (an event
    loop interrupted in its constructor) may fail in their destructors at exit, and Python
    would print those failures as "Exception ignored ... Traceback" and unawaited
    coroutines as warnings. Silence both for the rest of the process, so that an interrupt
    ends with granframe's one line and status 130."""
    import warnings

    sys.unraisablehook = lambda unraisable: None
    warnings.simplefilter("ignore")


def _interrupted(out) -> str:
    """What a Ctrl-C left at ``out``, in words."""
    from granframe.run.storage import RunStore, StoreError

    if not RunStore.exists(out):
        return f"nothing was written to '{out}'"
    try:
        status = RunStore.open(out, complete=False).progress.get("status")
    except StoreError as exc:
        return f"the store '{out}' cannot be read: {exc}"
    if status in ("interrupted", "running"):   # running: cut before the run could mark it
        return (f"the store '{out}' holds every complete snapshot (status {status}): "
                "continue with --resume")
    if status == "finished":
        return f"the store '{out}' holds the finished run"
    return f"the store '{out}' is as it was before this run (status {status})"


def sweep_command(args) -> int:
    """``granframe sweep``: every point of a parameter sweep into one store; the exit status
    (3 when a run failed, 130 when interrupted)."""
    from granframe.run.sweep import Sweep, run_sweep
    from granframe.validators import existing_file

    path = pathlib.Path(args.sweep)
    existing_file("sweep", "sweep", path, "a .toml sweep")
    try:
        result = run_sweep(Sweep.from_toml(read_text(path, "sweep", "sweep")), args.out,
                           scheduler=args.scheduler, workers=args.workers,
                           progress=args.progress, overwrite=args.overwrite,
                           retry_failed=args.retry_failed, protect=(path,),
                           processes=args.processes)
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


def _vary(text: str):
    """``KEY=V1,V2,...`` of ``granframe refine --vary``: the key and its values (integers
    where they are whole)."""
    key, sep, values = text.partition("=")
    if not sep or not key.strip() or not values.strip():
        raise ValueError(f"refine: parameter '--vary' = {text!r} is invalid; must read "
                         "KEY=V1,V2,... (e.g. grid.n_modes=24,32,48)")
    numbers = []
    for value in values.split(","):
        try:
            number = float(value)
        except ValueError:
            raise ValueError(f"refine: parameter '--vary' = {text!r} is invalid; its values "
                             f"must be numbers, not {value!r}") from None
        numbers.append(int(number) if number.is_integer() and "." not in value else number)
    return key.strip(), numbers


def refine_command(args) -> int:
    """``granframe refine``: the family of a description refined together, run as a sweep,
    and each quantity's observed order, Richardson estimate and grid convergence index
    (:mod:`granframe.run.refinement`); exit 3 when a member did not finish."""
    from granframe.run.description import RunDescription
    from granframe.run.refinement import Refinement, run_refinement
    from granframe.validators import existing_file

    path = pathlib.Path(args.description)
    existing_file("refine", "description", path, "a .toml run description")
    base = read_toml(path, "refine", "description")
    RunDescription.from_dict(base)
    vary = dict(_vary(text) for text in args.vary)
    refinement = Refinement(base, vary, args.quantity)
    try:
        result = run_refinement(refinement, args.out, workers=args.workers,
                                formal_order=args.formal_order, progress=args.progress,
                                overwrite=args.overwrite)
    except KeyboardInterrupt:
        print(f"\ngranframe: interrupted; '{args.out}/family.zarr' keeps every ended run: run "
              "the same command again to continue", file=sys.stderr)
        return 130
    out = pathlib.Path(args.out)
    print((out / "refinement.md").read_text(), end="")
    print(f"figure: {out / 'refinement.png'}; stores: {result.store}")
    finished = len(result.rows[0]["values"]) if result.rows else 0
    return 3 if finished < len(result.spacings) else 0


def processes():
    """(size, rank) of the processes a launcher started (:func:`granframe.parallel.launched`,
    read from the environment: nothing is imported)."""
    from granframe.parallel import launched

    size, rank, _ = launched()
    return size, rank
