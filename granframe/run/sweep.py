"""Parameter sweeps on Dask: a base description, axes of values, one zarr store.

A :class:`Sweep` is a base run description (a table, as in a TOML description) plus
*product* axes (every combination) and *zip* axes (varied together, one factor of the
product). Each point is a run; :func:`run_sweep` submits one Dask task per run, on a
``distributed.LocalCluster`` by default or on any cluster given by its scheduler address.

Layout of the sweep store ``STORE``::

    STORE/zarr.json            group; attrs["granframe_sweep"]: the sweep, run names, the
                               points refused for their parameters, created/updated times
    STORE/runs/<name>/         one run store (granframe.run.storage) per point
    STORE/table/               the sweep table: one row per run, in sweep order

The run stores are the record: each is written by the runner's commits (a store is
consistent after any interruption) and resumed by it. A run that is finished is skipped
when the sweep runs again; a run cut short (a worker killed, the sweep interrupted)
resumes from its last snapshot, on whichever worker takes it; a run stopped by a health
check stays failed with its message, and a point refused for its parameters is recorded
as refused in the root attributes (it has no run store) and not submitted again. Both are
run again when asked (``retry_failed``). The table is derived from the run stores by the
process that drives the sweep (one writer): one row per run, rewritten whole, so a row is
never written twice or half.

A sweep store is extended by running a sweep of the same base with more axis values: every
run the store holds must be a point of the new sweep, the runs already ended are kept, and
only the new points are run. A sweep of another base, or one that drops points, is
refused; ``overwrite`` replaces the store (only a granframe store, see
:func:`granframe.run.storage.check_replaceable`).

:func:`open_sweep` gives the table as a gridded ``xarray.Dataset`` (one dimension per
product axis and one for the zip axes, the parameters as coordinates), and
:func:`describe_sweep` says what a sweep store holds (``granframe info``). The flat table
also opens with ``xarray.open_zarr(STORE, group="table")`` (dimension ``run``) or
:func:`read_table`.
"""

from __future__ import annotations

import contextlib
import copy
import importlib.util
import itertools
import json
import math
import os
import pathlib
import re
import shutil
import sys
import time
import uuid
import warnings

import attrs
import numpy
import tqdm
import zarr

from granframe import validators as check
from granframe._version import __version__
from granframe.run.description import RunDescription
from granframe.run.storage import (LONG_NAMES, SWEEP_SCHEMA_KEY, TRASH, StoreDamagedError,
                                   WriterLock, check_replaceable, codecs, differences, now,
                                   recover, sibling, store_kind)

SCHEMA = "granframe.run.sweep/1"
#: the final moments of a run the table keeps
TABLE_MOMENTS = ("temperature", "kurtosis", "sonine_a2", "mass", "negative_mass_fraction")
#: the resolution indicators of a run's last commit the table keeps
#: (:func:`granframe.velocity.estimators.resolution_report`; ``fields_shell`` of a space
#: run, :func:`granframe.run.monitors.cell_resolution_report`, NaN for a homogeneous one),
#: and its warnings as one text
TABLE_RESOLUTION = ("tail_error", "pairs_beyond_support", "fields_shell")
#: the columns a table written before them lacks, and their values there; the warnings of
#: the run's last commit are what ``granframe run`` prints when the run ends
_NO_RESOLUTION = {**{name: math.nan for name in TABLE_RESOLUTION}, "resolution_warning": "",
                  "accuracy_warning": ""}
#: the table row of a run not run yet (or cut short); every column of the table
_PENDING = {"status": "pending", "message": "", "wall_seconds": math.nan, "steps": 0,
            "time": math.nan, **{name: math.nan for name in TABLE_MOMENTS}, **_NO_RESOLUTION}


def _axes(owner: str, name: str, value) -> dict:
    if value is None:
        return {}
    if not isinstance(value, dict) or not all(
            isinstance(k, str) and isinstance(v, (list, tuple)) and v for k, v in value.items()):
        check.reject(owner, name, value, "must be a table of dotted parameter -> non-empty list "
                     "of values", error=TypeError)
    return {k: list(v) for k, v in value.items()}


