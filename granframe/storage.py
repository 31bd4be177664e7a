"""One run, one zarr (v3) store: snapshots of f, moments every step, full metadata.

Layout (every array carries ``dimension_names``, so ``xarray.open_zarr`` gives a
labelled dataset):

=====================  ===========================  ===================================
array                  dimensions                   contents
=====================  ===========================  ===================================
``f``                  time, v1, ..., vd            snapshots of f, one per chunk
``time``               time                         snapshot times
``v1`` ... ``vd``      vi                           grid points
``step_time``          step_time                    time after each step (0 first)
``step``, ``dt``       step_time                    step index, step size taken
moments                step_time                    mass, temperature, kinetic_energy,
                                                    min_f, negative_mass_fraction,
                                                    kurtosis, sonine_a2
``momentum``           step_time, axis              int v f dv
=====================  ===========================  ===================================

Crash safety: zarr (>= 3.1.3) writes every chunk and metadata document to a
temporary file and renames it into place, so a file is either old or new.
Records are appended in *commits*: data first, then ``progress`` in the
root attributes, then the consolidated metadata. ``progress`` names the
last complete snapshot and the moment records that go with it; anything
beyond it (a commit cut short by SIGKILL) is truncated on resume.
"""

from __future__ import annotations

import datetime
import os
import pathlib
import shutil
import warnings

import numpy
import zarr

from granframe._version import __version__

SCHEMA = "granframe.run/1"
SCALAR_MOMENTS = ("mass", "temperature", "kinetic_energy", "min_f", "negative_mass_fraction",
                  "kurtosis", "sonine_a2")
_LONG_NAMES = {
    "f": "distribution function f(t, v)", "time": "time of the snapshot",
    "step_time": "time after the step", "step": "step index", "dt": "step size taken",
    "mass": "mass int f dv", "temperature": "temperature int |v-u|^2 f / (d rho)",
    "kinetic_energy": "kinetic energy int |v|^2/2 f dv", "min_f": "minimum of f on the grid",
    "negative_mass_fraction": "int max(-f, 0) dv / int |f| dv",
    "kurtosis": "kurtosis rho int |v-u|^4 f / (int |v-u|^2 f)^2",
    "sonine_a2": "second Sonine coefficient d/(d+2) kurtosis - 1",
    "momentum": "momentum int v f dv",
}
MOMENT_CHUNK = 4096


class StoreError(ValueError):
    """A store that cannot be used as asked (exists, other description, not a run store)."""


def _consolidate(path) -> None:
    with warnings.catch_warnings():  # zarr: consolidated metadata is not in the v3 spec (yet)
        warnings.simplefilter("ignore", category=UserWarning)
        zarr.consolidate_metadata(str(path))


