"""One run, one zarr (v3) store: snapshots of f, moments every step, full metadata.

Layout (every array carries ``dimension_names`` and the CF attributes ``long_name`` and
``units``, the root the flat CF attributes of :func:`root_attributes` beside granframe's
own ``granframe`` entry, so ``xarray.open_zarr`` gives a labelled dataset;
:func:`granframe.open_run` gives it checked and cut to the last commit):

=====================  ===========================  ===================================
array                  dimensions                   contents
=====================  ===========================  ===================================
``f``                  time, v1, ..., vd            snapshots of f, one per chunk
``time``               time                         snapshot times
``snapshot_step``      time                         step index of the snapshot
``snapshot_dt_next``   time                         step size proposed after it
``v1`` ... ``vd``      vi                           grid points
``step_time``          step_time                    time after each step (0 first)
``step``, ``dt``       step_time                    step index, step size taken
moments                step_time                    mass, temperature, kinetic_energy,
                                                    min_f, negative_mass_fraction,
                                                    kurtosis, sonine_a2
``momentum``           step_time, axis              int v f dv
``heat_flux``          step_time, axis              int (v-u)_i |v-u|^2 f dv / 2
``pressure_tensor``    step_time, axis, axis2       int (v-u)_i (v-u)_j f dv
=====================  ===========================  ===================================

A store written before granframe recorded the heat flux and the pressure tensor lacks
both and names no ``record_arrays`` in its metadata (:attr:`RunStore.record_arrays`); it is
read, checked and resumed in that layout.

What is stored can be trusted:

- **Checksums.** Every chunk ends in a CRC-32C (zarr's ``crc32c`` codec), so a
  damaged chunk raises on read, in granframe and in xarray alike. Every chunk is
  written, even one equal to the fill value, so a missing chunk is damage, never a
  legitimate gap; floating-point arrays are filled with NaN and integer ones with -1,
  so a reader that does not check (``xarray.open_zarr``) sees a missing chunk as NaN
  or -1, never as a zero. :meth:`RunStore.verify` reads every committed chunk
  (``granframe check``).
- **Commits.** Records are appended in commits: data first, then ``progress`` in the
  root attributes, then the consolidated metadata. zarr (>= 3.1.3) writes every chunk
  and metadata document to a temporary file and renames it into place, so a file is
  either old or new; ``progress`` names the last complete snapshot and the moment
  records that go with it, and anything beyond it (a commit cut short) is dropped on
  resume. There is one moment record per step, step 0 included, so the records of
  snapshot k are ``snapshot_step[k] + 1``. A commit is four phases
  (:meth:`RunStore.begin_commit`, :meth:`~RunStore.write_block`,
  :meth:`~RunStore.write_shared`, :meth:`~RunStore.end_commit`; the notes of
  :class:`RunStore`), so that in a space run, whose f and fields are chunked by block of
  cells, the owner of each block writes its own chunk files.
- **Atomic creation and replacement.** A store is built beside its path, as
  ``.NAME.granframe-new-TOKEN``, up to its first commit, then renamed into place; an
  existing store being replaced is first renamed to ``.NAME.granframe-old-TOKEN`` and
  deleted only after the new one is in place. A kill at any moment leaves the old
  store, or the new one with its first commit; the next writer finishes a swap that
  was cut between the two renames (:func:`recover`).
- **One writer.** A writer holds an exclusive lock (``flock``) on ``.NAME.granframe.lock``
  beside the store, which names the holder (pid, host, since) and is removed when the
  writer ends. The kernel releases the lock when the holder dies, however it dies; a
  second writer is refused with the holder's name (:class:`WriterLock`).
- **Only granframe's own data is replaced.** ``overwrite`` replaces a granframe run or
  sweep store (recognised by its metadata) or an empty directory, nothing else
  (:func:`check_replaceable`).
"""

from __future__ import annotations

import datetime
import errno
import fcntl
import functools
import itertools
import json
import math
import os
import pathlib
import platform
import shutil
import sys
import uuid
import warnings

import attrs
import numpy
import zarr

from granframe._version import __version__
from granframe.validators import is_integer, is_real, reject

#: zarr warns of every entry of a store that is not a zarr array or group (a directory left
#: by a write a kill cut short, a file a user dropped in); granframe reads only the arrays of
#: its layout, and ``granframe check`` names those entries in one line (:func:`stray_entries`)
warnings.filterwarnings("ignore", message="Object at .* is not recognized as a component of a "
                        "Zarr hierarchy", category=UserWarning)

SCHEMA = "granframe.run/2"
SWEEP_SCHEMA_KEY = "granframe_sweep"
SCALAR_MOMENTS = ("mass", "temperature", "kinetic_energy", "min_f", "negative_mass_fraction",
                  "kurtosis", "sonine_a2")
#: arrays along the snapshot dimension ``time`` and along ``step_time``
SNAPSHOT_ARRAYS = ("f", "time", "snapshot_step", "snapshot_dt_next")
#: moments with d or d x d components, recorded every step beside ``momentum``
TENSOR_MOMENTS = ("pressure_tensor", "heat_flux")
#: the moments recorded after every step, and the record arrays: the step and its moments
RECORDED_MOMENTS = ("momentum",) + SCALAR_MOMENTS + TENSOR_MOMENTS
RECORD_ARRAYS = ("step_time", "step", "dt") + RECORDED_MOMENTS
#: the records of a store whose metadata names none (``record_arrays``): written before
#: granframe recorded the pressure tensor and heat flux; it keeps that layout when resumed
FIRST_RECORD_ARRAYS = ("step_time", "step", "dt", "momentum") + SCALAR_MOMENTS
_LONG_NAMES = {
    "f": "distribution function f(t, v)", "time": "time of the snapshot",
    "snapshot_step": "step index of the snapshot",
    "snapshot_dt_next": "step size proposed after the snapshot",
    "step_time": "time after the step", "step": "step index", "dt": "step size taken",
    "mass": "mass int f dv", "temperature": "temperature int |v-u|^2 f / (d rho)",
    "kinetic_energy": "kinetic energy int |v|^2/2 f dv", "min_f": "minimum of f on the grid",
    "negative_mass_fraction": "int max(-f, 0) dv / int |f| dv",
    "kurtosis": "kurtosis rho int |v-u|^4 f / (int |v-u|^2 f)^2",
    "sonine_a2": "second Sonine coefficient d/(d+2) kurtosis - 1",
    "momentum": "momentum int v f dv",
    "pressure_tensor": "pressure tensor int (v-u)_i (v-u)_j f dv",
    "heat_flux": "heat flux int (v-u)_i |v-u|^2 f dv / 2",
}
#: the long names of the records of a space run with a hierarchy of collision models
#: (``space.hierarchy``; :data:`granframe.run.problems.space.LEVEL_RECORDS`)
LEVEL_LONG_NAMES = {
    "level": "collision model of each cell over the step: its index in space.hierarchy.levels",
    "realizability": "Navier-Stokes realizability indicator kappa = max(|sigma|_F / p, "
                     "|q| / (p sqrt T)) of each cell after the collision step (NaN before "
                     "the first step, infinite where the cell has no equilibrium)",
    "distance": "relative L1 distance delta = sum |f - M[f]| h^d / rho of each cell from its "
                "local Maxwellian after the collision step (NaN before the first step and "
                "where the cell has no equilibrium)",
    "reach": "cells on each side that the level of each cell reaches in the next choice: "
             "max(buffer, free_paths x eps sqrt(2T) / nu_s / dx)",
}

#: the long names of a space run's arrays where they differ from :data:`_LONG_NAMES`: the
#: fields are per cell (rho, u, T, P, q of the cell average of f), the totals are
#: integrals over x as well, and the wall records what entered [0, ell] through each
#: wall over one step (time-integrated fluxes, positive inwards)
_SPACE_LONG_NAMES = {
    **LEVEL_LONG_NAMES,
    "f": "distribution function f(t, x, v), cell averages",
    "x": "cell centre",
    "mass": "total mass int int f dv dx",
    "kinetic_energy": "total kinetic energy int int |v|^2/2 f dv dx",
    "min_f": "minimum of f over the cells and the grid",
    "negative_mass_fraction": "int int max(-f, 0) dv dx / int int |f| dv dx",
    "density": "density rho = int f dv of each cell",
    "velocity": "bulk velocity u = int v f dv / rho of each cell",
    "temperature": "temperature int |v-u|^2 f dv / (d rho) of each cell",
    "pressure_tensor": "pressure tensor int (v-u)_i (v-u)_j f dv of each cell",
    "heat_flux": "heat flux int (v-u)_i |v-u|^2 f dv / 2 of each cell",
    "wall_mass": "mass that entered the interval through the wall over the step (the "
                 "time integral of the upwind wall flux int v_1 f dv, positive inwards)",
    "wall_energy": "energy that entered the interval through the wall over the step (the "
                   "time integral of the upwind wall flux int v_1 |v|^2/2 f dv, positive "
                   "inwards)",
    "wall_momentum": "momentum (components v1 ... vd) that entered the interval through the "
                     "wall over the step (the time integral of the upwind wall flux "
                     "int v_1 v f dv, positive along +v_i); per unit time, the force of the "
                     "wall on the gas",
}
#: CF version whose attribute names the stores and :func:`granframe.open_run` use
CONVENTIONS = "CF-1.10"
#: what every quantity is measured in; all are dimensionless (CF's units "1")
NONDIMENSIONALISATION = (
    "All quantities are dimensionless (units 1): granframe solves "
    "d_t f = Q_I(f, f)/eps + tau Delta_v f in reduced variables. Velocities (v1 ... vd) "
    "are in units of a reference thermal speed v0 = sqrt(k_B T_ref / m), so that the "
    "temperature T = int |v-u|^2 f dv / (d rho) is in units of T_ref; f is in units of "
    "n0 / v0^d, so that its mass int f dv is the number density in units of a reference "
    "density n0 (the initial condition sets it, 1 by default); time (time, step_time, dt) "
    "is in units of the collision time in which the kernel reads "
    "B = C |g|^lambda b(cos theta) E^gamma with the constant C of the run's kernel, by "
    "default the review's convention C = 1/(2 pi) in 2D and 1/(4 pi) in 3D (Maxwell "
    "molecules B = 1/(2 pi) in 2D, hard spheres B = |g|/(4 pi) in 3D). The heat bath tau "
    "and the Knudsen number eps are in these units too.")