@attrs.frozen
class Sweep:
    """A base run description and the axes that vary it.

    Parameters
    ----------
    base : dict
        A run description as a table (``RunDescription.to_dict`` or a TOML table).
    product : dict
        Dotted parameter (``restitution.value``, ``grid.n_modes``, ``kernel``) -> values;
        every combination is run.
    zip : dict
        Dotted parameter -> values, all of the same length; varied together, as one factor
        of the product.
    """

    base: dict = attrs.field()
    product: dict = attrs.field(factory=dict, converter=lambda v: _axes("Sweep", "product", v))
    zip: dict = attrs.field(factory=dict, converter=lambda v: _axes("Sweep", "zip", v))

    @base.validator
    def _check_base(self, attribute, value):
        if not isinstance(value, dict):
            check.reject("Sweep", "base", value, "must be a run description table",
                         error=TypeError)

    def __attrs_post_init__(self):
        lengths = {len(v) for v in self.zip.values()}
        if len(lengths) > 1:
            check.reject("Sweep", "zip", {k: len(v) for k, v in self.zip.items()},
                         "must have lists of one length (they are varied together)")
        both = set(self.product) & set(self.zip)
        if both:
            check.reject("Sweep", "zip", sorted(both), "must not repeat a product parameter")
        if not self.product and not self.zip:
            check.reject("Sweep", "product", {}, "or zip must give at least one axis")

    @classmethod
    def from_dict(cls, data: dict) -> "Sweep":
        """``{"base": {...}, "product": {...}, "zip": {...}}`` (the TOML layout)."""
        if not isinstance(data, dict):
            check.reject("Sweep", "sweep", data, "must be a table", error=TypeError)
        return check.from_table(cls, data, "Sweep")

    @classmethod
    def from_toml(cls, text: str) -> "Sweep":
        import tomllib

        try:
            return cls.from_dict(tomllib.loads(text))
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"Sweep: the TOML text is invalid: {exc}") from None

    def to_dict(self) -> dict:
        return {"base": self.base, "product": self.product, "zip": self.zip}

    def points(self) -> list[dict]:
        """Every point: dotted parameter -> value, in a fixed order (product, then zip)."""
        keys = list(self.product)
        zipped = list(zip(*self.zip.values())) if self.zip else [()]
        points = []
        for combination in itertools.product(*self.product.values()):
            for row in zipped:
                points.append({**dict(zip(keys, combination)), **dict(zip(self.zip, row))})
        return points


def run_name(point: dict) -> str:
    """A zarr-safe group name from a point's parameters, e.g. ``restitution.value-0.5``."""
    parts = []
    for key, value in point.items():
        text = value if isinstance(value, str) else json.dumps(value)
        parts.append(f"{key}-{text}")
    return re.sub(r"[^A-Za-z0-9._-]+", "_", "__".join(parts))


def apply(base: dict, point: dict) -> dict:
    """The base table with the point's dotted parameters set."""
    table = copy.deepcopy(base)
    for key, value in point.items():
        node, *path = key.split(".")
        target, parts = table, [node] + path
        for part in parts[:-1]:
            child = target.get(part)
            if isinstance(child, str):          # a component given by name only
                child = {"name": child}
            target[part] = child if isinstance(child, dict) else {}
            target = target[part]
        target[parts[-1]] = value
    return table


def _summary(path) -> dict:
    """The table row of a run store: status, message, wall time, steps, final moments."""
    from granframe.run.storage import RunStore

    store = RunStore.open(path)
    progress = store.progress
    row = {"status": progress.get("status", "created"), "message": progress.get("message", ""),
           "wall_seconds": float(progress.get("wall_seconds", 0.0)),
           "steps": int(progress.get("step", 0)), "time": float(progress.get("time", 0.0))}
    n = int(progress.get("records", 0))
    group = store.group
    space = group["temperature"].ndim == 2           # (time, x): the fields of each cell
    for name in TABLE_MOMENTS:
        if not n or (space and name not in ("temperature", "mass",
                                            "negative_mass_fraction")):
            row[name] = math.nan
        elif space and name == "temperature":      # the gas's: sum rho T / sum rho
            density = numpy.asarray(group["density"][n - 1])
            row[name] = float((density * group["temperature"][n - 1]).sum() / density.sum())
        else:
            row[name] = float(group[name][n - 1])
    resolution = progress.get("resolution") or {}
    row.update({name: float(resolution.get(name, math.nan)) for name in TABLE_RESOLUTION})
    row["resolution_warning"] = "; ".join(resolution.get("warnings", ()))
    row["accuracy_warning"] = "; ".join((progress.get("accuracy") or {}).get("warnings", ()))
    return row


def _status(path) -> str | None:
    """The status of the run store at ``path``; None when there is none (a store is put
    in place whole, see granframe.run.storage), ``damaged`` when it cannot be read."""
    from granframe.run.storage import RunStore, StoreError

    if not RunStore.exists(path):
        return None
    try:
        return RunStore.open(path).progress.get("status", "created")
    except StoreError:
        return "damaged"


#: the message of a point refused for its parameters begins with this
REFUSED = "refused: "


def _failed(message: str) -> dict:
    return {**_PENDING, "status": "failed", "message": message, "wall_seconds": 0.0,
            "time": 0.0}


