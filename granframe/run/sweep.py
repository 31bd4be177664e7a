"""Parameter sweeps on Dask: a base description, axes of values, one zarr store.

A :class:`Sweep` is a base run description (a table, as in a TOML description) plus
*product* axes (every combination) and *zip* axes (varied together, one factor of the
product). Each point is a run; :func:`run_sweep` submits one Dask task per run, on a
``distributed.LocalCluster`` by default or on any cluster given by its scheduler address.

Layout of the sweep store ``STORE``::

    STORE/zarr.json            group; attrs["granframe_sweep"]: the sweep, run names
    STORE/runs/<name>/         one run store (granframe.run.storage) per point
    STORE/table/               the sweep table: one row per run, in sweep order

The run stores are the record: each is written by the runner's commits (a store is
consistent after any interruption) and resumed by it. A run that is finished is skipped
when the sweep runs again; a run cut short (a worker killed, the sweep interrupted)
resumes from its last snapshot, on whichever worker takes it; a run stopped by a health
check, or refused for its parameters, stays failed with its message. The table is
derived from the run stores by the process that drives the sweep (one writer): one row
per run, rewritten whole, so a row is never written twice or half. It opens with
``xarray.open_zarr(STORE, group="table")`` (dimension ``run``) or :func:`read_table`.
"""

from __future__ import annotations

import copy
import itertools
import json
import math
import pathlib
import re
import time
import warnings

import attrs
import numpy
import tqdm
import zarr

from granframe import validators as check
from granframe.run.description import RunDescription
from granframe.run.storage import WriterLock, codecs, store_kind

SCHEMA = "granframe.run.sweep/1"
#: the final moments of a run the table keeps
TABLE_MOMENTS = ("temperature", "kurtosis", "sonine_a2", "mass", "negative_mass_fraction")


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
    for name in TABLE_MOMENTS:
        row[name] = float(store.group[name][n - 1]) if n else math.nan
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


def _failed(message: str) -> dict:
    return {"status": "failed", "message": message, "wall_seconds": 0.0, "steps": 0,
            "time": 0.0, **{name: math.nan for name in TABLE_MOMENTS}}


def run_point(description: dict, path: str, poll: float = 1.0) -> dict:
    """Run (or resume, or skip) one point into ``path``; the task a worker executes.

    Returns its table row. Parameters the description refuses, health stops and a damaged
    store are returned as ``failed`` with the message; nothing is raised. When another
    process holds the store's writer lock (Dask gave the task again to a new worker while
    the first, presumed dead, still runs it), this one waits for it, polling every
    ``poll`` seconds, and then takes the store as that process left it: finished, or cut
    short and resumed from there. Two processes never write one store.
    """
    from granframe.run.runner import HealthError, Simulation
    from granframe.run.storage import StoreError, StoreLockedError

    status = _status(path)
    if status in ("finished", "failed"):
        return _row(path)
    if status == "damaged":
        return _failed(f"store: the run store '{path}' cannot be read (granframe check "
                       "lists the damage)")
    try:
        simulation = Simulation(RunDescription.from_dict(description))
    except (ValueError, TypeError) as exc:
        return _failed(f"refused: {exc}")
    while True:
        try:
            simulation.run(path, resume=True, progress=False)
            break
        except StoreLockedError:
            time.sleep(poll)
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


def _write_table(root: zarr.Group, names, points, rows) -> None:
    """The sweep table, rewritten whole from ``rows`` (name -> row; missing: pending)."""
    columns = {"name": numpy.array(names, dtype=str)}
    for key in points[0] if points else ():
        values = [p[key] for p in points]
        kind = str if any(isinstance(v, str) for v in values) else float
        columns[key] = numpy.array([kind(v) if not isinstance(v, bool) else float(v)
                                    for v in values])
    empty = {"status": "pending", "message": "", "wall_seconds": math.nan, "steps": 0,
             "time": math.nan, **{m: math.nan for m in TABLE_MOMENTS}}
    for field, default in empty.items():
        values = [rows.get(n, empty)[field] for n in names]
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
    """What a sweep did: its store, and how many runs finished, failed or were skipped."""

    store: str
    finished: int
    failed: int
    skipped: int
    wall_seconds: float