#: added to :data:`NONDIMENSIONALISATION` for a run in self-similar variables
RESCALED_NOTE = (
    " This run is rescaled (free cooling in self-similar variables, "
    "granframe.equations.rescaled): time and step_time are the rescaled time s, v1 ... vd "
    "the velocities xi and f the profile g(s, xi), with f(t, v) = omega^d g(s, u + omega "
    "(v - u)), omega = exp(rescaling_rate s) and dt/ds = omega^rescaling_degree.")
REFERENCES = (
    "J. A. Carrillo, J. Hu, Z. Ma, T. Rey, Recent development in kinetic theory of "
    "granular materials: analysis and numerical methods, arXiv:2001.11206 (the review); "
    "F. Filbet, L. Pareschi, G. Toscani, J. Comput. Phys. 202 (2005) 216-235; "
    "J. Hu, Z. Ma, J. Comput. Phys. 385 (2019) 119-134")

MOMENT_CHUNK = 4096
SNAPSHOT_CHUNK = 1024
#: the cells axis of a space run's store: the first dimension after ``time`` of f and
#: after ``step_time`` of the fields; the arrays that have it are written block by block
CELLS = "x"
#: statuses of a run that may be continued
RESUMABLE = ("running", "interrupted")
_STAGING, _TRASH = "granframe-new", "granframe-old"


class StoreError(ValueError):
    """A store that cannot be used as asked (exists, other description, not a run store)."""


class StoreLockedError(StoreError):
    """The store is being written by another live process (named in the message)."""


class StoreExistsError(StoreError):
    """A granframe store is at the path (a run given ``resume`` continues it instead)."""


class StoreDamagedError(StoreError):
    """Committed data of the store is missing or fails its checksum.

    ``problems`` lists what is wrong, as :meth:`RunStore.verify` gives it.
    """

    def __init__(self, message, problems=()):
        super().__init__(message)
        self.problems = list(problems)


def codecs() -> dict:
    """The compressors of every granframe array: zstd, then a CRC-32C of the chunk."""
    return {"compressors": (zarr.codecs.ZstdCodec(level=0), zarr.codecs.Crc32cCodec()),
            "config": {"write_empty_chunks": True}}


def fill_value(dtype) -> float | int:
    """NaN for floating-point arrays, -1 for integer ones: a missing chunk is never a zero."""
    return math.nan if numpy.dtype(dtype).kind == "f" else -1


def consolidate(path) -> None:
    """Consolidate the metadata of the store at ``path`` (a path, or a zarr store object)."""
    with warnings.catch_warnings():  # zarr: consolidated metadata is not in the v3 spec (yet)
        warnings.simplefilter("ignore", category=UserWarning)
        zarr.consolidate_metadata(str(path) if isinstance(path, (str, os.PathLike)) else path)


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat()


def array_attributes(name: str, space: bool = False) -> dict:
    """The CF attributes of the array ``name`` of a run store: ``long_name`` and ``units``.

    ``space``: the store of a space run (its metadata has a ``space`` entry), whose
    fields are per cell and whose totals are integrals over x too.
    """
    names = {**_LONG_NAMES, **_SPACE_LONG_NAMES} if space else _LONG_NAMES
    long_name = names.get(name, f"velocity component {name}")
    return {"long_name": long_name, "units": "1"}


def flat_attributes(prefix: str, value) -> dict:
    """``value`` as attributes netCDF accepts: nested dicts become ``prefix_key`` names.

    Strings and numbers are kept (a bool as 0 or 1), a list of numbers or of strings
    stays a list, any other list becomes its JSON text; None and empty lists are left
    out (no attribute).
    """
    if isinstance(value, dict):
        flat = {}
        for key, item in value.items():
            flat.update(flat_attributes(f"{prefix}_{key}", item))
        return flat
    if value is None or (isinstance(value, list) and not value):
        return {}
    if isinstance(value, bool):
        return {prefix: int(value)}
    if isinstance(value, list):
        alike = all(isinstance(v, str) for v in value) or all(map(is_real, value))
        return {prefix: value if alike else json.dumps(value)}
    return {prefix: value}


def root_attributes(meta: dict) -> dict:
    """The flat CF attributes of a run store's root, from its ``granframe`` metadata.

    ``title``, ``source``, ``history``, ``Conventions``, ``references``,
    ``nondimensionalisation``, ``granframe_schema``, ``description_toml``, and the
    provenance, the rescaling and the f0 projection as ``provenance_*``,
    ``rescaling_*`` and ``f0_projection_*`` scalars. The same for every store of one
    description; what changes with each commit (``progress``) is not among them.
    """
    description = meta["description"]
    note = NONDIMENSIONALISATION + (RESCALED_NOTE if "rescaling" in meta else "")
    return {
        "title": description.get("title") or "granframe run",
        "source": f"granframe {meta['version']}",
        "history": f"{meta['created']} created by granframe run (granframe "
                   f"{meta['version']}, store schema {meta['schema']})",
        "Conventions": CONVENTIONS, "references": REFERENCES,
        "nondimensionalisation": note, "granframe_schema": meta["schema"],
        "description_toml": meta["description_toml"],
        **flat_attributes("provenance", meta.get("provenance", {})),
        **flat_attributes("rescaling", meta.get("rescaling")),
        **flat_attributes("f0_projection", meta.get("f0_projection")),
    }