def mpiexec() -> str | None:
    """The ``mpiexec`` installed beside this Python (the mpich wheel's of the ``mpi`` extra),
    else the one on PATH; None when there is none."""
    beside = pathlib.Path(sys.executable).with_name("mpiexec")
    return str(beside) if beside.is_file() else shutil.which("mpiexec")


def _run_processes(description: dict, path: str, processes: int, mode: str) -> dict | None:
    """Run one point as ``mpiexec -n processes granframe run`` (its description in a
    temporary TOML file); None when it ran (the store says how), else a failed row with
    the launcher's last words."""
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory(prefix="granframe-sweep-") as folder:
        toml = pathlib.Path(folder) / "point.toml"
        toml.write_text(RunDescription.from_dict(description).to_toml())
        done = subprocess.run([mpiexec(), "-n", str(processes), sys.executable, "-m",
                               "granframe.tools.cli", "run", str(toml), "--out", path, mode],
                              capture_output=True, text=True, check=False)
    if done.returncode in (0, 3):           # finished, or stopped by a health check
        return None
    last = (done.stderr.strip().splitlines() or ["(nothing on stderr)"])[-1]
    prefix = REFUSED if done.returncode == 2 else ""
    return _failed(f"{prefix}mpiexec -n {processes} granframe run exited with status "
                   f"{done.returncode}: {last}")


def run_point(description: dict, path: str, poll: float = 1.0,
              retry_failed: bool = False, processes: int = 1) -> dict:
    """Run (or resume, or skip) one point into ``path``; the task a worker executes.

    Returns its table row. Parameters the description refuses (message ``refused: ...``),
    health stops and a damaged store are returned as ``failed`` with the message; nothing
    is raised. A run stopped by a health check is returned as it is, or with
    ``retry_failed`` run again from the start (its store replaced atomically). When
    another process holds the store's writer lock (Dask gave the task again to a new
    worker while the first, presumed dead, still runs it), this one waits for it, polling
    every ``poll`` seconds, and then takes the store as that process left it: finished, or
    cut short and resumed from there. Two processes never write one store at once.

    Parameters
    ----------
    description : dict
        The point's run description as a table (:func:`apply` of the base and the point).
    path : str
        Its run store, ``STORE/runs/<name>``.
    poll : float
        Seconds between looks at a writer lock held by another process.
    retry_failed : bool
        Run a run stopped by a health check again, from the start.
    processes : int
        MPI processes of the run: above 1 it runs as ``mpiexec -n processes granframe run``
        (:func:`mpiexec`), the task waiting for it.

    Returns
    -------
    dict
        The table row: status, message, wall_seconds, steps, time, final moments.
    """
    from granframe.run.runner import HealthError, Simulation
    from granframe.run.storage import StoreError, StoreLockedError

    status = _status(path)
    if status == "finished" or (status == "failed" and not retry_failed):
        return _row(path)
    if status == "damaged":
        return _failed(f"store: the run store '{path}' cannot be read (granframe check "
                       "lists the damage)")
    try:
        simulation = Simulation(RunDescription.from_dict(description))
    except (ValueError, TypeError) as exc:
        return _failed(f"{REFUSED}{exc}")
    if processes > 1:
        failed = _run_processes(description, path, processes,
                                "--overwrite" if status == "failed" else "--resume")
        return failed if failed is not None else _row(path)
    mode = {"overwrite": True} if status == "failed" else {"resume": True}
    while True:
        try:
            simulation.run(path, progress=False, **mode)
            break
        except StoreLockedError:
            time.sleep(poll)
            mode = {"resume": True}            # take the store as its holder leaves it
        except HealthError:
            break                              # the store says failed, with the message
        except StoreError as exc:
            return _failed(f"store: {exc}")
    return _row(path)


def _row(path) -> dict:
    """The table row of a run store, or a failed row saying why it cannot be read."""
    try:
        return _summary(path)
    except ValueError as exc:       # a store error, or a chunk failing its checksum
        return _failed(f"store: {exc}")


def _text(value) -> str:
    """A parameter value as text: a string itself, anything else as JSON."""
    return value if isinstance(value, str) else json.dumps(value, sort_keys=True)


def _write_table(root: zarr.Group, names, points, rows) -> None:
    """The sweep table, rewritten whole from ``rows`` (name -> row; missing: pending)."""
    columns = {"name": numpy.array(names, dtype=str)}
    for key in points[0] if points else ():
        values = [p[key] for p in points]
        numeric = all(isinstance(v, (int, float)) for v in values)      # bool is an int
        columns[key] = numpy.array([float(v) for v in values] if numeric
                                   else [_text(v) for v in values])
    for field, default in _PENDING.items():
        values = [rows.get(n, _PENDING)[field] for n in names]
        columns[field] = numpy.array(values, dtype=str if isinstance(default, str) else float)
    group = root.require_group("table")
    for key, values in columns.items():
        text = values.dtype.kind == "U"
        array = group.create_array(key, shape=values.shape, dtype=str if text else "f8",
                                   dimension_names=["run"], overwrite=True,
                                   fill_value="" if text else math.nan, **codecs())
        array[:] = values.astype(object) if text else values
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", category=UserWarning)
        zarr.consolidate_metadata(root.store)


