"""Command-line interface: ``granframe <command>``.

Commands
--------
plugins [--json] [[FAMILY] NAME]
    List every registered implementation per family with its source and a
    one-line description; with NAME, show one implementation (its family, description,
    parameters with their types and defaults, docstring summary). The JSON forms are
    documented in docs/plugins.md.
bench [--json] [--backend NAME] [--threads T] [--repeats R] [--precision P]
      [--config D:N[:N_RHO:M] ...] [--batch B ...]
    Time the fast operator against the FFT floor (docs/benchmarks.md); with --batch, on
    stacks of B distributions, per distribution.
run SOURCE --out STORE [--resume [--rollback]] [--overwrite] [--quick] [--only NAMES]
    [--progress] [--set KEY=VALUE ...]
    Run a description (a TOML file or a study module under studies/) into a zarr store;
    a study with several runs writes STORE/<name>.zarr each, then its report (from the
    runs that have ended, so also after --only). --set overrides a key of the description.
    Exit status 3 when a health check stopped the run, 130 when interrupted.
plot STORE --out DIR [--format png|pdf|svg] [--dpi DPI]
    Draw the figures of a run (PNG unless --format says otherwise).
info STORE [--json]
    Say what is in a store (--json: a run store's content as a JSON document).
check STORE
    Read every committed chunk of a run (or sweep) store and list the missing or damaged
    ones; exit status 3 when there is any.
sweep SWEEP.toml --out STORE [--scheduler ADDRESS] [--workers N] [--overwrite]
      [--retry-failed] [--progress]
    Run every point of a parameter sweep on Dask into one zarr store (docs/scaling.md);
    running it again skips ended runs and resumes cut ones. Exit status 3 when a run failed.
advise SCENE.toml [--out DESCRIPTION.toml] [--json]
    Propose the cheapest configuration predicted to meet the scene's tolerance
    (docs/advise.md); --out writes it as a run description for ``granframe run``. A scene
    with a [space] table, or a space run description, also gets the price of a hierarchy
    of collision models against the all-kinetic run.
limits SOURCE [--quick] [--set KEY=VALUE ...] [--json] [--no-cost]
    The explicit time-step limit of each run of a description, and the rates behind it,
    without building the operator; then the run's estimated cost (its operator built and
    one step timed; --no-cost leaves it out). Exit status 3 when a fixed time step is above
    a limit (the table is printed all the same).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import pathlib
import re
import sys

import attrs

from granframe._version import __version__


def _plugins(args) -> int:
    from granframe.registry import FAMILIES, default_registries

    registries = default_registries()
    families = list(FAMILIES)
    if len(args.names) == 1 and args.names[0] in FAMILIES:
        families = args.names
    elif args.names:
        entry = _entry(registries, args.names)
        if args.json:
            json.dump(_entry_document(entry), sys.stdout, indent=2)
            sys.stdout.write("\n")
        else:
            print(_entry_text(entry))
        return 0
    if args.json:
        document = registries.to_json()
        document["families"] = {f: document["families"][f] for f in families}
        json.dump(document, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    for family in families:
        entries = registries.entries(family)
        print(f"{family} ({len(entries)})")
        if not entries:
            print("    (none registered)")
        width = max((len(e.name) for e in entries), default=0)
        for e in entries:
            print(f"    {e.name:<{width}}  {e.description}  [{e.source}]")
    return 0


def _entry(registries, names):
    """The registered implementation that ``plugins NAME`` or ``plugins FAMILY NAME``
    means; an unknown one gets the closest name."""
    from granframe.errors import UnknownNameError
    from granframe.registry import FAMILIES, did_you_mean

    if len(names) > 2:
        raise ValueError(f"plugins: parameter 'names' = {' '.join(names)!r} is invalid; give "
                         "NAME or FAMILY NAME, e.g. granframe plugins collision_kernels vhs")
    if len(names) == 2:
        return registries.get(*names)
    [name] = names
    found = registries.find(name)
    if len(found) > 1:
        raise UnknownNameError(f"plugins: name {name!r} is registered in several families "
                               f"({', '.join(e.family for e in found)}); give FAMILY NAME, "
                               f"e.g. granframe plugins {found[0].family} {name}")
    if not found:
        known = [n for family in FAMILIES for n in registries.names(family)] + list(FAMILIES)
        raise UnknownNameError(f"plugins: name {name!r} is not registered in any family"
                               f"{did_you_mean(name, known)} (granframe plugins lists them)")
    return found[0]


def _entry_document(entry) -> dict:
    """``granframe plugins NAME --json`` (docs/plugins.md)."""
    parameters = entry.parameters()
    return {"schema": "granframe.plugin/1", "granframe_version": __version__,
            "family": entry.family, **entry.to_dict(), "factory": entry.factory_path,
            "summary": entry.summary(),
            "parameters": None if parameters is None else [p.to_dict() for p in parameters]}


def _entry_text(entry) -> str:
    """``granframe plugins NAME``: one implementation in words."""
    from granframe.registry import OPERATOR_ARGUMENTS

    lines = [f"{entry.name} ({entry.family})",
             f"  description  {entry.description}",
             f"  source       {entry.source}",
             f"  factory      {entry.factory_path}"]
    summary = entry.summary()
    if summary and summary != entry.description:
        lines.append(f"  summary      {summary}")
    parameters = entry.parameters()
    after = (f" (after {', '.join(OPERATOR_ARGUMENTS)})"
             if entry.family == "collision_operators" else "")
    if parameters is None:
        lines.append("parameters: not known (the factory has no signature)")
    elif not parameters:
        lines.append(f"parameters{after}: none")
    else:
        lines.append(f"parameters{after}:")
        rows = [(p.name, p.type or "-", "required" if p.required else f"default {p.default!r}")
                for p in parameters]
        widths = [max(len(row[i]) for row in rows) for i in range(2)]
        lines.extend(f"  {n:<{widths[0]}}  {t:<{widths[1]}}  {d}" for n, t, d in rows)
    return "\n".join(lines)


def _bench(args) -> int:
    from granframe.tools import bench

    from granframe.backends import AUTO, resolve_backend

    backend = resolve_backend(AUTO if args.backend is None else args.backend)
    if args.space is not None:
        configs = ([bench.parse_space_config(c) for c in args.space] if args.space
                   else list(bench.DEFAULT_SPACE_CONFIGS))
        records = bench.run_space(configs, backend, args.threads, args.repeats)
        heading = (f"space step (Strang: transport, RK4 collisions on all cells, transport), "
                   f"backend {backend}, {args.threads} threads, median of {args.repeats} "
                   "rounds after warm-up")
        table = bench.space_table
    else:
        configs = ([bench.parse_config(c) for c in args.config] if args.config
                   else list(bench.DEFAULT_CONFIGS))
        records = bench.run(configs, backend, args.threads, args.repeats, args.precision,
                            batches=args.batch or (1,), quadratures=args.quadrature or (None,))
        heading = (f"fast_spectral, backend {backend}, {args.threads} threads, "
                   f"{args.precision}, median of {args.repeats} evaluations after warm-up"
                   + (", B distributions per evaluation (time and floor per distribution)"
                      if args.batch else ""))
        table = bench.table
    if args.json:
        json.dump({"schema": "granframe.tools.bench/1", "granframe_version": __version__,
                   "records": records}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(heading)
        print(table(records))
    return 0


def _run(args) -> int:
    from granframe.registry import did_you_mean
    from granframe.run import storage
    from granframe.run.runner import check_run_modes

    check_run_modes(args.resume, args.overwrite)   # before the study is loaded
    if args.rollback and not args.resume:
        raise ValueError("run: --rollback applies to --resume (it continues from the last "
                         "intact commit of a damaged store)")
    study = _load_study(args.source, args.quick)
    if args.only and list(study.runs) != [""]:
        unknown = [n for n in args.only.split(",") if n not in study.runs]
        if unknown:
            raise ValueError(f"run: parameter 'only' = {args.only!r} is invalid; the study's "
                             f"runs are {', '.join(study.runs)}"
                             f"{did_you_mean(unknown[0], study.runs)}")
    if args.set:
        study = attrs.evolve(study, runs={name: _with_settings(description, args.set)
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
    if study.report is not None and _processes()[1] == 0:   # one process draws the report
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
    return ValueError(f"run: the report of study '{source}' failed: {_where(exc, source)}; "
                      f"the runs' stores in '{out}' are kept (fix the report, then run again "
                      "with --resume)")


def _read_text(path: pathlib.Path, command: str, parameter: str) -> str:
    """The text of the file ``path``; a file that is not UTF-8 text refused naming it."""
    try:
        return path.read_text()
    except UnicodeDecodeError as exc:
        raise ValueError(f"{command}: parameter '{parameter}' = '{path}' is invalid; it is not "
                         f"UTF-8 text ({exc.reason} at byte {exc.start}): a TOML file is "
                         "expected") from None


def _load_study(source, quick: bool):
    """:func:`~granframe.run.runner.load_study`, a source that is not text and a study
    that exits (``sys.exit`` while it is imported or makes its runs) refused naming it."""
    from granframe.run.runner import load_study

    try:
        return load_study(source, quick=quick)
    except UnicodeDecodeError as exc:
        raise ValueError(f"run: parameter 'source' = '{source}' is invalid; it is not UTF-8 "
                         f"text ({exc.reason} at byte {exc.start}): a .toml description or a "
                         ".py study module is expected") from None
    except SystemExit as exc:
        raise ValueError(f"run: study '{source}' is invalid; it called sys.exit({exc.code!r}) "
                         "while granframe loaded it or made its runs, so it gives no run: a "
                         "study module defines description(quick) or runs(quick) and does "
                         "not exit") from None


def _with_settings(description, settings: list[str]):
    """``description`` with each ``KEY=VALUE`` of ``run --set`` applied, in order.

    KEY is a dotted key of the description's table (``grid.n_modes``,
    ``operator.sphere.n_points``, ``kernel.name``); one that the description cannot have
    is refused with the closest that it can. The grid's half width and truncation radius,
    when they are the ones its support radius implies, are derived again from the new
    one. VALUE is read as a TOML value (``64``, ``0.5``, ``true``, ``"rk4"``, ``[1, 2]``,
    ``{name = "lebedev", order = 7}``), or taken as a string when it is not one
    (``kernel.name=hard_spheres``).
    """
    import tomllib

    from granframe.registry import did_you_mean
    from granframe.run.description import RunDescription

    data = description.to_dict()
    derived = attrs.evolve(description.grid, half_width=None, truncation_radius=None)
    for key in ("half_width", "truncation_radius"):   # they follow --set grid.support_radius
        if getattr(derived, key) == getattr(description.grid, key):
            del data["grid"][key]
    for setting in settings:
        key, equals, text = setting.partition("=")
        key = key.strip()
        if not equals or not key:
            raise ValueError(f"run: parameter 'set' = {setting!r} is invalid; must be "
                             "KEY=VALUE, e.g. --set grid.n_modes=64")
        known = _settable_keys(data)
        if key not in known:
            raise ValueError(f"run: parameter 'set' = {setting!r} is invalid; '{key}' is not "
                             f"a key of the description{did_you_mean(key, known)}")
        try:
            value = tomllib.loads(f"value = {text.strip()}")["value"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        *parents, last = key.split(".")
        node = data
        for part in parents:
            child = node.get(part)
            node[part] = node = ({"name": child} if isinstance(child, str)
                                 else child if isinstance(child, dict) else {})
        node[last] = value
    return RunDescription.from_dict(data)


def _settable_keys(data: dict) -> list[str]:
    """The dotted keys a description table ``data`` can have: every key it has, every
    field of RunDescription and of its grid, output, health and space tables, and for each
    component (and each quadrature among the operator's options, and the reconstruction
    and walls of the space table) ``name`` and the parameters of the implementation it
    names."""
    from granframe.backends import resolve_backend
    from granframe.registry import default_registries
    from granframe.run.description import (COMPONENT_FAMILIES, Health, Output,
                                           RunDescription, Space)
    from granframe.velocity.grid import VelocityGrid

    def present(table, prefix=""):
        for key, value in table.items():
            yield prefix + key
            if isinstance(value, dict):
                yield from present(value, f"{prefix}{key}.")

    def parameters(family, table, prefix):
        name = table.get("name") if isinstance(table, dict) else table
        yield f"{prefix}name"
        if not isinstance(name, str):
            return
        try:
            entry = default_registries().get(
                family, resolve_backend(name) if family == "array_backends" else name)
        except ValueError:   # an unknown name: the description names the closest
            return
        yield from (prefix + p.name for p in entry.parameters() or ())

    keys = set(present(data))
    tables = {"grid": VelocityGrid, "output": Output, "health": Health, "space": Space}
    for field in attrs.fields(RunDescription):
        if field.init:
            keys.add(field.alias or field.name)
    for table, cls in tables.items():
        keys.update(f"{table}.{f.alias or f.name}" for f in attrs.fields(cls) if f.init)
    for field, family in COMPONENT_FAMILIES.items():
        keys.update(parameters(family, data.get(field), f"{field}."))
    operator = data.get("operator")
    for option, value in (operator.items() if isinstance(operator, dict) else ()):
        if isinstance(value, dict):
            keys.update(parameters("quadratures", value, f"operator.{option}."))
    space = data.get("space") if isinstance(data.get("space"), dict) else {}
    for field in ("reconstruction", "left", "right"):
        keys.update(parameters("reconstructions" if field == "reconstruction" else "boundaries",
                               space.get(field, "muscl" if field == "reconstruction"
                                         else "periodic"), f"space.{field}."))
    return sorted(keys)


def _where(exc: BaseException, source) -> str:
    """``Type: message (at file:line)``, the line being the innermost one in ``source``."""
    from granframe.run.runner import line_in

    line = line_in(exc, source)
    return f"{type(exc).__name__}: {exc}" + (f" (at {source}:{line})" if line else "")


def _run_one(description, out, args) -> int:
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
        if progress.get("status") == "finished":
            if _processes()[1] == 0:   # the lock is one process's
                RunStore.resume(out, description.to_dict()).close()   # refuses another description
            print(f"{out}: the run is already finished (t = {progress['time']:g}, "
                  f"{progress['step']} steps, {progress.get('wall_seconds', 0.0):.1f} s)")
            return 0
    try:
        simulation = Simulation(description, partition=args.partition)
        # a space run keeps no projection record (None): nothing to note
        note = projection_note(simulation.projection) if simulation.projection else None
        if note:
            print(f"granframe: {note}", file=sys.stderr)
        hint = cooling_hint(description)
        if hint:
            print(f"granframe: hint: {hint}", file=sys.stderr)
        with _together(simulation.communicator):
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
        print("\ngranframe: interrupted; " + _interrupted(out), file=sys.stderr)
        return 130
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
    return 0


@contextlib.contextmanager
def _together(communicator):
    """Around the part of a run that its processes make together (the cost estimate's step
    and the run): an error in one process is printed with its number and ends them all
    (:meth:`~granframe.abc.Communicator.abort`, status 2 for granframe's refusals, 1 for
    anything else), since the others would wait for it for ever. A health stop and a
    Ctrl-C reach every process at the same step and pass through."""
    from granframe.run.runner import HealthError

    try:
        yield
    except (HealthError, KeyboardInterrupt):
        raise
    except BaseException as exc:
        if communicator.size == 1:
            raise
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


def _info_document(path) -> dict:
    """``granframe info STORE --json``: what ``info`` says of a run store, as JSON
    (docs/runner.md): the store's metadata and progress as stored, and the range of its
    snapshots and moments."""
    from granframe.run.storage import RunStore, StoreDamagedError, store_kind, summarise

    if store_kind(path) == "sweep":
        raise ValueError(f"info: parameter 'store' = '{path}' is invalid; --json describes "
                         f"run stores, and it is a sweep store (granframe info {path} "
                         "describes it)")
    store = RunStore.open(path)   # refuses what is not a run store
    problems = store.verify([n for n in store.array_names() if n != "f"])
    if problems:
        raise StoreDamagedError(f"store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
    group, progress = store.group, store.progress
    document = {"schema": "granframe.info/1", "store": str(store.path),
                "metadata": store.metadata, "progress": progress, "snapshots": None,
                "moments": None}
    if progress.get("snapshots"):
        times = group["time"][:int(progress["snapshots"])]
        document["snapshots"] = {"count": len(times), "shape": list(group["f"].shape[1:]),
                                 "first_time": float(times[0]), "last_time": float(times[-1])}
    if progress.get("records"):
        n = int(progress["records"])
        # a space run records totals over the interval (no kurtosis; T is per cell)
        names = (("mass", "kinetic_energy", "min_f") if "space" in store.metadata
                 else ("mass", "temperature", "kurtosis", "min_f"))
        document["moments"] = {
            "records": n, "first_time": float(group["step_time"][0]),
            "last_time": float(group["step_time"][n - 1]), "steps": int(group["step"][n - 1]),
            **{name: {"first": float(group[name][0]), "last": float(group[name][n - 1])}
               for name in names}}
    return document


def _info(args) -> int:
    if args.json:
        json.dump(_info_document(args.store), sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
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
        result = run_sweep(Sweep.from_toml(_read_text(path, "sweep", "sweep")), args.out,
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


def _limit_runs(args) -> tuple[dict, bool]:
    """The runs ``limits`` reports: each description as given (``--set`` applied) but with
    ``health.step_limit = false``, so that one whose step is above the transport's CFL
    limit is built and reported rather than refused; and whether ``granframe run`` would
    check the step limits (the ``health.step_limit`` the description asks for)."""
    import tomllib

    from granframe.run.description import RunDescription

    path = pathlib.Path(args.source)
    unchecked = ["health.step_limit=false"]
    if path.suffix == ".toml" and path.is_file() and not args.quick:
        try:
            table = tomllib.loads(_read_text(path, "limits", "source"))
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"limits: the TOML text of '{path}' is invalid: {exc}") from None
        health = table.get("health")
        checked = health.get("step_limit", True) if isinstance(health, dict) else True
        table["health"] = {**(health if isinstance(health, dict) else {}), "step_limit": False}
        runs = {"": RunDescription.from_dict(table)}
    else:
        runs = _load_study(args.source, args.quick).runs
        checked = all(d.health.step_limit for d in runs.values())
    for setting in args.set:
        key, _, value = setting.partition("=")
        if key.strip() == "health.step_limit":
            checked = value.strip() != "false"
    return ({name: _with_settings(d, args.set + unchecked) for name, d in runs.items()},
            checked)


def _limits(args) -> int:
    from granframe.run.problems import time_step_limit

    runs, checked = _limit_runs(args)
    refused = ("granframe run refuses it" if checked else
               "health.step_limit = false: granframe run does not check it")
    status, document = 0, {}
    for name, d in runs.items():
        limit = time_step_limit(d)
        adaptive = d.build("integrator").adaptive
        above = limit is not None and not adaptive and d.time_step > limit.limit
        transport = None if d.space is None else d.space.transport_limit(d.grid)
        above_cfl = transport is not None and d.time_step > transport * (1 + 1e-12)
        status = 3 if above or above_cfl else status
        document[name] = {
            "integrator": d.integrator.name, "time_step": d.time_step, "adaptive": adaptive,
            "limit": None if limit is None or adaptive else limit.limit,
            "interval": None if limit is None or adaptive else limit.interval,
            "dominant": None if limit is None else str(limit.dominant),
            "rates": {} if limit is None else {str(k): v for k, v in limit.rates.items()},
            "within": None if limit is None or adaptive else not above,
            **({} if transport is None else {"transport_limit": transport,
                                             "within_transport_limit": not above_cfl})}
        cost = None if args.no_cost else _limit_cost(d)
        document[name]["cost"] = None if cost is None or isinstance(cost, str) else (
            cost.to_dict())
        if args.json:
            continue
        head = (f"[{name}] " if name else "") + f"'{d.integrator.name}': "
        if transport is not None:
            print((f"[{name}] " if name else "") + f"transport ('{d.space.reconstruction.name}',"
                  f" SSP RK3 half steps): dt <= {transport:.4g}; time_step = "
                  f"{d.time_step:g} is " + (f"ABOVE it ({refused})" if above_cfl else
                                            f"within it ({d.time_step / transport:.3g} of it)"))
        _limit_table(head, d, limit, adaptive, above, refused)
        if cost is not None:
            print((f"[{name}] " if name else "") + (cost if isinstance(cost, str)
                                                    else cost.text()))
    if args.json:
        json.dump({"schema": "granframe.limits/1", "runs": document}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    return status


def _limit_cost(description):
    """The run's :class:`~granframe.run.problems.RunCost` (its problem built and one step
    timed), or why it could not be estimated."""
    from granframe.run.problems import make_problem, run_cost

    try:
        return run_cost(make_problem(description))
    except (ValueError, MemoryError, FloatingPointError) as exc:
        return f"estimated cost: not estimated ({type(exc).__name__}: {exc})"


def _limit_table(head, d, limit, adaptive, above, refused) -> None:
    """The lines of ``granframe limits`` on the collisions' explicit step limit of ``d``."""
    from granframe.registry import default_registries
    from granframe.stepping.stability import PART_NAMES

    if limit is None:
        print(head + "no explicit step limit (the scheme treats none of the equation's "
              "stiff parts explicitly)")
        return
    radii = ", ".join(f"{PART_NAMES.get(part, part)} = {rate:.4g}" for part, rate in
                      sorted(limit.rates.items(), key=lambda x: -x[1]))
    if limit.interval == 0.0:
        registry = default_registries()
        stable = sorted(n for n in registry.names("time_integrators") if getattr(
            registry.get("time_integrators", n).factory, "imaginary_interval", 0.0) > 0.0)
        print(head + f"unstable at any step: {PART_NAMES['drift']} has an imaginary "
              f"spectrum (radii: {radii}) and the scheme is not stable on the imaginary "
              f"axis; use one that is: {', '.join(stable)}")
        return
    if adaptive:
        print(head + f"adaptive: its error control keeps the steps stable (spectral "
              f"radii: {radii})")
        return
    print(head + f"dt <= {limit.limit:.4g}, set by {PART_NAMES.get(limit.dominant)} "
          f"(spectral radii: {radii}; stable for dt * (sum of radii) <= "
          f"{limit.interval:g})")
    if above:
        print(f"  time_step = {d.time_step:g}: ABOVE the limit ({refused})")
    else:
        print(f"  time_step = {d.time_step:g}: within it ({d.time_step / limit.limit:.3g} "
              "of the limit)")