class RunStore:
    """A run's store, opened for writing (:meth:`create`, :meth:`resume`) or reading (:meth:`open`)."""

    def __init__(self, path, group: zarr.Group):
        self.path = pathlib.Path(path)
        self.group = group

    # -- opening ----------------------------------------------------------------------
    @classmethod
    def create(cls, path, description: dict, description_toml: str, grid, provenance: dict,
               overwrite: bool = False, rescaling: dict | None = None) -> "RunStore":
        """A new, empty store for ``description``; refuses an existing path unless ``overwrite``.

        ``rescaling`` (rescaled runs) is the map to physical variables,
        :meth:`granframe.rescaling.Rescaling.to_dict`, kept in the metadata.
        """
        path = pathlib.Path(path)
        if path.is_file() or (path.is_dir() and any(path.iterdir())):
            if not overwrite:
                raise StoreError(f"store '{path}' exists; pass --resume to continue the run "
                                 "it holds, or --overwrite to replace it")
            shutil.rmtree(path) if path.is_dir() else path.unlink()
        group = zarr.open_group(str(path), mode="w", zarr_format=3)
        d = grid.dimension
        axes = [f"v{i + 1}" for i in range(d)]
        for name, points in zip(axes, [grid.points()] * d):
            array = group.create_array(name, shape=points.shape, dtype="f8",
                                       dimension_names=[name])
            array[:] = points
            array.attrs["long_name"] = f"velocity component {name}"
        group.create_array("f", shape=(0,) + grid.shape, chunks=(1,) + grid.shape, dtype="f8",
                           dimension_names=["time"] + axes)
        group.create_array("time", shape=(0,), chunks=(1024,), dtype="f8",
                           dimension_names=["time"])
        for name, dtype in (("step_time", "f8"), ("step", "i8"), ("dt", "f8")) + tuple(
                (m, "f8") for m in SCALAR_MOMENTS):
            group.create_array(name, shape=(0,), chunks=(MOMENT_CHUNK,), dtype=dtype,
                               dimension_names=["step_time"])
        group.create_array("momentum", shape=(0, d), chunks=(MOMENT_CHUNK, d), dtype="f8",
                           dimension_names=["step_time", "axis"])
        for name, text in _LONG_NAMES.items():
            group[name].attrs["long_name"] = text
        group.attrs["granframe"] = {
            "schema": SCHEMA, "version": __version__, "description": description,
            "description_toml": description_toml, "provenance": provenance,
            "created": datetime.datetime.now(datetime.timezone.utc).isoformat(),
            "progress": {"snapshots": 0, "records": 0, "status": "created"},
            **({} if rescaling is None else {"rescaling": rescaling}),
        }
        _consolidate(path)
        return cls(path, group)

    @staticmethod
    def exists(path) -> bool:
        """True when ``path`` holds a zarr group (a store to resume or refuse)."""
        return (pathlib.Path(path) / "zarr.json").is_file()

    @classmethod
    def open(cls, path, mode: str = "r") -> "RunStore":
        """An existing run store (``mode`` 'r' or 'r+')."""
        path = pathlib.Path(path)
        if not path.exists():
            raise StoreError(f"store '{path}' does not exist")
        try:
            group = zarr.open_group(str(path), mode=mode, use_consolidated=False)
        except (FileNotFoundError, ValueError, zarr.errors.GroupNotFoundError) as exc:
            raise StoreError(f"'{path}' is not a zarr group: {exc}") from None
        meta = group.attrs.get("granframe")
        if not isinstance(meta, dict) or meta.get("schema") != SCHEMA:
            raise StoreError(f"'{path}' is not a granframe run store (no '{SCHEMA}' metadata)")
        return cls(path, group)

    @classmethod
    def resume(cls, path, description: dict) -> "RunStore":
        """The store of an interrupted run of ``description``, cut back to its last commit."""
        store = cls.open(path, mode="r+")
        stored = store.metadata["description"]
        if stored != description:
            differences = sorted(_differences(stored, description))
            raise StoreError(f"store '{path}' holds a run of another description (differs in: "
                             f"{', '.join(differences)}); it is never appended to: choose "
                             "another --out, or --overwrite to replace it")
        status = store.progress.get("status")
        if status == "failed":
            raise StoreError(f"store '{path}' holds a run stopped by a health check "
                             f"({store.progress.get('message')}); resuming would fail again: "
                             "change the description and start afresh")
        store._truncate()
        return store

    # -- state ------------------------------------------------------------------------
    @property
    def metadata(self) -> dict:
        return self.group.attrs["granframe"]

    @property
    def progress(self) -> dict:
        return self.metadata["progress"]

    @property
    def snapshot_count(self) -> int:
        return int(self.progress["snapshots"])

    def last_snapshot(self):
        """(f, t) of the last committed snapshot, f as a NumPy array."""
        k = self.snapshot_count
        if k == 0:
            raise StoreError(f"store '{self.path}' has no complete snapshot to resume from")
        return self.group["f"][k - 1], float(self.group["time"][k - 1])

    def _truncate(self) -> None:
        """Drop whatever lies beyond the last commit (a commit cut short)."""
        k, n = self.snapshot_count, int(self.progress["records"])
        for name in ("f", "time"):
            array = self.group[name]
            if array.shape[0] != k:
                array.resize((k,) + array.shape[1:])
        for name in ("step_time", "step", "dt", "momentum") + SCALAR_MOMENTS:
            array = self.group[name]
            if array.shape[0] != n:
                array.resize((n,) + array.shape[1:])

    # -- writing ----------------------------------------------------------------------
    def commit(self, snapshots, records: dict, progress: dict) -> None:
        """Append snapshots [(t, f)] and moment records (name -> 1-D/2-D arrays), then mark them.

        ``progress`` (JSON-ready) is stored together with the new counts; the
        store is consistent before and after, whatever happens in between.
        """
        group = self.group
        k = self.snapshot_count
        if snapshots:
            times = numpy.array([t for t, _ in snapshots], dtype=float)
            group["f"].resize((k + len(snapshots),) + group["f"].shape[1:])
            for i, (_, f) in enumerate(snapshots):
                group["f"][k + i] = f
            group["time"].resize((k + len(times),))
            group["time"][k:] = times
            k += len(times)
        n = int(self.progress["records"])
        count = len(records["step_time"]) if records else 0
        if count:
            for name, values in records.items():
                array = group[name]
                array.resize((n + count,) + array.shape[1:])
                array[n:] = numpy.asarray(values)
            n += count
        meta = self.metadata
        meta["progress"] = dict(progress, snapshots=k, records=n)
        meta["updated"] = datetime.datetime.now(datetime.timezone.utc).isoformat()
        group.attrs["granframe"] = meta
        _consolidate(self.path)


def _differences(a, b, prefix=""):
    """Dotted keys where two nested dicts differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            yield from _differences(a.get(key), b.get(key), f"{prefix}{key}.")
    elif a != b:
        yield prefix.rstrip(".") or "(root)"


def describe(path) -> str:
    """Human-readable summary of a store (``granframe info``)."""
    store = RunStore.open(path)
    meta, progress = store.metadata, store.progress
    group = store.group
    lines = [f"store       {os.fspath(store.path)}",
             f"granframe   {meta['version']} (schema {meta['schema']}), created {meta['created']}",
             f"status      {progress.get('status')}"
             + (f": {progress['message']}" if progress.get("message") else "")]
    if progress.get("snapshots"):
        times = group["time"][:int(progress["snapshots"])]
        lines.append(f"snapshots   {len(times)} of f {tuple(group['f'].shape[1:])}, "
                     f"t = {times[0]:g} .. {times[-1]:g}")
    if progress.get("records"):
        n = int(progress["records"])
        lines.append(f"moments     {n} records (every step), t = "
                     f"{float(group['step_time'][0]):g} .. {float(group['step_time'][n - 1]):g}, "
                     f"{int(group['step'][n - 1])} steps")
        for name in ("mass", "temperature", "kurtosis", "min_f"):
            values = group[name][[0, n - 1]]
            lines.append(f"  {name:<12s}{values[0]:.10g} -> {values[1]:.10g}")
    provenance = meta.get("provenance", {})
    if provenance:
        lines.append("provenance")
        width = max(len(key) for key in provenance) + 2
        for key, value in provenance.items():
            lines.append(f"  {key:<{width}s}{value}")
    lines.append("description (TOML)")
    lines.extend("  " + line for line in meta["description_toml"].strip().splitlines())
    return "\n".join(lines)