def read_table(store) -> dict:
    """The sweep table as columns (name -> NumPy array); ``pandas.DataFrame(read_table(s))``
    gives a data frame."""
    group = zarr.open_group(str(store), mode="r")["table"]
    return {key: numpy.asarray(group[key][:]) for key in group.array_keys()}


@attrs.frozen
class SweepResult:
    """What a sweep did: its store, and how many runs finished, failed or were skipped.

    ``finished`` and ``failed`` count every point of the sweep that has ended; among them,
    ``skipped`` runs whose stores had ended before and ``refused`` points refused for their
    parameters before, which were not submitted again.
    """

    store: str
    finished: int
    failed: int
    skipped: int
    refused: int
    wall_seconds: float


def run_sweep(sweep: Sweep, out, *, client=None, scheduler: str | None = None,
              workers: int | None = None, progress: bool | None = None,
              overwrite: bool = False, retry_failed: bool = False,
              protect=(), processes: int = 1) -> SweepResult:
    """Run every point of ``sweep`` into the store ``out`` on Dask (see the module notes).

    Parameters
    ----------
    sweep : Sweep
        The base description and its axes.
    out : str or pathlib.Path
        A new path, an empty directory, or a sweep store of the same base (continued, or
        extended by new axis values: its ended runs are kept).
    client : distributed.Client, optional
        Where the runs are submitted; else ``scheduler``, else a ``LocalCluster`` of
        ``workers`` single-threaded worker processes (default: one per core). A client or
        cluster made here is closed after the sweep.
    scheduler : str, optional
        The address of an existing Dask scheduler.
    workers : int, optional
        Worker processes of the LocalCluster.
    progress : bool, optional
        A progress bar; None shows it on a terminal only.
    overwrite : bool
        Replace the granframe store at ``out`` (a run or sweep store, never anything else,
        nor a store holding a path of ``protect``;
        :func:`granframe.run.storage.check_replaceable`).
    retry_failed : bool
        Run again the points refused for their parameters and the runs stopped by a
        health check (from the start); without it, both stay failed.
    protect : sequence of paths
        Paths ``out`` must not hold when it is replaced (the sweep's own file).
    processes : int
        MPI processes per run (``mpiexec -n processes granframe run`` on the worker that
        takes it; a space run spreads its cells over them, docs/scaling.md); 1 runs each
        in its worker's process.

    Returns
    -------
    SweepResult
        Runs finished and failed, among them those that had ended before (skipped) and
        the points refused before and not submitted again (refused).
    """
    _check_run_arguments(sweep, workers)
    if importlib.util.find_spec("distributed") is None:
        raise ValueError("run_sweep: Dask (distributed) is not installed here, and the runs of "
                         "a sweep (granframe sweep, granframe refine) are Dask tasks: "
                         "pip install 'granframe[sweep]'")
    if isinstance(processes, bool) or not isinstance(processes, int) or processes < 1:
        check.reject("run_sweep", "processes", processes, "must be a whole number >= 1 (MPI "
                     "processes per run)")
    if processes > 1 and mpiexec() is None:
        check.reject("run_sweep", "processes", processes, "needs mpiexec, which is not "
                     "installed here: pip install 'granframe[mpi]' (an MPI from the package "
                     "index), or run with processes = 1")
    start = time.perf_counter()
    out = pathlib.Path(out)
    _check_out(out, overwrite, protect)
    points = sweep.points()
    names = [run_name(p) for p in points]
    if len(set(names)) != len(names):
        check.reject("run_sweep", "sweep", sweep.to_dict(), "gives two points the same name")
    with WriterLock(out):
        recover(out)               # an overwrite cut short: the old store back, or deleted
        if overwrite:
            _clear(out, protect)
        return _drive(sweep, out, points, names, client, scheduler, workers, progress,
                      retry_failed, start, processes)


def _check_run_arguments(sweep, workers) -> None:
    """Refuse a ``sweep`` that is not a :class:`Sweep` and ``workers`` that are not None or
    a whole number >= 1."""
    if not isinstance(sweep, Sweep):
        check.reject("run_sweep", "sweep", sweep, "must be a Sweep", error=TypeError)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        check.reject("run_sweep", "workers", workers, "must be a whole number >= 1 (worker "
                     "processes of the LocalCluster), or None for one per core")