def _advise(args) -> int:
    """``granframe advise``: a scene (no ``grid``) gets the advice of
    :func:`~granframe.tools.advise.advise`; a run description with a ``[space]`` table (it
    has a ``grid``) is priced as it is, all-kinetic and with a hierarchy of collision models
    (:func:`~granframe.tools.advise.price_hierarchy`)."""
    import tomllib

    from granframe.run.description import RunDescription
    from granframe.tools.advise import Scene, advise, price_hierarchy

    path = pathlib.Path(args.scene)
    if not path.is_file():
        raise ValueError(f"advise: parameter 'scene' = '{args.scene}' is invalid; no such file")
    try:
        data = tomllib.loads(_read_text(path, "advise", "scene"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"advise: the TOML text of '{path}' is invalid: {exc}") from None
    if "grid" in data:
        if args.out:
            raise ValueError(f"advise: parameter '--out' = '{args.out}' is invalid; it writes "
                             f"the description advised for a scene, and '{path}' is a run "
                             "description (it has a grid), priced as it is: add the "
                             "fragment the report shows to it instead")
        price = price_hierarchy(RunDescription.from_dict(data))
        if args.json:
            json.dump({"schema": "granframe.hierarchy_price/1", **price.to_dict()}, sys.stdout,
                      indent=2)
            sys.stdout.write("\n")
        else:
            print(price.report())
        return 0
    advice = advise(Scene.from_dict(data))
    if args.json:
        json.dump({"schema": "granframe.advice/1", "closed_form": advice.closed_form,
                   "errors": advice.errors, "predicted_seconds": advice.predicted_seconds,
                   "evaluation_seconds": advice.evaluation_seconds,
                   "evaluations": advice.evaluations, "reasons": list(advice.reasons),
                   "description": None if advice.description is None
                   else advice.description.to_dict(),
                   "space": None if advice.space is None else advice.space.to_dict()},
                  sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(advice.report())
    if args.out and advice.description is not None:
        pathlib.Path(args.out).write_text(advice.description.to_toml())
        if not args.json:
            print(f"description: {args.out} (granframe run {args.out} --out STORE)")
    return 0


class Parser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` that names the closest choice or option when
    one is mistyped (Python 3.11's argparse has no ``suggest_on_error``).

    Subcommands get parsers of the same class (``add_subparsers`` makes them so). Each
    parser refuses the arguments it does not know itself, instead of returning them from
    :meth:`parse_known_args`, so that the message comes with the subcommand's usage and
    names the closest of its options; an unknown option is reported before a missing
    required argument.
    """

    def parse_known_args(self, args=None, namespace=None):
        self._arguments = list(sys.argv[1:] if args is None else args)
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(self._unrecognized(extras))
        return namespace, extras

    def error(self, message):
        from granframe.registry import did_you_mean

        choice = re.fullmatch(r"argument .*?: invalid choice: '(.*?)' \(choose from (.*)\)",
                              message)
        if choice:
            choices = [c.strip().strip("'") for c in choice.group(2).split(",")]
            message += did_you_mean(choice.group(1), choices)
        elif message.startswith("the following arguments are required"):
            unknown = [token for token in getattr(self, "_arguments", ())
                       if self._is_unknown_option(token)]
            if unknown:
                message = self._unrecognized(unknown)
        super().error(message)

    def _is_unknown_option(self, token: str) -> bool:
        if not token.startswith("-") or token in ("-", "--") or re.fullmatch(
                r"-\d+$|-\d*\.\d+", token):
            return False
        option = token.split("=", 1)[0]
        known = self._option_string_actions
        return option not in known and not (option.startswith("--") and any(
            name.startswith(option) for name in known))

    def _unrecognized(self, tokens) -> str:
        """``unrecognized arguments: ...``, with the closest option to each unknown one."""
        from granframe.registry import closest

        options = [name for name in self._option_string_actions if name.startswith("--")]
        hints = []
        for token in tokens:
            match = closest(token.split("=", 1)[0], options) if token.startswith("-") else None
            if match is not None:
                hints.append(f"'{match}'" if len(tokens) == 1 else f"'{match}' for '{token}'")
        return f"unrecognized arguments: {' '.join(tokens)}" + (
            f"; did you mean {', '.join(hints)}?" if hints else "")


#: What each command's ``--help`` says above its options (argparse's description) and,
#: below them, its examples (the epilog).
COMMAND_HELP = {
    "plugins": ("""\
List the registered implementations of every family (collision kernels, restitution laws,
quadratures, collision operators, time integrators, initial conditions, array backends)
with their source. With NAME (FAMILY NAME when the name is registered in several families,
or FAMILY alone for one family's list), show one implementation: its family, description,
source, docstring summary and parameters with their types and defaults.""",
                """\
  granframe plugins
  granframe plugins toscani
  granframe plugins collision_operators fast_spectral --json"""),
    "bench": ("""\
Time the fast spectral operator against the FFT floor, the time of the transforms it cannot
avoid (docs/benchmarks.md). --batch evaluates stacks of B distributions at once and reports
time and floor per distribution.""",
              """\
  granframe bench --config 2:64 --config 3:32 --repeats 5
  granframe bench --config 3:32 --quadrature auto review
  granframe bench --json --backend numpy --batch 1 8 64
  granframe bench --space 3:32:64 2:64:256"""),
    "run": ("""\
Run a description (a .toml file, or a study module defining description(quick) or
runs(quick)) into a zarr store. A study with several runs writes STORE/<name>.zarr for each,
then its report to STORE/report from the runs that have ended (also after --only). --set
overrides a key of the description (repeatable; the value is read as TOML). Before the
first step it prints the run's estimated cost: one step timed on this machine, times the
number of steps. Exit status 3 when a health check stopped a run, 130 when interrupted.""",
            """\
  granframe run studies/heated_maxwell.py --out runs/h.zarr
  granframe run studies/heated_maxwell.py --out runs/h.zarr --resume
  granframe run desc.toml --out runs/d.zarr --set grid.n_modes=64 --set kernel.name=vhs
  granframe run studies/review_test1.py --out runs/test1 --only a,b"""),
    "plot": ("""\
Draw the figures of a run store (temperature, relative entropy, slices and contours of f,
moments) into a folder.""",
             """\
  granframe plot runs/h.zarr --out figures/h"""),
    "info": ("""\
Say what is in a store. A run store: status, snapshots, moments, the resolution of the last
commit and its warnings, the accuracy monitors (their values, largest values, first excess
and warnings), provenance and the description; with --json, its metadata and
progress as stored and the range of its snapshots and moments, as one JSON document. A
sweep store: its axes, how many points finished, failed or are pending, its failures, the
runs that end under-resolved, and its base description.""",
             """\
  granframe info runs/h.zarr
  granframe info runs/h.zarr --json
  granframe info runs/sweep.zarr"""),
    "check": ("""\
Read every committed chunk of a run (or sweep) store and verify its checksum; list the
missing or damaged ones (exit status 3 when there is any).""",
              """\
  granframe check runs/h.zarr"""),
    "sweep": ("""\
Run every point of a parameter sweep (a base description and its axes) on Dask into one
zarr store (docs/scaling.md). Running it again skips ended runs and resumes cut ones; a
sweep of the same base with more axis values extends the store and runs only the new
points. Points refused for their parameters are not run again unless --retry-failed;
--overwrite replaces a sweep (or run) store, never anything else. Exit status 3 when a run
failed.""",
              """\
  granframe sweep sweep.toml --out runs/sweep.zarr --workers 2
  granframe sweep sweep.toml --out runs/sweep.zarr --retry-failed
  granframe sweep sweep.toml --out runs/sweep.zarr --overwrite"""),
    "advise": ("""\
Propose the cheapest configuration (grid, quadratures, time step) predicted to meet a
scene's tolerance on its temperature or distribution (docs/advise.md). A scene with a
[space] table (cells, walls), or a space run description, also gets the price of a
hierarchy of collision models chosen cell by cell against the all-kinetic run.""",
               """\
  granframe advise scene.toml
  granframe advise scene.toml --out desc.toml && granframe run desc.toml --out runs/a.zarr
  granframe advise space-run.toml"""),
    "limits": ("""\
Report the explicit time-step limit of each run of a description (a .toml file or a study
module) and the spectral radii behind it (heat bath, collisions, energy dissipation, and the
drift of a rescaled run), from the description alone: the operator is not built, so it
takes a fraction of a second where building it takes seconds to minutes. It is the limit
granframe run checks before the first step (docs/runner.md, docs/stability.md). A space
run's transport (CFL) limit comes first. Then the run's cost on this machine: its operator
is built and one step timed, times the number of steps (--no-cost leaves it out, and the
command takes a fraction of a second). Exit status 3 when the description's fixed time step
is above a limit; the table is printed all the same.""",
               """\
  granframe limits studies/heated_maxwell.py
  granframe limits studies/space.py --quick --no-cost
  granframe limits desc.toml --set time_step=0.05 --set grid.n_modes=64
  granframe limits desc.toml --json"""),
}


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="granframe", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Fourier spectral solvers for the inelastic Boltzmann equation.",
        epilog="examples:\n  granframe plugins\n  granframe run studies/heated_maxwell.py "
               "--out runs/h.zarr\n  granframe COMMAND --help")
    parser.add_argument("--version", action="version", version=f"granframe {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    plugins = commands.add_parser("plugins", help="list registered implementations per family")
    plugins.add_argument("names", nargs="*", metavar="[FAMILY] NAME",
                         help="show this implementation (or this family)")
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
    bench.add_argument("--quadrature", action="extend", nargs="+", metavar="PRESET",
                       choices=["auto", "review"],
                       help="time each configuration D:N with the rules of these presets of "
                            "fast_spectral's quadrature option (e.g. --quadrature auto "
                            "review) instead of its N_RHO and M")
    bench.add_argument("--space", nargs="*", metavar="D:N:CELLS[:N_RHO:M]", default=None,
                       help="time one step of a space run and its parts instead (default "
                            "configurations: 3:32:64 and 2:64:256, the review's rules)")
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
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a key of the description (repeatable), e.g. "
                          "grid.n_modes=64; VALUE is read as TOML")
    run.add_argument("--partition", type=_partition, default=None, metavar="C1,C2,...",
                     help="under mpiexec: the cells of each process, in rank order, whole "
                          "chunks of space.block_cells (default: as even as the chunks "
                          "allow)")
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
    info = commands.add_parser("info", help="say what is in a run or sweep store")
    info.add_argument("store", metavar="STORE")
    info.add_argument("--json", action="store_true",
                      help="a run store's content as a JSON document")
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
                        help="physics, quantity (temperature or distribution) and tolerance, "
                             "with a [space] table for a space scene; or a space run "
                             "description, to price a hierarchy")
    advise.add_argument("--out", metavar="DESCRIPTION.toml",
                        help="write the proposed run description")
    advise.add_argument("--json", action="store_true", help="machine-readable output")
    advise.set_defaults(handler=_advise)
    limits = commands.add_parser("limits", help="the explicit time-step limit of a run "
                                 "and its estimated cost")
    limits.add_argument("source", metavar="STUDY_OR_TOML",
                        help="a .toml description or a study module (.py)")
    limits.add_argument("--quick", action="store_true",
                        help="the study's quick runs (study modules only)")
    limits.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a key of the description, as for run (repeatable)")
    limits.add_argument("--json", action="store_true", help="machine-readable output")
    limits.add_argument("--no-cost", action="store_true",
                        help="leave out the cost estimate (which builds the operator and "
                             "times one step)")
    limits.set_defaults(handler=_limits)
    for name, command in commands.choices.items():
        command.description, examples = COMMAND_HELP[name]
        command.epilog = f"examples:\n{examples}"
        command.formatter_class = argparse.RawDescriptionHelpFormatter
    return parser


def _partition(text: str) -> list[int]:
    """--partition: whole numbers separated by commas."""
    try:
        counts = [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a list of cell counts such as "
                                         "24,40") from None
    return counts


def _processes():
    """(size, rank) of the processes a launcher started (:func:`granframe.parallel.launched`,
    read from the environment: nothing is imported)."""
    from granframe.parallel import launched

    size, rank, _ = launched()
    return size, rank


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:      # the imports made here are inside the handling of a Ctrl-C too
        size, rank = _processes()
        if size > 1 and args.command != "run":
            if rank == 0:
                print(f"granframe: error: granframe {args.command} runs in one process; "
                      f"under mpiexec ({size} processes) only granframe run is spread over "
                      "them", file=sys.stderr)
            return 2
        if size > 1 and rank != 0:      # one voice: process 0's; the others speak on errors
            import os

            sys.stdout = open(os.devnull, "w")
            sys.stderr = open(os.devnull, "w")
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
    handled it. A Ctrl-C while the process exits after the command (the libraries'
    ``atexit`` callbacks: Dask, thread pools) ends it at once with the command's status,
    instead of an "Exception ignored in atexit callback" traceback.
    """
    import os
    import signal

    interruptible = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if interruptible:   # not ignored
        signal.signal(signal.SIGINT, _interrupt)
    code = main()

    def leave(signum=None, frame=None):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):   # a closed pipe or stream
                pass
        os._exit(code)

    if code == 130:
        leave()
    if interruptible:
        signal.signal(signal.SIGINT, leave)
    sys.exit(code)


if __name__ == "__main__":
    entry()