def run_sweep(sweep: Sweep, out, *, client=None, scheduler: str | None = None,
              workers: int | None = None, progress: bool | None = None) -> SweepResult:
    """Run every point of ``sweep`` into the store ``out`` on Dask (see the module notes).

    ``client`` (a ``distributed.Client``), else ``scheduler`` (an address), else a
    ``LocalCluster`` of ``workers`` single-threaded worker processes (default: one per
    core) made for the sweep and closed after it.
    """
    import distributed

    if not isinstance(sweep, Sweep):
        check.reject("run_sweep", "sweep", sweep, "must be a Sweep", error=TypeError)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        check.reject("run_sweep", "workers", workers, "must be a whole number >= 1 (worker "
                     "processes of the LocalCluster), or None for one per core")
    start = time.perf_counter()
    out = pathlib.Path(out)
    kind = store_kind(out)
    if kind == "other" and {p.name for p in out.iterdir()} == {"runs"}:
        kind = "sweep"             # run stores written before the sweep's own metadata
    if kind not in ("missing", "empty", "sweep"):
        what = {"run": "a granframe run store", "file": "a file"}.get(kind, "not a sweep store")
        check.reject("run_sweep", "out", str(out), f"must be a new path, an empty directory or "
                     f"a sweep store; it is {what}")
    points = sweep.points()
    names = [run_name(p) for p in points]
    if len(set(names)) != len(names):
        check.reject("run_sweep", "sweep", sweep.to_dict(), "gives two points the same name")
    with WriterLock(out):
        return _drive(sweep, out, points, names, client, scheduler, workers, progress, start)


def _drive(sweep, out, points, names, client, scheduler, workers, progress, start):
    """run_sweep with the sweep store's writer lock held (one driver, one table writer)."""
    import distributed

    root = zarr.open_group(str(out), mode="a", zarr_format=3)
    previous = root.attrs.get("granframe_sweep")
    if previous is not None and previous.get("sweep") != json.loads(json.dumps(sweep.to_dict())):
        check.reject("run_sweep", "out", str(out), "holds another sweep; choose a new store")
    root.attrs["granframe_sweep"] = {"schema": SCHEMA, "sweep": sweep.to_dict(), "runs": names}
    paths = {n: str(out / "runs" / n) for n in names}
    rows, todo = {}, []
    for name, point in zip(names, points):
        if _status(paths[name]) in ("finished", "failed"):
            rows[name] = _row(paths[name])
            continue
        todo.append((name, apply(sweep.base, point)))
    skipped = len(rows)
    _write_table(root, names, points, rows)
    own = None
    if client is None:
        if scheduler is not None:
            client = distributed.Client(scheduler)
        else:
            own = distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                           processes=True, dashboard_address=":0")
            client = distributed.Client(own)
    try:
        print(f"sweep: {len(names)} runs, {skipped} already ended, {len(todo)} to run; "
              f"Dask dashboard: {client.dashboard_link}")
        futures = {client.submit(run_point, description, paths[name], key=f"granframe-{name}",
                                 pure=False): name for name, description in todo}
        counts = {"finished": 0, "failed": 0}
        bar = tqdm.tqdm(total=len(todo), disable=None if progress is None else not progress,
                        unit="run", dynamic_ncols=True)
        try:
            for future in distributed.as_completed(futures):
                name = futures[future]
                rows[name] = future.result()
                counts["finished" if rows[name]["status"] == "finished" else "failed"] += 1
                running = sum(len(keys) for keys in client.processing().values())
                bar.update(1)
                bar.set_postfix_str(f"done {counts['finished']}, failed {counts['failed']}, "
                                    f"running {running}", refresh=False)
                _write_table(root, names, points, rows)
        finally:
            bar.close()
    finally:
        if own is not None:
            client.close()
            own.close()
    finished = sum(1 for r in rows.values() if r["status"] == "finished")
    return SweepResult(str(out), finished, len(rows) - finished, skipped,
                       time.perf_counter() - start)