def _check_out(out: pathlib.Path, overwrite: bool, protect) -> None:
    """Refuse an ``out`` that a sweep may not write: with ``overwrite``, what
    :func:`check_replaceable` refuses; without it, anything but a new path, an empty
    directory or a sweep store (or a directory of run stores only, written before the
    sweep's own metadata)."""
    kind = store_kind(out)
    if kind == "other" and {p.name for p in out.iterdir()} == {"runs"}:
        kind = "sweep"             # run stores written before the sweep's own metadata
    if overwrite:
        check_replaceable(out, protect)          # refused before anything is touched
    elif kind not in ("missing", "empty", "sweep"):
        what = {"run": "a granframe run store (--overwrite replaces it)",
                "file": "a file"}.get(kind, "not a sweep store")
        check.reject("run_sweep", "out", str(out), f"must be a new path, an empty directory or "
                     f"a sweep store; it is {what}")


def _clear(out: pathlib.Path, protect) -> None:
    """Replace the granframe store at ``out`` by an empty directory (its lock held).

    The store is renamed aside, the empty directory made, then the old store deleted: a
    kill before the directory exists leaves the old store for :func:`recover` to put back,
    a kill after it leaves the old store for :func:`recover` to delete.
    """
    check_replaceable(out, protect)              # again, now that no sweep can start
    if store_kind(out) in ("missing", "empty"):
        return
    trash = sibling(out, TRASH, uuid.uuid4().hex[:12])
    os.rename(out, trash)
    out.mkdir()
    shutil.rmtree(trash)


def _check_extension(previous: dict, sweep: Sweep, names, out) -> None:
    """Refuse a sweep that is not the stored one or an extension of it (same base, every
    stored run one of its points)."""
    stored = previous["sweep"]
    changed = list(differences(stored.get("base"), json.loads(json.dumps(sweep.base))))
    advice = "choose a new store, or --overwrite to replace it"
    if changed:
        check.reject("run_sweep", "out", str(out), f"holds another sweep: its base differs at "
                     f"{', '.join(changed[:5])}; a sweep store is extended only by a sweep of "
                     f"the same base ({advice})")
    runs, wanted = previous.get("runs", []), set(names)
    dropped = [name for name in runs if name not in wanted]
    if dropped:
        check.reject("run_sweep", "out", str(out), f"holds another sweep: {len(dropped)} of its "
                     f"{len(runs)} runs are not points of this one ({', '.join(dropped[:3])}"
                     f"{', ...' if len(dropped) > 3 else ''}); a sweep store is extended only "
                     f"by adding axis values ({advice})")


def _sorted_points(sweep, names, points, paths, refused, retry_failed):
    """(rows, todo, kept): the table rows of the runs that ended (finished, or failed and
    not retried), of which ``kept`` the points refused before and not retried, and the
    (name, description) of the runs to submit."""
    rows, todo, kept = {}, [], 0
    for name, point in zip(names, points):
        status = _status(paths[name])
        if status == "finished" or (status == "failed" and not retry_failed):
            rows[name] = _row(paths[name])
        elif status is None and name in refused and not retry_failed:
            rows[name] = _failed(refused[name])
            kept += 1
        else:
            todo.append((name, apply(sweep.base, point)))
    return rows, todo, kept


def _drive(sweep, out, points, names, client, scheduler, workers, progress, retry_failed,
           start, processes=1):
    """run_sweep with the sweep store's writer lock held (one driver, one table writer)."""
    import distributed

    root = zarr.open_group(str(out), mode="a", zarr_format=3)
    previous = root.attrs.get(SWEEP_SCHEMA_KEY) or {}
    if "sweep" in previous:
        _check_extension(previous, sweep, names, out)
    paths = {n: str(out / "runs" / n) for n in names}
    refused = {n: m for n, m in previous.get("refused", {}).items() if n in paths}
    meta = {"schema": SCHEMA, "version": __version__, "sweep": sweep.to_dict(),
            "runs": names, "refused": refused, "created": previous.get("created", now())}
    root.attrs[SWEEP_SCHEMA_KEY] = {**meta, "updated": now()}
    rows, todo, kept = _sorted_points(sweep, names, points, paths, refused, retry_failed)
    skipped = len(rows) - kept
    _write_table(root, names, points, rows)
    with contextlib.ExitStack() as made:           # a client or cluster made here is closed
        if client is None and scheduler is not None:
            client = made.enter_context(distributed.Client(scheduler))
        elif client is None:
            cluster = made.enter_context(distributed.LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True,
                dashboard_address=":0"))
            client = made.enter_context(distributed.Client(cluster))
        kept_refused = (f", {kept} refused before (--retry-failed submits them again)"
                        if kept else "")
        print(f"sweep: {len(names)} runs, {skipped} already ended{kept_refused}, {len(todo)} "
              f"to run; Dask dashboard: {client.dashboard_link}")
        futures = {client.submit(run_point, description, paths[name], retry_failed=retry_failed,
                                 processes=processes, key=f"granframe-{name}",
                                 pure=False): name
                   for name, description in todo}
        counts = {"finished": 0, "failed": 0}
        with tqdm.tqdm(total=len(todo), disable=None if progress is None else not progress,
                       unit="run", dynamic_ncols=True) as bar:
            for future in distributed.as_completed(futures):
                name = futures[future]
                rows[name] = row = future.result()
                if row["status"] == "failed" and row["message"].startswith(REFUSED):
                    refused[name] = row["message"]
                else:
                    refused.pop(name, None)
                counts["finished" if row["status"] == "finished" else "failed"] += 1
                running = sum(len(keys) for keys in client.processing().values())
                bar.update(1)
                bar.set_postfix_str(f"done {counts['finished']}, failed {counts['failed']}, "
                                    f"running {running}", refresh=False)
                root.attrs[SWEEP_SCHEMA_KEY] = {**meta, "refused": refused, "updated": now()}
                _write_table(root, names, points, rows)
    finished = sum(1 for r in rows.values() if r["status"] == "finished")
    return SweepResult(str(out), finished, len(rows) - finished, skipped, kept,
                       time.perf_counter() - start)