# -- what a path holds ----------------------------------------------------------------------
def _root_attributes(path: pathlib.Path) -> dict | None:
    """The root attributes of the zarr v3 group at ``path``; None when there is none."""
    try:
        document = json.loads((path / "zarr.json").read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(document, dict) or document.get("node_type") != "group":
        return None
    attributes = document.get("attributes")
    return attributes if isinstance(attributes, dict) else {}


def store_kind(path) -> str:
    """What ``path`` holds: 'missing', 'file', 'empty', 'run', 'sweep' or 'other'.

    'run' and 'sweep' are recognised by granframe's metadata in the root ``zarr.json``.
    """
    path = pathlib.Path(path)
    if not os.path.lexists(path):
        return "missing"
    if not path.is_dir() or path.is_symlink():
        return "file"
    if not any(path.iterdir()):
        return "empty"
    attributes = _root_attributes(path)
    if attributes is None:
        return "other"
    meta = attributes.get("granframe")
    if isinstance(meta, dict) and str(meta.get("schema", "")).startswith("granframe.run/"):
        return "run"
    if isinstance(attributes.get(SWEEP_SCHEMA_KEY), dict):
        return "sweep"
    return "other"


def _foreign_entries(path: pathlib.Path, kind: str) -> list[str]:
    """Entries at the top of a granframe store that granframe did not write."""
    if kind == "run":
        meta = (_root_attributes(path) or {}).get("granframe", {})
        own = set(SNAPSHOT_ARRAYS) | set(meta.get("record_arrays", RECORD_ARRAYS)) | {"zarr.json"}
        own |= set(meta.get("coordinate_arrays", ()))
        own |= {p.name for p in path.iterdir() if p.name[:1] == "v" and p.name[1:].isdigit()}
    else:
        own = {"zarr.json", "runs", "table"}
    return sorted(p.name for p in path.iterdir()
                  if p.name not in own and not p.name.endswith(".partial"))


def _inside(inner: pathlib.Path, outer: pathlib.Path) -> bool:
    return inner == outer or outer in inner.parents


def check_replaceable(path, protect=()) -> None:
    """Refuse, by name, to replace anything but a granframe store or an empty directory.

    ``path`` may be replaced when it is missing, an empty directory, or a granframe run
    or sweep store (recognised by its metadata) holding nothing granframe did not write.
    Refused: a file, any other directory, the current directory, a directory holding the
    current directory, a directory holding any path of ``protect`` (the source of the
    run), and a sweep store with a run still written by a live process.
    """
    path = pathlib.Path(path)
    kind = store_kind(path)
    if kind == "missing":
        return
    where = path.resolve()
    if _inside(pathlib.Path.cwd().resolve(), where):
        raise StoreError(f"--overwrite refused: '{path}' is the current directory or holds "
                         "it; choose a store path such as runs/NAME.zarr")
    for source in protect:
        if _inside(pathlib.Path(source).resolve(), where):
            raise StoreError(f"--overwrite refused: '{path}' holds the source '{source}'; "
                             "choose a store path beside it")
    if kind == "file":
        raise StoreError(f"--overwrite refused: '{path}' is a file, not a granframe store; "
                         "only a granframe run or sweep store, or an empty directory, is "
                         "replaced")
    if kind == "other":
        entries = sorted(p.name for p in path.iterdir())
        shown = ", ".join(entries[:5]) + (", ..." if len(entries) > 5 else "")
        raise StoreError(f"--overwrite refused: '{path}' is not a granframe store (it holds "
                         f"{shown}); only a granframe run or sweep store, or an empty "
                         "directory, is replaced")
    if kind == "sweep" and (path / "runs").is_dir():
        for run in sorted((path / "runs").iterdir()):   # workers may outlive their driver
            WriterLock.check_free(run)
    if kind in ("run", "sweep"):
        foreign = _foreign_entries(path, kind)
        if foreign:
            raise StoreError(f"--overwrite refused: the granframe store '{path}' also holds "
                             f"files granframe did not write ({', '.join(foreign[:5])}); "
                             "move them out first")


# -- the writer lock ------------------------------------------------------------------------
def lock_path(path) -> pathlib.Path:
    """The lock file of the store ``path``: ``.NAME.granframe.lock`` beside it."""
    path = pathlib.Path(path)
    return path.parent / f".{path.name}.granframe.lock"


class WriterLock:
    """An exclusive lock on a store path, held by one writer at a time.

    ``flock`` on the file ``.NAME.granframe.lock`` beside the store, which records the
    holder (pid, host, since, command) for the message a second writer gets. The
    holder removes the file when it releases the lock, so a store leaves nothing beside
    it; the kernel drops the lock when its holder's process ends, however it ends (a
    kill, a crash), so a dead holder never blocks, and its file is taken over. A lock
    taken on a file that its holder removed meanwhile is dropped and taken again on
    the file now at the path (the inode is compared), so two writers never both hold it.
    """

    def __init__(self, path):
        self.path = pathlib.Path(path)
        self.file = lock_path(path)
        self._handle = None

    def acquire(self) -> "WriterLock":
        """Take the lock, or raise :class:`StoreLockedError` naming its live holder."""
        self.file.parent.mkdir(parents=True, exist_ok=True)
        while True:
            handle = open(self.file, "a+")
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                handle.close()
                if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise StoreError(f"cannot lock '{self.file}' for writing: {exc}") from None
                raise StoreLockedError(
                    f"store '{self.path}' is being written by {self.holder()}; a second "
                    "writer is refused (wait for it to end, or stop it)") from None
            try:
                current = os.stat(self.file).st_ino == os.fstat(handle.fileno()).st_ino
            except FileNotFoundError:
                current = False
            if current:
                break
            handle.close()      # its holder removed this file meanwhile: take the new one
        handle.seek(0)
        handle.truncate()
        handle.write(json.dumps({"pid": os.getpid(), "host": platform.node(), "since": _now(),
                                 "command": " ".join(sys.argv)[:300]}) + "\n")
        handle.flush()
        self._handle = handle
        return self

    def holder(self) -> str:
        """Who holds (or last held) the lock, in words."""
        try:
            info = json.loads(self.file.read_text())
            return (f"pid {info['pid']} on host {info['host']} since {info['since']} "
                    f"({info.get('command', '')})")
        except (OSError, ValueError, KeyError, TypeError):
            return "another process (its record is being written)"

    @property
    def held(self) -> bool:
        return self._handle is not None

    @classmethod
    def check_free(cls, path) -> None:
        """Raise :class:`StoreLockedError` when a live process holds the lock of ``path``
        (a lock file left by a dead holder is free); takes nothing."""
        lock = cls(path)
        try:
            handle = open(lock.file)
        except FileNotFoundError:
            return
        with handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except OSError:
                raise StoreLockedError(f"store '{lock.path}' is being written by "
                                       f"{lock.holder()}") from None

    def release(self) -> None:
        """Remove the lock file, then drop the lock (in this order: see the class notes)."""
        if self._handle is not None:
            self.file.unlink(missing_ok=True)
            fcntl.flock(self._handle, fcntl.LOCK_UN)
            self._handle.close()
            self._handle = None

    def __enter__(self):
        return self if self.held else self.acquire()

    def __exit__(self, *exc):
        self.release()


def _sibling(path: pathlib.Path, role: str, token: str) -> pathlib.Path:
    """``.NAME.ROLE-TOKEN`` beside ``path``: a staged (role 'granframe-new') or a replaced
    ('granframe-old') store."""
    return path.parent / f".{path.name}.{role}-{token}"


def _siblings(path: pathlib.Path, role: str) -> list[pathlib.Path]:
    """The staged or replaced stores of ``path`` (names compared as text: a store's name
    may hold any character, glob patterns included)."""
    prefix = f".{path.name}.{role}-"
    try:
        entries = os.scandir(path.parent)
    except FileNotFoundError:
        return []
    with entries:
        return sorted(path.parent / e.name for e in entries
                      if e.name.startswith(prefix) and e.name[len(prefix):].isalnum())


def recover(path) -> None:
    """Finish or clean what a writer of ``path`` left when it was killed.

    Call with the store's :class:`WriterLock` held (no other writer is at work), so
    every staging or replaced sibling belongs to a writer that has died:

    - ``path`` missing and a replaced store beside it: the kill fell between the two
      renames of a swap; the new store (complete up to its first commit) is put in
      place, or the old one when the new is not there;
    - a replaced store beside ``path``: deleted (the swap was done);
    - a staging store: a creation cut short, deleted.
    """
    path = pathlib.Path(path)
    for old in _siblings(path, _TRASH):
        new = _sibling(path, _STAGING, old.name.rsplit("-", 1)[-1])
        if not os.path.lexists(path):
            os.rename(new if store_kind(new) == "run" and _published(new) else old, path)
        if old.exists():
            shutil.rmtree(old)
    for new in _siblings(path, _STAGING):
        shutil.rmtree(new)


def _published(path: pathlib.Path) -> bool:
    """True when the staged store at ``path`` holds its first commit (ready to swap in)."""
    meta = (_root_attributes(path) or {}).get("granframe", {})
    return int(meta.get("progress", {}).get("snapshots", 0)) >= 1


def _chunk_grid(array, extent: int):
    """Chunk indices of ``array`` covering its first ``extent`` entries along axis 0."""
    counts = [math.ceil(extent / array.chunks[0])] + [
        math.ceil(s / c) for s, c in zip(array.shape[1:], array.chunks[1:])]
    return itertools.product(*(range(n) for n in counts))


def _chunk_file(root: pathlib.Path, name: str, index) -> pathlib.Path:
    return root / name / "c" / pathlib.Path(*map(str, index))


@attrs.frozen
class RecordArray:
    """An array recorded after every step.

    Parameters
    ----------
    name : str
        The array's name in the store.
    shape, dimensions : tuple
        Its shape and dimension names after ``step_time``.
    dtype : str
        Its data type ('f8', 'i8').
    chunk : int
        Records per chunk along ``step_time``.
    cells_chunk : int or None
        Cells per chunk along its first dimension after ``step_time``, which must then be
        the cells axis ``x``: a space run's fields are chunked by block of cells
        (``cells_chunk = block_cells``), so that the owner of a block writes chunk files
        no other block touches (:meth:`RunStore.write_block`). None: one chunk spans
        each dimension after ``step_time`` whole.
    """

    name: str
    shape: tuple = ()
    dimensions: tuple = ()
    dtype: str = "f8"
    chunk: int = MOMENT_CHUNK
    cells_chunk: int | None = attrs.field(default=None)

    @cells_chunk.validator
    def _check_cells_chunk(self, attribute, value):
        if value is None:
            return
        if tuple(self.dimensions[:1]) != (CELLS,) or not self.shape:
            reject("RecordArray", "cells_chunk", value, f"is only allowed for a record whose "
                   f"first dimension after step_time is the cells axis '{CELLS}' (record "
                   f"'{self.name}' has dimensions {tuple(self.dimensions)}); leave it None")
        if not is_integer(value) or not 1 <= value <= self.shape[0]:
            reject("RecordArray", "cells_chunk", value, f"must be None or a whole number of "
                   f"cells from 1 to {self.shape[0]} (the cells of record '{self.name}')")

    @property
    def chunks(self) -> tuple:
        """The chunk shape of the array in the store (``step_time`` first)."""
        after = tuple(self.shape) if self.cells_chunk is None else \
            (self.cells_chunk,) + tuple(self.shape[1:])
        return (self.chunk,) + after


@attrs.frozen
class Layout:
    """What a run store holds besides its metadata.

    Parameters
    ----------
    coordinates : tuple
        ``(name, values, dimensions)`` of each coordinate array (written once).
    snapshot_shape, snapshot_chunks, snapshot_dimensions : tuple
        Shape, chunk shape and dimension names of one snapshot of ``f`` (after ``time``;
        one snapshot per chunk along ``time``).
    records : tuple
        The :class:`RecordArray` of each record, ``step_time``, ``step`` and ``dt`` first
        (a space run's fields chunked by block of cells: ``cells_chunk``).
    space : dict or None
        A space-inhomogeneous run's cells and blocks (kept in the metadata).
    """

    coordinates: tuple
    snapshot_shape: tuple
    snapshot_chunks: tuple
    snapshot_dimensions: tuple
    records: tuple
    space: dict | None = None

    def create(self, group) -> None:
        """Create the layout's (empty) arrays in ``group``, the coordinates filled."""
        space = self.space is not None
        for name, values, dimensions in self.coordinates:
            values = numpy.asarray(values)
            _create(group, name, values.shape, values.shape, values.dtype.str[1:],
                    list(dimensions), space)[:] = values
        _create(group, "f", (0,) + tuple(self.snapshot_shape),
                (1,) + tuple(self.snapshot_chunks), "f8",
                ["time"] + list(self.snapshot_dimensions), space)
        for name, dtype in (("time", "f8"), ("snapshot_step", "i8"), ("snapshot_dt_next", "f8")):
            _create(group, name, (0,), (SNAPSHOT_CHUNK,), dtype, ["time"], space)
        for spec in self.records:
            _create(group, spec.name, (0,) + tuple(spec.shape), spec.chunks,
                    spec.dtype, ["step_time"] + list(spec.dimensions), space)


#: the step, its time and its size: the first records of every layout
STEP_RECORDS = (RecordArray("step_time"), RecordArray("step", dtype="i8"), RecordArray("dt"))


def homogeneous_layout(grid) -> Layout:
    """The layout of a space-homogeneous run on ``grid``: f (time, v1, ..., vd) and the
    moments of :data:`RECORDED_MOMENTS` after every step."""
    d = grid.dimension
    axes = tuple(f"v{i + 1}" for i in range(d))
    points = grid.points()
    tensors = {"momentum": ((d,), ("axis",)), "heat_flux": ((d,), ("axis",)),
               "pressure_tensor": ((d, d), ("axis", "axis2"))}
    records = STEP_RECORDS + tuple(RecordArray(name, *tensors.get(name, ((), ())))
                                   for name in RECORDED_MOMENTS)
    return Layout(tuple((name, points, (name,)) for name in axes), grid.shape, grid.shape,
                  axes, records)


@attrs.frozen
class CommitPlan:
    """Where one commit puts its data: what :meth:`RunStore.begin_commit` returns.

    Two ranges of plain integers, so that the writer that began the commit can send the
    plan to the writers of the blocks (an MPI broadcast pickles it).

    Attributes
    ----------
    snapshots : range
        The indices along ``time`` of the commit's new snapshots.
    records : range
        The indices along ``step_time`` of its new moment records.
    """

    snapshots: range
    records: range


class RunStore:
    """A run's store, opened for writing (:meth:`create`, :meth:`resume`) or reading (:meth:`open`).

    A store opened for writing holds the :class:`WriterLock` until :meth:`close`. A store
    created with ``path`` None is held in memory (a :class:`zarr.storage.MemoryStore`):
    the same layout, commits and metadata, no file, no lock; its ``path`` is None.

    Parameters
    ----------
    path : str, os.PathLike or None
        Where the store is (None: in memory).
    group : zarr.Group
        Its root group.
    lock : WriterLock or None
        The lock a writer holds on ``path``.

    Notes
    -----
    **Commits.** A commit appends snapshots of f and moment records and makes them
    visible at once. :meth:`commit` does it in one call, as four phases which several
    writers can share when the store has a cells axis (a space run, whose f and fields
    are chunked by block of cells: :attr:`cell_arrays`):

    1. ``plan = store.begin_commit(snapshot_count, record_count)``, one writer (the
       holder of the lock): every array is resized to hold the new entries (metadata
       only); the :class:`CommitPlan` says where they go.
    2. ``store.write_block(plan, cells=slice(a, b), f=..., records=...)``, the owner of
       cells a..b: its cells of the new snapshots of f and of the new field records. It
       writes the chunk files of those cells and no other file, so the owners of
       different blocks write concurrently and in any order; a and b must lie on the
       chunk boundaries along ``x`` of every array in :attr:`cell_arrays`.
    3. ``store.write_shared(plan, times=..., step=..., dt_next=..., records=...)``, one
       writer: what no block owns, the snapshot times (``time``), ``snapshot_step``,
       ``snapshot_dt_next`` and the records without a cells axis (``step_time``,
       ``step``, ``dt``, the totals, the wall records); in a store without a cells axis
       (a space-homogeneous run) f and every record.
    4. ``store.end_commit(plan, progress)``, one writer, once every write of phases 2
       and 3 has returned: ``progress`` with the new counts, then the consolidated
       metadata. This makes the commit visible.

    Until phase 4 the store reads as before the commit: readers go by the counts in
    ``progress``, and :meth:`resume` drops whatever lies beyond them, so a commit cut
    short in any phase, with its blocks written in any order or some not at all, is
    never seen. zarr writes each chunk file whole, to a temporary file renamed into
    place, so a kill leaves every file old or new.

    A writer in another process writes its blocks into a store on disk that it opens
    with ``RunStore.open(path, mode="r+")`` (it takes no lock: it writes under the lock
    of the writer that begins and ends the commits), with the plan that writer sends
    it. ``path`` is where the store is then: a new store is staged beside its final
    path until :meth:`publish` puts it in place after its first commit, so the other
    writers open it again after that.

    Examples
    --------
    The owner of each block of ``block`` cells writes its part of a commit of one
    snapshot ``f`` (cells, v1, ..., vd) and the records ``fields`` (per cell) and
    ``rest``:

    >>> plan = store.begin_commit(1, len(rest["step_time"]))          # doctest: +SKIP
    >>> for a in range(0, cells, block):                                # doctest: +SKIP
    ...     store.write_block(plan, slice(a, a + block), f=[f[a:a + block]],
    ...                       records={name: values[:, a:a + block]
    ...                                for name, values in fields.items()})
    >>> store.write_shared(plan, times=[t], step=step, dt_next=dt_next,
    ...                    records=rest)                                # doctest: +SKIP
    >>> store.end_commit(plan, progress)                                # doctest: +SKIP
    """

    def __init__(self, path, group: zarr.Group, lock: WriterLock | None = None):
        self.path = None if path is None else pathlib.Path(path)
        self.group = group
        self.lock = lock
        self._target = None      # a staged store: where publish() puts it
        self._token = None       # ... and the token of its staged and replaced names
        self._old = False        # ... replacing an existing store

    # -- opening ----------------------------------------------------------------------
    @classmethod
    def create(cls, path, description: dict, description_toml: str, grid, provenance: dict,
               overwrite: bool = False, rescaling: dict | None = None,
               protect=(), projection: dict | None = None,
               layout: "Layout | None" = None) -> "RunStore":
        """A new store for ``description``, staged beside ``path``; see :meth:`publish`.

        ``path`` None: a store in memory, which nothing else can see (no lock, nothing
        to publish or replace).
        Refuses an existing store unless ``overwrite``, and anything but a granframe
        store or an empty directory even then (:func:`check_replaceable`, ``protect``:
        paths that must not be inside it). ``rescaling`` (rescaled runs) is the map to
        physical variables, :meth:`granframe.equations.rescaled.Rescaling.to_dict`, and
        ``projection`` the moments of f0 before and after its Nyquist projection
        (:func:`granframe.model.initial.check_projection`), both kept in the metadata.
        ``layout`` is what the store holds (:class:`Layout`); by default a
        space-homogeneous run's (:func:`homogeneous_layout`). The first :meth:`commit` and
        :meth:`publish` put it in place.
        """
        memory = path is None
        path = None if memory else pathlib.Path(path)
        if not memory:
            _check_creatable(path, overwrite, protect)   # refused before anything is written
        lock, staging = (None if memory else WriterLock(path).acquire()), None
        try:
            if memory:
                kind, token = None, None
                group = zarr.create_group(zarr.storage.MemoryStore(), zarr_format=3)
            else:
                recover(path)
                kind = store_kind(path)
                _check_creatable(path, overwrite, protect)
                token = uuid.uuid4().hex[:12]
                staging = _sibling(path, _STAGING, token)
                group = zarr.create_group(str(staging), zarr_format=3)
            layout = homogeneous_layout(grid) if layout is None else layout
            layout.create(group)
            meta = {
                "schema": SCHEMA, "version": __version__, "description": description,
                "record_arrays": [spec.name for spec in layout.records],
                **({} if layout.space is None else {
                    "coordinate_arrays": [name for name, _, _ in layout.coordinates],
                    "space": layout.space}),
                "description_toml": description_toml, "provenance": provenance,
                "created": _now(),
                "progress": {"snapshots": 0, "records": 0, "status": "created"},
                **({} if rescaling is None else {"rescaling": rescaling}),
                **({} if projection is None else {"f0_projection": projection}),
            }
            group.attrs.put({**root_attributes(meta), "granframe": meta})   # one write
        except BaseException:
            if staging is not None:
                shutil.rmtree(staging, ignore_errors=True)
            if lock is not None:
                lock.release()
            raise
        store = cls(staging, group, lock)
        store._target, store._token = path, token
        store._old = kind in ("run", "sweep")
        return store

    def discard(self) -> None:
        """Remove a staged store that was never put in place, and release the lock."""
        if self._target is not None:
            shutil.rmtree(self.path, ignore_errors=True)
        self.close()

    def publish(self) -> None:
        """Put a staged store in place: one rename, or two when it replaces a store.

        The replaced store is deleted after the new one is in place.
        """
        target, staging = self._target, self.path
        if target is None:
            return
        trash = _sibling(target, _TRASH, self._token)
        if self._old:
            os.rename(target, trash)
        try:
            os.rename(staging, target)
        except OSError as exc:      # a store appeared at an empty or missing path meanwhile
            if self._old:
                os.rename(trash, target)
            shutil.rmtree(staging)
            raise StoreError(f"store '{target}' could not be put in place ({exc}); another "
                             "process wrote it meanwhile") from None
        self.path, self._target = target, None
        self.group = zarr.open_group(str(target), mode="r+", use_consolidated=False)
        if self._old:
            shutil.rmtree(trash)

    @staticmethod
    def exists(path) -> bool:
        """True when ``path`` holds a zarr group (a store to resume or refuse), or held one
        whose replacement was cut between its two renames (:func:`recover` completes it)."""
        path = pathlib.Path(path)
        return (path / "zarr.json").is_file() or (
            not os.path.lexists(path) and bool(_siblings(path, _TRASH)))

    @classmethod
    def open(cls, path, mode: str = "r", complete: bool = True) -> "RunStore":
        """An existing run store (``mode`` 'r' or 'r+').

        ``complete``: refuse a store with a committed chunk missing
        (:class:`StoreDamagedError`).
        """
        path = pathlib.Path(path)
        if not path.exists():
            if _siblings(path, _TRASH):
                raise StoreError(f"store '{path}' is being replaced, or its replacement was "
                                 "cut short: run it again with --resume to complete it")
            raise StoreError(f"store '{path}' does not exist")
        try:
            group = zarr.open_group(str(path), mode=mode, use_consolidated=False)
        except (FileNotFoundError, ValueError, zarr.errors.GroupNotFoundError) as exc:
            raise StoreError(f"'{path}' is not a zarr group: {exc}") from None
        meta = group.attrs.get("granframe")
        if isinstance(meta, dict) and str(meta.get("schema", "")).startswith("granframe.run/") \
                and meta.get("schema") != SCHEMA:
            raise StoreError(f"'{path}' is a granframe store of schema '{meta.get('schema')}' "
                             f"(granframe {meta.get('version')}); this granframe reads "
                             f"'{SCHEMA}' (with checksums): run it again to a new store")
        if not isinstance(meta, dict) or meta.get("schema") != SCHEMA:
            raise StoreError(f"'{path}' is not a granframe run store (no '{SCHEMA}' metadata)")
        store = cls(path, group)
        missing = store.verify(read=False) if complete else store._absent_arrays()
        if missing:
            raise StoreDamagedError(f"store '{path}' is damaged: {summarise(missing)} "
                                    "(granframe check lists every problem)", missing)
        return store

    @classmethod
    def resume(cls, path, description: dict, rollback: bool = False) -> "RunStore":
        """The store of an interrupted run of ``description``, cut back to its last commit.

        Takes the writer lock, finishes a replacement cut short, and checks what the run
        continues from: the committed moment records and the last snapshot must be
        present and pass their checksums. When they do not, :class:`StoreDamagedError`
        names the damage and the last intact commit; ``rollback`` continues from that
        commit instead (the snapshots and records after it are dropped).
        """
        lock = WriterLock(path).acquire()
        try:
            recover(path)
            store = cls.open(path, mode="r+", complete=False)
            store.lock = lock
            stored = store.metadata["description"]
            if stored != description:
                differences = sorted(_differences(stored, description))
                raise StoreError(f"store '{path}' holds a run of another description (differs "
                                 f"in: {', '.join(differences)}); it is never appended to: "
                                 "choose another --out, or --overwrite to replace it")
            status = store.progress.get("status")
            if status == "failed":
                raise StoreError(f"store '{path}' holds a run stopped by a health check "
                                 f"({store.progress.get('message')}); resuming would fail "
                                 "again: change the description and start afresh")
            if status not in RESUMABLE + ("finished",):
                raise StoreError(f"store '{path}' has status '{status}', which cannot be "
                                 f"resumed (resumable: {', '.join(RESUMABLE)})")
            for partial in pathlib.Path(path).rglob("*.partial"):   # writes cut by a kill
                partial.unlink()
            store._truncate()
            if status != "finished":
                store._continue_from_intact(rollback)
        except BaseException:
            lock.release()
            raise
        return store

    def close(self) -> None:
        """Release the writer lock (a store opened for writing)."""
        if self.lock is not None:
            self.lock.release()

    # -- state ------------------------------------------------------------------------
    @property
    def metadata(self) -> dict:
        return self.group.attrs["granframe"]

    @property
    def progress(self) -> dict:
        return self.metadata["progress"]

    @property
    def record_arrays(self) -> tuple:
        """The moment records of this store: :data:`RECORD_ARRAYS`, or
        :data:`FIRST_RECORD_ARRAYS` for a store written before the metadata named them."""
        return tuple(self.metadata.get("record_arrays", FIRST_RECORD_ARRAYS))

    @property
    def coordinate_arrays(self) -> tuple:
        """The coordinate arrays of this store: those its metadata names (a space run's
        ``v1`` ... ``vd`` and ``x``), else ``v1`` ... ``vd``."""
        names = self.metadata.get("coordinate_arrays")
        if names is not None:
            return tuple(names)
        d = len(self.group["f"].shape) - 1 if "f" in self._names() else \
            int(self.metadata["description"]["grid"]["dimension"])
        return tuple(f"v{i + 1}" for i in range(d))

    @property
    def location(self):
        """Where zarr finds the store: its path, or the in-memory zarr store."""
        return self.group.store if self.path is None else self.path

    @property
    def snapshot_count(self) -> int:
        return int(self.progress["snapshots"])

    def last_snapshot(self, cells: slice | None = None):
        """(f, t) of the last committed snapshot, f as a NumPy array; ``cells``: only those
        cells of a space run's f (the range a process owns), read from their chunks."""
        k = self.snapshot_count
        if k == 0:
            raise StoreError(f"store '{self.path}' has no complete snapshot to resume from")
        f = self.group["f"]
        return (f[k - 1] if cells is None else f[(k - 1, cells)],
                float(self.group["time"][k - 1]))

    def _extent(self, name: str) -> int:
        """Committed entries of an array along its first axis."""
        if name in SNAPSHOT_ARRAYS:
            return self.snapshot_count
        if name in self.record_arrays:
            return int(self.progress["records"])
        return self.group[name].shape[0]

    def _names(self) -> list[str]:
        return sorted(self.group.array_keys())

    def _absent_arrays(self) -> list[dict]:
        """Arrays of the layout that are not in the store at all."""
        expected = set(SNAPSHOT_ARRAYS + self.record_arrays + self.coordinate_arrays)
        return [{"array": name, "chunk": [], "first": 0, "kind": "missing array",
                 "detail": ""} for name in sorted(expected - set(self._names()))]

    def verify(self, names=None, snapshots=None, read: bool = True) -> list[dict]:
        """Every committed chunk of ``names`` (default: all arrays) read and checked.

        Returns the problems, each a dict: array, chunk (index), first (first entry along
        the first axis), kind ('missing array', 'missing' or 'damaged') and detail.
        ``snapshots`` limits the chunks of ``f`` read to those indices; ``read`` False
        only checks that the chunks are on disk.
        """
        problems = self._absent_arrays() if names is None else []
        for name in names or self._names():
            array = self.group[name]
            for index in _chunk_grid(array, self._extent(name)):
                if name == "f" and snapshots is not None and index[0] not in snapshots:
                    continue
                if not _chunk_file(self.path, name, index).is_file():
                    problems.append(_problem(name, array, index, "missing"))
                    continue
                if not read:
                    continue
                try:
                    array.get_block_selection(index)
                except Exception as exc:   # any decoding failure is damage
                    problems.append(_problem(name, array, index, "damaged", str(exc)))
        return problems

    def _continue_from_intact(self, rollback: bool) -> None:
        """Check what a resumed run reads; roll back to the last intact commit if asked.

        The run continues from the last snapshot whose f and snapshot entries are intact.
        A damaged chunk of the moment records before it does not stop that: with
        ``rollback`` its records are dropped (NaN; the step numbers, record i being step i,
        are written again) and listed in the metadata's ``dropped_records``
        (:func:`describe` shows them).
        """
        k = self.snapshot_count
        small = [n for n in self._names() if n != "f" and n not in self.coordinate_arrays]
        problems = self.verify(small)
        bad_snapshot = min((p["first"] for p in problems if p["array"] in SNAPSHOT_ARRAYS),
                           default=k)
        intact = None
        for j in range(min(k, bad_snapshot) - 1, -1, -1):
            damage = self.verify(["f"], snapshots={j})
            if not damage:
                intact = j
                break
            problems += damage
        if not problems:
            return
        where = summarise(problems)
        if intact is None:
            raise StoreDamagedError(f"store '{self.path}' is damaged ({where}) and holds no "
                                    "intact commit to continue from; start afresh with "
                                    "--overwrite", problems)
        t = float(self.group["time"][intact])
        step = int(self.group["snapshot_step"][intact])
        records = [p for p in problems if p["array"] in self.record_arrays
                   and p["first"] <= step and p["kind"] != "missing array"]
        dropped = [self._drop_records(p["array"], tuple(p["chunk"]), step + 1)
                   for p in records]
        if not rollback:
            lost = (f"; the moment records of the damaged chunks ({sum(d['count'] for d in dropped)}"
                    " records) are dropped (NaN)" if dropped else "")
            raise StoreDamagedError(
                f"store '{self.path}' is damaged ({where}); the last intact commit is "
                f"snapshot {intact} at t = {t:.6g} (step {step}): run again with --resume "
                f"--rollback to continue from it (the {k - 1 - intact} snapshots after it are "
                f"dropped{lost})", problems)
        for problem in records:
            self._drop_records(problem["array"], tuple(problem["chunk"]), step + 1, write=True)
        if dropped:
            meta = self.metadata
            meta["dropped_records"] = meta.get("dropped_records", []) + dropped
            self.group.attrs["granframe"] = meta
        progress = self.progress
        self._write_progress(dict(progress, snapshots=intact + 1, records=step + 1, step=step,
                                  time=t, status="running",
                                  dt_next=float(self.group["snapshot_dt_next"][intact]),
                                  rollbacks=progress.get("rollbacks", []) + [k - 1]))
        self._truncate()

    def _drop_records(self, name: str, index: tuple, extent: int, write: bool = False) -> dict:
        """The records of the chunk ``index`` of the record array ``name`` up to entry
        ``extent``: ``{"array", "first", "count"}``; with ``write`` its damaged file is
        replaced by NaN (-1 in integer arrays), and ``step`` by the step numbers."""
        array = self.group[name]
        region = tuple(slice(i * c, min((i + 1) * c, n))
                       for i, c, n in zip(index, array.chunks, (extent,) + array.shape[1:]))
        if write:
            shape = tuple(r.stop - r.start for r in region)
            values = (numpy.arange(region[0].start, region[0].stop).reshape(shape)
                      if name == "step" else numpy.full(shape, fill_value(array.dtype)))
            _chunk_file(self.path, name, index).unlink(missing_ok=True)
            array.with_config({"write_empty_chunks": True})[region] = values   # NaN: the fill
        return {"array": name, "first": region[0].start, "count": region[0].stop - region[0].start}

    def _truncate(self) -> None:
        """Drop whatever lies beyond the last commit (a commit cut short).

        Chunk files wholly beyond it are deleted too, so that no stale chunk is ever
        merged into a later write.
        """
        for name in SNAPSHOT_ARRAYS + self.record_arrays:
            array = self.group[name]
            extent = self._extent(name)
            if array.shape[0] != extent:
                first_gone = math.ceil(extent / array.chunks[0])
                for index in _chunk_grid(array, array.shape[0]):
                    if index[0] >= first_gone:
                        _chunk_file(self.path, name, index).unlink(missing_ok=True)
                array.resize((extent,) + array.shape[1:])

    # -- writing ----------------------------------------------------------------------
    @functools.cached_property
    def cell_arrays(self) -> tuple:
        """The arrays split by cells, which :meth:`write_block` writes: those whose first
        dimension after ``time`` or ``step_time`` is the cells axis ``x`` (a space run's f
        and fields); empty in a space-homogeneous run's store."""
        return tuple(name for name in SNAPSHOT_ARRAYS[:1] + self.record_arrays
                     if tuple(self.group[name].metadata.dimension_names or ())[1:2] == (CELLS,))

    def commit(self, snapshots, records: dict, progress: dict) -> None:
        """Append snapshots [(t, f)] and moment records (name -> arrays along step_time),
        then mark them.

        Records that the store's layout lacks (:attr:`record_arrays`: the pressure tensor
        and heat flux of a store written before granframe recorded them) are left out.
        ``progress`` (JSON-ready) is stored together with the new counts; the
        store is consistent before and after, whatever happens in between. Each
        snapshot is stored with the step and the proposed next step size of
        ``progress`` (the state a run continues from). It runs the four phases of the
        class notes, all cells in one :meth:`write_block`.
        """
        count, cells, shared = self._split_records(records)
        fs = [f for _, f in snapshots]
        plan = self.begin_commit(len(snapshots), count)
        split = "f" in self.cell_arrays
        if split:
            self.write_block(plan, slice(None), f=fs, records=cells)
        self.write_shared(plan, times=[t for t, _ in snapshots], step=progress.get("step"),
                          dt_next=progress.get("dt_next"), records=shared,
                          f=None if split else fs)
        self.end_commit(plan, progress)

    def _split_records(self, records: dict) -> tuple[int, dict, dict]:
        """``(count, cells, shared)`` of a commit's ``records``: how many there are, and
        those of the store's layout (:attr:`record_arrays`) split into the arrays with a
        cells axis (:attr:`cell_arrays`, :meth:`write_block`'s) and the others
        (:meth:`write_shared`'s)."""
        count = len(records["step_time"]) if records else 0
        layout, split = self.record_arrays, self.cell_arrays
        given = {name: values for name, values in records.items() if name in layout} \
            if count else {}
        return (count, {n: v for n, v in given.items() if n in split},
                {n: v for n, v in given.items() if n not in split})

    def begin_commit(self, snapshot_count: int, record_count: int) -> CommitPlan:
        """Open a commit (phase 1 of the class notes; one writer).

        Parameters
        ----------
        snapshot_count, record_count : int
            How many snapshots of f and moment records the commit appends (>= 0).

        Returns
        -------
        CommitPlan
            Where they go, for :meth:`write_block`, :meth:`write_shared` and
            :meth:`end_commit`. Every snapshot array (``snapshot_count`` > 0) and every
            record array (``record_count`` > 0) is resized to hold them: metadata only,
            no chunk file is written.
        """
        for name, value in (("snapshot_count", snapshot_count), ("record_count", record_count)):
            if not is_integer(value) or value < 0:
                reject("RunStore.begin_commit", name, value, "must be a whole number >= 0")
        k, n = self.snapshot_count, int(self.progress["records"])
        plan = CommitPlan(range(k, k + snapshot_count), range(n, n + record_count))
        for names, entries in ((SNAPSHOT_ARRAYS, plan.snapshots),
                               (self.record_arrays, plan.records)):
            for name in names if entries else ():
                array = self.group[name]
                array.resize((entries.stop,) + array.shape[1:])
        return plan

    def write_block(self, plan: CommitPlan, cells: slice, f=None,
                    records: dict | None = None) -> None:
        """Write the cells ``cells`` of a commit's new snapshots and field records (phase 2
        of the class notes; the owner of those cells).

        Only chunk files of these cells are written, so the owners of different blocks
        may write at the same time, in any order.

        Parameters
        ----------
        plan : CommitPlan
            The open commit (:meth:`begin_commit`).
        cells : slice
            The cells a..b (``slice(a, b)``; ``slice(None)`` for all of them). a and b
            must be multiples of the chunk width along ``x`` of every array in
            :attr:`cell_arrays` (b may be the number of cells), so that no chunk file is
            shared with the owner of other cells.
        f : sequence of array_like, optional
            The cells a..b of each new snapshot, shape (b - a, v1, ..., vd); as many as
            the plan has snapshots (none when it has none).
        records : dict, optional
            name -> the cells a..b of the new records of a field, shape
            (records, b - a, ...), for names of :attr:`cell_arrays`. A field left out
            gets no data in this commit, which :meth:`verify` then reports as missing.

        Raises
        ------
        ValueError
            The store has no cells axis, ``cells`` is out of range or misaligned, or
            ``f`` or a record does not match the plan.
        StoreError
            ``plan`` is not the open commit of the store (:meth:`begin_commit` not called).
        """
        owner = "RunStore.write_block"
        _check_plan(owner, plan)
        start, stop = self._block(cells)
        region = (slice(start, stop),)
        names = tuple(n for n in self.cell_arrays if n != "f")
        _write(self._snapshot_writes(owner, plan, f, region)
               + self._record_writes(owner, plan, records, names, region))

    def write_shared(self, plan: CommitPlan, times=(), step: int | None = None,
                     dt_next: float | None = None, records: dict | None = None,
                     f=None) -> None:
        """Write what no block owns (phase 3 of the class notes; one writer).

        Parameters
        ----------
        plan : CommitPlan
            The open commit (:meth:`begin_commit`).
        times : sequence of float
            The times of the new snapshots (``time``), one per snapshot of the plan.
        step : int, optional
            The step index of the new snapshots (``snapshot_step``); needed when the plan
            has snapshots.
        dt_next : float, optional
            The step size proposed after them (``snapshot_dt_next``), the state a run
            continues from; needed when the plan has snapshots.
        records : dict, optional
            name -> the new records of an array without a cells axis, shape
            (records, ...): ``step_time``, ``step``, ``dt``, the moments or totals, the
            wall records. One left out gets no data in this commit, which
            :meth:`verify` then reports as missing.
        f : sequence of array_like, optional
            The new snapshots of f, shape (v1, ..., vd), in a store without a cells axis
            only (in a space run's, :meth:`write_block` writes f).

        Raises
        ------
        ValueError
            An argument does not match the plan or the store.
        StoreError
            ``plan`` is not the open commit of the store (:meth:`begin_commit` not called).
        """
        owner = "RunStore.write_shared"
        _check_plan(owner, plan)
        split = self.cell_arrays
        if "f" in split and f is not None:
            raise ValueError(f"{owner}: parameter 'f' holds {len(f)} snapshot(s); it must be "
                             "None in a store with a cells axis: each block's owner writes "
                             "its cells of f (write_block)")
        writes = [] if "f" in split else self._snapshot_writes(owner, plan, f, ())
        count = len(plan.snapshots)
        times = _shaped(owner, "times", numpy.asarray(times, dtype=float), (count,))
        if count:
            for name, value in (("step", step), ("dt_next", dt_next)):
                if value is None:
                    reject(owner, name, value, f"must be given with the {count} new "
                           "snapshot(s) of the plan: the step and the step size proposed "
                           "after it, from which a run continues")
            where = (slice(plan.snapshots.start, plan.snapshots.stop),)
            writes += [(self._planned(owner, plan, name), where, values) for name, values in
                       (("time", times), ("snapshot_step", int(step)),
                        ("snapshot_dt_next", float(dt_next)))]
        names = tuple(n for n in self.record_arrays if n not in split)
        _write(writes + self._record_writes(owner, plan, records, names, ()))

    def end_commit(self, plan: CommitPlan, progress: dict) -> None:
        """Make a commit visible (phase 4 of the class notes; one writer, after every
        :meth:`write_block` and :meth:`write_shared` of the commit has returned).

        Parameters
        ----------
        plan : CommitPlan
            The open commit (:meth:`begin_commit`).
        progress : dict
            The state of the run (JSON-ready: status, step, time, dt_next, ...), stored
            in the metadata with the new counts of snapshots and records.

        Raises
        ------
        StoreError
            ``plan`` is not the open commit: the store's counts are not where it starts
            (a commit ended twice, or a plan of another commit).
        """
        _check_plan("RunStore.end_commit", plan)
        k, n = self.snapshot_count, int(self.progress["records"])
        if (plan.snapshots.start, plan.records.start) != (k, n):
            reject("RunStore.end_commit", "plan", plan, f"is not the open commit: the store "
                   f"holds {k} snapshots and {n} records, the plan starts at snapshot "
                   f"{plan.snapshots.start} and record {plan.records.start} (a commit is ended "
                   "once; begin_commit opens the next)", error=StoreError)
        self._write_progress(dict(progress, snapshots=plan.snapshots.stop,
                                  records=plan.records.stop))

    def _block(self, cells) -> tuple[int, int]:
        """The first and the end cell of ``cells``, checked against the chunks along ``x``
        of every array of :attr:`cell_arrays`."""
        owner, split = "RunStore.write_block", self.cell_arrays
        if "f" not in split:
            reject(owner, "cells", cells, "has no use: the store has no cells axis (a "
                   "space-homogeneous run); write f and every record with write_shared")
        total = self.group["f"].shape[1]
        if not isinstance(cells, slice) or cells.step not in (None, 1) or not all(
                bound is None or is_integer(bound) for bound in (cells.start, cells.stop)):
            reject(owner, "cells", cells, f"must be a slice a:b of the {total} cells (step 1)")
        start = 0 if cells.start is None else int(cells.start)
        stop = total if cells.stop is None else int(cells.stop)
        if not 0 <= start < stop <= total:
            reject(owner, "cells", cells, f"must be a slice a:b of the {total} cells with "
                   f"0 <= a < b <= {total}")
        for name in split:
            width = self.group[name].chunks[1]
            if start % width or (stop % width and stop != total):
                reject(owner, "cells", cells, f"is not aligned with the blocks of array "
                       f"'{name}', chunked by {width} cells along x ({total} cells): a and b "
                       f"must be multiples of {width} (b may be {total}), so that no chunk "
                       "file is shared with the owner of other cells")
        return start, stop

    def _planned(self, owner: str, plan: CommitPlan, name: str):
        """The array ``name``, checked to be resized by :meth:`begin_commit` for ``plan``."""
        array = self.group[name]
        stop = (plan.snapshots if name in SNAPSHOT_ARRAYS else plan.records).stop
        if array.shape[0] != stop:
            reject(owner, "plan", plan, f"does not fit the store: array '{name}' holds "
                   f"{array.shape[0]} entries, the plan ends at {stop}; a commit's data are "
                   "written after its begin_commit and before its end_commit",
                   error=StoreError)
        return array

    def _snapshot_writes(self, owner: str, plan: CommitPlan, f, region: tuple) -> list:
        """The writes (array, selection, values) of the new snapshots ``f`` of ``plan``,
        cut to ``region`` of the cells, checked."""
        count, given = len(plan.snapshots), 0 if f is None else len(f)
        if given != count:
            raise ValueError(f"{owner}: parameter 'f' holds {given} snapshot(s); it must hold "
                             f"the {count} new snapshot(s) of the plan")
        if not count:
            return []
        array = self._planned(owner, plan, "f")
        shape = _region_shape(array.shape[1:], region)
        return [(array, (index,) + region, _shaped(owner, "f", numpy.asarray(snapshot), shape))
                for index, snapshot in zip(plan.snapshots, f)]

    def _record_writes(self, owner: str, plan: CommitPlan, records: dict | None, names: tuple,
                       region: tuple) -> list:
        """The writes (array, selection, values) of the new ``records`` of ``plan`` (names
        among ``names``), cut to ``region`` of the cells, checked."""
        records = records or {}
        other = sorted(set(records) - set(names))
        if other:
            reject(owner, "records", other, f"must name arrays among {list(names)} (the "
                   f"{'cell' if region else 'shared'} records of this store; the "
                   f"{'shared ones: write_shared' if region else 'cell ones: write_block'})")
        if records and not plan.records:
            reject(owner, "records", sorted(records), "must be empty: the plan has no records")
        where = (slice(plan.records.start, plan.records.stop),) + region
        writes = []
        for name, values in records.items():
            array = self._planned(owner, plan, name)
            shape = (len(plan.records),) + _region_shape(array.shape[1:], region)
            writes.append((array, where, _shaped(owner, f"records['{name}']",
                                                 numpy.asarray(values), shape)))
        return writes

    def commit_together(self, communicator, cells: slice, snapshots, records: dict,
                        progress: dict) -> None:
        """One commit of a space run written by all its processes
        (:class:`granframe.abc.Communicator`; a serial run is the case of one): the four
        phases of the class notes, collective.

        Process 0, the holder of the writer lock, begins the commit and sends the plan;
        every process writes its ``cells`` (whole chunks: the range it owns) of the new
        snapshots of f and of the field records (:meth:`write_block`); once all have
        written, process 0 writes the shared records and ends the commit. A write that
        fails in any process fails the commit in all of them, before it is made visible
        (:class:`StoreError` naming the process), so the store keeps its last commit.

        Parameters
        ----------
        communicator : granframe.abc.Communicator
        cells : slice
            The cells this process owns.
        snapshots : list of (float, array_like)
            The new snapshots (t, f of ``cells``), the same times in every process.
        records : dict
            name -> new records: those of the cells axis for ``cells``, the others (the
            same in every process) for the whole interval.
        progress : dict
            As for :meth:`end_commit` (process 0's counts).
        """
        count, owned, shared = self._split_records(records)
        plan = collective(communicator, lambda: self.begin_commit(len(snapshots), count))
        try:
            if communicator.rank != 0:       # the arrays were resized by process 0
                self.group = zarr.open_group(str(self.path), mode="r+", use_consolidated=False)
            self.write_block(plan, cells, f=[f for _, f in snapshots], records=owned)
            failure = None
        except Exception as exc:      # reported to every process below
            failure = f"process {communicator.rank}: {type(exc).__name__}: {exc}"
        failures = [f for f in communicator.allgather_object(failure) if f]
        if failures:
            raise StoreError(f"store '{self.path}': the commit was not made, the store keeps "
                             f"its last one ({'; '.join(failures)})")

        def end():
            self.write_shared(plan, times=[t for t, _ in snapshots], step=progress.get("step"),
                              dt_next=progress.get("dt_next"), records=shared)
            self.end_commit(plan, progress)

        collective(communicator, end)

    def mark(self, status: str, **extra) -> None:
        """Set the status of the last commit (e.g. 'interrupted'), adding no data."""
        self._write_progress(dict(self.progress, status=status, **extra))

    def _write_progress(self, progress: dict) -> None:
        meta = self.metadata
        meta["progress"] = progress
        meta["updated"] = _now()
        self.group.attrs["granframe"] = meta
        consolidate(self.location)


def collective(communicator, function):
    """``function()`` run by process 0 alone, its value or its exception broadcast to every
    process, where it is returned or raised: so that a store operation made by process 0
    (which holds the writer lock) stops every process at the same point when it fails."""
    outcome = None
    if communicator.rank == 0:
        try:
            outcome = ("value", function())
        except Exception as exc:      # raised in every process below
            outcome = ("error", exc)
    kind, value = communicator.bcast(outcome)
    if kind == "error":
        raise value
    return value


def _check_creatable(path: pathlib.Path, overwrite: bool, protect) -> None:
    kind = store_kind(path)
    if kind in ("run", "sweep") and not overwrite:
        raise StoreExistsError(f"store '{path}' exists; pass --resume to continue the run it "
                               "holds, or --overwrite to replace it")
    if kind in ("file", "other") and not overwrite:
        raise StoreError(f"'{path}' exists and is not a granframe store; choose another --out")
    check_replaceable(path, protect)


def _create(group, name, shape, chunks, dtype, dimension_names, space=False):
    return group.create_array(name, shape=shape, chunks=chunks, dtype=dtype,
                              fill_value=fill_value(dtype), dimension_names=dimension_names,
                              attributes=array_attributes(name, space), **codecs())


def _check_plan(owner: str, plan) -> None:
    if not isinstance(plan, CommitPlan):
        reject(owner, "plan", plan, "must be the CommitPlan that begin_commit returned")


def _write(writes: list) -> None:
    """Each (array, selection, values) of ``writes``, checked beforehand: nothing is written
    when an argument is refused."""
    for array, selection, values in writes:
        array[selection] = values


def _region_shape(shape: tuple, region: tuple) -> tuple:
    """``shape`` with its first axes cut to the slices (start and stop given) of ``region``."""
    return tuple(s.stop - s.start for s in region) + tuple(shape[len(region):])


def _shaped(owner: str, parameter: str, values: numpy.ndarray, shape: tuple) -> numpy.ndarray:
    """``values``, refused unless of ``shape`` (zarr would broadcast some shapes)."""
    if values.shape != tuple(shape):
        raise ValueError(f"{owner}: parameter '{parameter}' has shape {values.shape}; it must "
                         f"have shape {tuple(shape)} (the plan's entries, the cells written, "
                         "then the array's own dimensions)")
    return values


def _problem(name, array, index, kind, detail="") -> dict:
    return {"array": name, "chunk": list(index), "first": index[0] * array.chunks[0],
            "kind": kind, "detail": detail}


def summarise(problems) -> str:
    """The first few problems of :meth:`RunStore.verify`, in words."""
    shown = [f"{p['kind']} chunk {p['array']}/c/{'/'.join(map(str, p['chunk']))}"
             if p["chunk"] else f"{p['kind']} {p['array']}" for p in problems[:3]]
    return ", ".join(shown) + (f" and {len(problems) - 3} more" if len(problems) > 3 else "")


def _differences(a, b, prefix=""):
    """Dotted keys where two nested dicts differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            yield from _differences(a.get(key), b.get(key), f"{prefix}{key}.")
    elif a != b:
        yield prefix.rstrip(".") or "(root)"


def _cells(index: int, block: int) -> str:
    """The cells of block ``index`` of a space run's f (chunked by block), in words."""
    return f", block {index}: cells {index * block}..{(index + 1) * block - 1}"


def check(path) -> tuple[bool, list[str]]:
    """Read every committed chunk of a run store, or of every run of a sweep store.

    Returns (intact, report lines); ``granframe check`` prints the lines and exits 3
    when the store is damaged.
    """
    path = pathlib.Path(path)
    kind = store_kind(path)
    if kind == "sweep":
        runs = sorted(p for p in (path / "runs").iterdir() if not p.name.startswith(".")) \
            if (path / "runs").is_dir() else []
        lines, intact = [f"sweep store {path}: {len(runs)} run stores"], True
        for run in [r for r in runs if store_kind(r) != "run"]:
            intact = False
            lines.append(f"  damaged: runs/{run.name} is not a readable run store")
        runs = [r for r in runs if store_kind(r) == "run"]
        if (path / "table" / "zarr.json").is_file():
            table = zarr.open_group(str(path / "table"), mode="r", use_consolidated=False)
            for name in sorted(table.array_keys()):
                try:
                    table[name][:]
                except Exception as exc:   # any decoding failure is damage
                    intact = False
                    lines.append(f"  damaged: table/{name}: {exc}")
        for run in runs:
            ok, more = check(run)
            intact &= ok
            lines += ["  " + line for line in more]
        return intact, lines
    try:
        store = RunStore.open(path)
    except StoreDamagedError:
        store = RunStore(path, zarr.open_group(str(path), mode="r", use_consolidated=False))
    problems = store.verify()
    progress = store.progress
    chunks = sum(sum(1 for _ in _chunk_grid(store.group[n], store._extent(n)))
                 for n in store._names())
    lines = [f"{path}: status {progress.get('status')}, {store.snapshot_count} snapshots, "
             f"{progress.get('records')} records; {chunks} committed chunks read, "
             f"{len(problems)} problems"]
    block = (store.metadata.get("space") or {}).get("block_cells")
    lines += [f"  {p['kind']}: {p['array']}" + (
        f"/c/{'/'.join(map(str, p['chunk']))} (from entry {p['first']}"
        + (_cells(p["chunk"][1], block) if block and p["array"] == "f" else "") + ")"
        if p["chunk"] else "")
        + (f": {p['detail']}" if p["detail"] else "") for p in problems]
    partial = sorted(str(p.relative_to(path)) for p in path.rglob("*.partial"))
    if partial:
        lines.append(f"  {len(partial)} file(s) of a write cut short (removed on --resume): "
                     + ", ".join(partial[:3]))
    stray = stray_entries(path)
    if stray:
        lines.append(f"  {len(stray)} entr{'y' if len(stray) == 1 else 'ies'} that no run "
                     f"writes (ignored; left by a write cut short, or added by hand): "
                     + ", ".join(stray[:3]))
    return not problems, lines


def dropped_note(metadata: dict) -> str | None:
    """The moment records a rollback dropped (the metadata's ``dropped_records``), in
    words; None when it dropped none."""
    dropped = metadata.get("dropped_records")
    if not dropped:
        return None
    return "dropped the moment records of damaged chunks: " + "; ".join(
        f"{d['array']} {d['first']} .. {d['first'] + d['count'] - 1} ("
        + ("written again: record i is step i" if d["array"] == "step" else "now NaN") + ")"
        for d in dropped)


def stray_entries(path) -> list[str]:
    """The directories at the top of the run store ``path`` that are not zarr arrays or
    groups (no ``zarr.json``), which every read ignores."""
    path = pathlib.Path(path)
    return sorted(p.name for p in path.iterdir()
                  if p.is_dir() and not (p / "zarr.json").is_file())


def _named(component: dict) -> str:
    """A reconstruction or boundary of a description's ``space`` section as
    ``name(key=value, ...)``."""
    params = ", ".join(f"{key}={value}" for key, value in component.items() if key != "name")
    return component["name"] + (f"({params})" if params else "")


def _describe_space(meta: dict, group, n: int) -> list[str]:
    """The lines of :func:`describe` for the first ``n`` records of a space run's store:
    the interval, its blocks and walls; the range over the cells of T(x) and rho(x) at the
    first and the last record; the totals; what entered through each wall, and the
    balance m(t) - m(0) - (mass entered) of the records."""
    space, section = meta["space"], meta["description"]["space"]
    cells, length, block = space["cells"], space["length"], space["block_cells"]
    lines = [f"space       {cells} cells on [0, {length:g}] (dx = {length / cells:.6g}), "
             f"{cells // block} blocks of {block} cells, reconstruction "
             f"{_named(section.get('reconstruction', {'name': 'muscl'}))}, walls: left "
             f"{_named(section.get('left', {'name': 'periodic'}))}, right "
             f"{_named(section.get('right', {'name': 'periodic'}))}"]
    for name, label in (("temperature", "T(x)"), ("density", "rho(x)")):
        first, last = group[name][0], group[name][n - 1]
        lines.append(f"  {label:<12s}in [{numpy.nanmin(first):.6g}, {numpy.nanmax(first):.6g}] "
                     f"-> [{numpy.nanmin(last):.6g}, {numpy.nanmax(last):.6g}] (over the cells)")
    entered = {name: group[name][:n].sum(axis=0) for name in ("wall_mass", "wall_energy")}
    for name, wall, label in (("mass", "wall_mass", "mass"),
                              ("kinetic_energy", "wall_energy", "energy")):
        first, last = group[name][[0, n - 1]]
        inflow = entered[wall].sum()
        lines.append(f"  {label:<12s}{first:.10g} -> {last:.10g} (drift "
                     f"{last / first - 1:+.2e}; entered through the walls {inflow:+.3e}, "
                     f"balance {last - first - inflow:+.2e})")
    values = group["min_f"][[0, n - 1]]
    lines.append(f"  {'min_f':<12s}{values[0]:.10g} -> {values[1]:.10g}")
    for wall, what in (("wall_mass", "mass"), ("wall_energy", "energy")):
        left, right = entered[wall]
        lines.append(f"  {what} entered through the left wall {left:+.6e}, the right wall "
                     f"{right:+.6e} (sums over the steps)")
    return lines


def describe(path) -> str:
    """Human-readable summary of a store (``granframe info``)."""
    store = RunStore.open(path)
    problems = store.verify([n for n in store._names() if n != "f"])
    if problems:
        raise StoreDamagedError(f"store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
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
        if "space" in meta:
            lines.extend(_describe_space(meta, group, n))
        else:
            for name in ("mass", "temperature", "kurtosis", "min_f"):
                values = group[name][[0, n - 1]]
                lines.append(f"  {name:<12s}{values[0]:.10g} -> {values[1]:.10g}")
    note = dropped_note(meta)
    if note:
        lines.append(f"rollback    {note}")
    resolution = progress.get("resolution")
    if resolution:
        lines.append(f"resolution  at t = {progress['time']:g} (the last commit): spectral tail "
                     f"{resolution['spectral_tail']:.3g} (estimated error "
                     f"{resolution['tail_error']:.3g}), negative mass share "
                     f"{resolution['negative_mass_fraction']:.3g}, share of pairs beyond 2S "
                     f"{resolution['pairs_beyond_support']:.3g}")
        if "cells" in resolution:           # a space run: the worst cell of each indicator
            lines.append("  worst cells " + ", ".join(
                f"{name} {resolution[name]:.3g} in cell {cell} (x = {resolution['x'][name]:.4g})"
                for name, cell in resolution["cells"].items()))
        lines.extend(f"  warning: {warning}" for warning in resolution["warnings"])
    if progress.get("accuracy"):
        from granframe.run.monitors import describe as describe_accuracy

        lines.extend(describe_accuracy(progress["accuracy"], progress["time"]))
    if meta.get("f0_projection"):
        lines.append("f0 projection (moments before -> after; the run starts after)")
        for name, m in meta["f0_projection"].items():
            lines.append(f"  {name:<12s}{m['before']:.10g} -> {m['after']:.10g}")
    provenance = meta.get("provenance", {})
    if provenance:
        lines.append("provenance")
        width = max(len(key) for key in provenance) + 2
        for key, value in provenance.items():
            lines.append(f"  {key:<{width}s}{value}")
    lines.append("description (TOML)")
    lines.extend("  " + line for line in meta["description_toml"].strip().splitlines())
    return "\n".join(lines)