# -- reading a sweep store ------------------------------------------------------------------
#: the table's columns besides the parameters and the run name, and their attributes
_RESULTS = {
    "status": {"long_name": "status of the run: finished, failed (see message) or pending "
                            "(not run yet, or cut short: running the sweep again resumes it)"},
    "message": {"long_name": "why the run failed; empty when it did not"},
    "wall_seconds": {"long_name": "wall-clock time of the run", "units": "s"},
    "steps": {"long_name": "time steps taken", "units": "1"},
    "time": {"long_name": "time reached by the run", "units": "1"},
    **{name: {"long_name": f"{LONG_NAMES[name]} at the end of the run (NaN unless "
                           "finished; of a space run the gas's, sum rho T / sum rho over "
                           "the cells for the temperature, NaN for kurtosis and a_2)",
              "units": "1"} for name in TABLE_MOMENTS},
    "tail_error": {"long_name": "error predicted by the spectral tail of f at the last "
                                "commit (3 max |hat f_k| / |hat f_0| on the outermost shell)",
                   "units": "1"},
    "pairs_beyond_support": {"long_name": "share of pairs of f at the last commit with "
                                          "relative speed beyond 2S (cut off by the "
                                          "operators)", "units": "1"},
    "fields_shell": {"long_name": "largest change of a cell's fields without the outermost "
                                  "shell of modes at the last commit (space runs; NaN "
                                  "for a homogeneous one)", "units": "1"},
    "resolution_warning": {"long_name": "what the run's resolution warnings say to raise "
                                        "(grid.n_modes, grid.support_radius); empty when f "
                                        "was resolved"},
    "accuracy_warning": {"long_name": "the run's accuracy warnings at its end (momentum drift, "
                                      "distance from the exact temperature law, mass and "
                                      "energy near the box edge); empty when it stayed "
                                      "accurate"},
}
def _sweep_metadata(path, owner: str) -> dict:
    """The ``granframe_sweep`` attributes of the sweep store at ``path``, or a clear error."""
    if not isinstance(path, (str, os.PathLike)):
        check.reject(owner, "path", path, "must be the path (str or os.PathLike) of a sweep "
                     "store", error=TypeError)
    path = pathlib.Path(path)
    kind = store_kind(path)
    if kind != "sweep":
        what = {"missing": "missing", "file": "a file", "empty": "an empty directory",
                "run": "a run store (granframe.open_run reads it)"}.get(
                    kind, "not a granframe store")
        check.reject(owner, "path", str(path), f"must be a sweep store (granframe sweep "
                     f"SWEEP.toml --out STORE); it is {what}")
    meta = zarr.open_group(str(path), mode="r", use_consolidated=False).attrs[SWEEP_SCHEMA_KEY]
    if "sweep" not in meta:
        check.reject(owner, "path", str(path), "must be a sweep store that records its sweep; "
                     "this one names its runs only (run its sweep over it again to record it)")
    return meta


def _stored_rows(path: pathlib.Path) -> dict:
    """Run name -> its row of the stored table; empty when there is no table yet."""
    root = zarr.open_group(str(path), mode="r", use_consolidated=False)
    if "table" not in root:
        return {}
    group, columns = root["table"], {}
    for key in ("name", *_RESULTS):
        if key in _NO_RESOLUTION and key not in group:   # a table written before them
            columns[key] = numpy.full(group["name"].shape, _NO_RESOLUTION[key])
            continue
        try:
            columns[key] = group[key][:]
        except ValueError as exc:           # a chunk failing its checksum
            raise StoreDamagedError(f"sweep store '{path}' is damaged: table/{key}: {exc} "
                                    "(granframe check lists every problem)") from None
    return {str(name): {key: columns[key][i] for key in _RESULTS}
            for i, name in enumerate(columns["name"])}


def _grid(sweep: Sweep) -> list[tuple[str, str, dict]]:
    """The dimensions of the gridded sweep: (name, axis kind, dotted parameter -> values);
    one per product axis, then one for the zip axes, named after the first of them."""
    dims = [(_variable(key), "product", {key: values}) for key, values in sweep.product.items()]
    if sweep.zip:
        dims.append((_variable(next(iter(sweep.zip))), "zip", sweep.zip))
    return dims


def _variable(key: str) -> str:
    """The variable name of a dotted parameter: ``grid.n_modes`` -> ``grid_n_modes``."""
    return re.sub(r"\W", "_", key)


def _coordinate(values: list) -> numpy.ndarray:
    """Axis values in their own type: int64, float64, bool, or text (JSON for tables)."""
    if all(isinstance(v, bool) for v in values):
        return numpy.array(values, dtype=bool)
    if all(check.is_integer(v) for v in values):
        return numpy.array(values, dtype=numpy.int64)
    if all(check.is_real(v) for v in values):
        return numpy.array(values, dtype=numpy.float64)
    return numpy.array([_text(v) for v in values], dtype=str)


def open_sweep(path) -> "xarray.Dataset":
    """The results of a sweep store as an ``xarray.Dataset`` on the sweep's grid.

    Each product axis is a dimension, its values the coordinate; the zip axes share one
    dimension, named after the first zipped parameter (whose values index it), with each
    zipped parameter a coordinate along it. Variable names replace the dots of parameters
    (``grid.n_modes`` -> ``grid_n_modes``; the dotted name is the ``parameter``
    attribute). Integer axes are int64, real ones float64, names and tables text.
    Variables on the grid: ``status``, ``message``, ``run`` (the run store under
    ``runs/``), ``wall_seconds``, ``steps``, ``time`` and the final moments
    (:data:`TABLE_MOMENTS`), NaN unless the run finished, and the resolution of the last
    commit (:data:`TABLE_RESOLUTION` and ``resolution_warning``, the warnings' text) and
    its accuracy warnings (``accuracy_warning``), as ``granframe run`` prints them at the
    end of a run. Every quantity is
    dimensionless (units "1") but the wall time (s). The root attributes (``title``,
    ``source``, ``history``, ``Conventions``, ``granframe_schema``, and the sweep as TOML
    text in ``sweep_toml``) are flat, so ``to_netcdf`` writes the dataset as it is.

    Parameters
    ----------
    path : str or pathlib.Path
        A sweep store (``granframe sweep ... --out STORE``).

    Returns
    -------
    xarray.Dataset
        Also for a sweep under way: its points not yet run are ``pending``.
    """
    import xarray

    meta = _sweep_metadata(path, "open_sweep")
    path = pathlib.Path(path)
    sweep = Sweep.from_dict(meta["sweep"])
    names = [run_name(p) for p in sweep.points()]
    dims = _grid(sweep)
    stored = _stored_rows(path)
    variables = _grid_variables(dims, names, [stored.get(name, _PENDING) for name in names])
    coordinates = _grid_coordinates(dims)
    taken = [_variable(key) for key in (*sweep.product, *sweep.zip)]
    if len(set(taken)) < len(taken) or set(taken) & set(variables):
        check.reject("open_sweep", "path", str(path), f"holds a sweep whose parameters "
                     f"{sorted([*sweep.product, *sweep.zip])} do not give distinct variable "
                     f"names (dots become underscores; {sorted(variables)} are taken)")
    return xarray.Dataset(variables, coordinates, _dataset_attributes(meta, sweep))


def _grid_variables(dims, names, rows) -> dict:
    """The variables of :func:`open_sweep`: the run names and the table's columns
    (:data:`_RESULTS`) on the sweep's grid, the final moments NaN unless finished."""
    shape = tuple(len(next(iter(axes.values()))) for _, _, axes in dims)
    dimensions = tuple(name for name, _, _ in dims)
    finished = numpy.array([row["status"] == "finished" for row in rows])
    variables = {"run": (dimensions, numpy.array(names, dtype=str).reshape(shape),
                         {"long_name": "name of the run store (STORE/runs/<run>)"})}
    for key, attributes in _RESULTS.items():
        values = numpy.array([row[key] for row in rows])
        if key in ("status", "message", "resolution_warning", "accuracy_warning"):
            values = values.astype(str)
        elif key == "steps":
            values = values.astype(numpy.int64)
        elif key in TABLE_MOMENTS:
            values = numpy.where(finished, values.astype(numpy.float64), math.nan)
        variables[key] = (dimensions, values.reshape(shape), dict(attributes))
    return variables


def _grid_coordinates(dims) -> dict:
    """The coordinates of :func:`open_sweep`: every swept parameter along its dimension,
    in its own type (:func:`_coordinate`)."""
    coordinates = {}
    for dimension, kind, axes in dims:
        for key, values in axes.items():
            values = _coordinate(values)
            attributes = {"long_name": f"sweep parameter {key} ({kind} axis)",
                          "parameter": key, **({"units": "1"} if values.dtype.kind in "if"
                                               else {})}
            coordinates[_variable(key)] = ((dimension,), values, attributes)
    return coordinates


def _dataset_attributes(meta: dict, sweep: Sweep) -> dict:
    """The flat root attributes of :func:`open_sweep`: title, source, history, conventions,
    the store schema, and the sweep as TOML text."""
    import tomli_w

    version = meta.get("version", "(version not recorded)")
    schema = meta.get("schema", SCHEMA)
    history = [f"{meta[key]} {what} by granframe sweep (granframe {version}, store schema "
               f"{schema})" for key, what in (("created", "created"), ("updated", "last written"))
               if key in meta]
    return {"title": sweep.base.get("title") or "granframe sweep",
            "source": f"granframe {version}", "history": "\n".join(history),
            "Conventions": "CF-1.10", "granframe_schema": schema,
            "sweep_toml": tomli_w.dumps(sweep.to_dict())}


def _axes_lines(dims) -> list[str]:
    """The lines of :func:`describe_sweep` that name the axes of the grid ``dims``
    (:func:`_grid`), at most 8 values of each."""
    lines = []
    for i, (dimension, kind, axes) in enumerate(dims):
        values = next(iter(axes.values()))
        shown = "; ".join(f"{key} = " + ", ".join(_text(v) for v in vals[:8])
                          + (", ..." if len(vals) > 8 else "") for key, vals in axes.items())
        lines.append(f"{'axes' if i == 0 else '':<12s}{dimension} ({kind}, {len(values)} "
                     f"values): {shown}")
    return lines


def describe_sweep(path) -> str:
    """What a sweep store holds, in words (``granframe info``): its axes, its points and
    how many finished, failed or are pending, its failures, where its table is, its base.

    Parameters
    ----------
    path : str or pathlib.Path
        A sweep store.

    Returns
    -------
    str
        The report, one item a line.
    """
    import tomli_w

    meta = _sweep_metadata(path, "describe_sweep")
    path = pathlib.Path(path)
    sweep = Sweep.from_dict(meta["sweep"])
    names = [run_name(p) for p in sweep.points()]
    stored = _stored_rows(path)
    rows = {name: stored.get(name, _PENDING) for name in names}
    lines = [f"sweep store {os.fspath(path)}",
             f"granframe   {meta.get('version', '(version not recorded)')} (schema "
             f"{meta.get('schema', SCHEMA)})"
             + (f", created {meta['created']}" if "created" in meta else "")
             + (f", updated {meta['updated']}" if "updated" in meta else "")]
    dims = _grid(sweep)
    lines.extend(_axes_lines(dims))
    counts = {}
    for row in rows.values():
        counts[row["status"]] = counts.get(row["status"], 0) + 1
    refused = sum(1 for n in names if n in meta.get("refused", {}))
    lines.append(f"points      {len(names)}: " + ", ".join(
        f"{counts[s]} {s}" + (f" ({refused} refused for their parameters)"
                              if s == "failed" and refused else "")
        for s in ("finished", "failed", "pending") if s in counts))
    failed = [(n, r["message"]) for n, r in rows.items() if r["status"] == "failed"]
    for name, message in failed[:5]:
        lines.append(f"  failed    {name}: {message}")
    if len(failed) > 5:
        lines.append(f"  ... and {len(failed) - 5} more failed (open_sweep gives every "
                     "message)")
    for kind, what in (("resolution", "under-resolved"), ("accuracy", "inaccurate")):
        warned = [n for n, r in rows.items()
                  if r["status"] == "finished" and r[f"{kind}_warning"]]
        if warned:
            lines.append(f"{kind:<12s}{len(warned)} of the finished runs end {what} "
                         f"({kind}_warning in open_sweep), e.g.")
            lines.append(f"  {warned[0]}: {rows[warned[0]][f'{kind}_warning']}")
    grid = " x ".join(f"{d} {len(next(iter(a.values())))}" for d, _, a in dims)
    lines.append(f"table       {grid}: granframe.open_sweep('{os.fspath(path)}'); the flat "
                 f"table: xarray.open_zarr('{os.fspath(path)}', group='table')")
    lines.append("base (TOML)")
    lines.extend("  " + line for line in tomli_w.dumps(sweep.base).strip().splitlines())
    return "\n".join(lines)
