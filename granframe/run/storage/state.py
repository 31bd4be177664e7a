"""An open run store's state: its group and metadata, what is committed, and its progress.

:class:`StoreState` is what every part of a :class:`~granframe.run.storage.RunStore`
reads: the metadata and ``progress`` in the root attributes, the record and coordinate
arrays of its layout, how many entries of each array are committed (:meth:`~StoreState.extent`),
the checks of those entries (:meth:`~StoreState.verify`), and the write of ``progress``
that ends a commit or sets a run's status (:meth:`~StoreState.mark`).
"""

from __future__ import annotations

import pathlib

import zarr

from granframe.run.storage.errors import StoreError
from granframe.run.storage.integrity import absent_arrays, chunk_problems
from granframe.run.storage.layout import consolidate
from granframe.run.storage.schema import FIRST_RECORD_ARRAYS, SNAPSHOT_ARRAYS, now


class StoreState:
    """A run store's root group and what its metadata says is committed.

    Parameters
    ----------
    path : str, os.PathLike or None
        Where the store is (None: in memory).
    group : zarr.Group
        Its root group.
    """

    def __init__(self, path, group: zarr.Group):
        self.path = None if path is None else pathlib.Path(path)
        self.group = group

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
        d = len(self.group["f"].shape) - 1 if "f" in self.array_names() else \
            int(self.metadata["description"]["grid"]["dimension"])
        return tuple(f"v{i + 1}" for i in range(d))

    @property
    def location(self):
        """Where zarr finds the store: its path, or the in-memory zarr store."""
        return self.group.store if self.path is None else self.path

    @property
    def snapshot_count(self) -> int:
        return int(self.progress["snapshots"])

    def last_snapshot(self, cells=None):
        """(f, t) of the last committed snapshot, f as a NumPy array; ``cells``: only those
        cells of a space run's f (the range a process owns, a slice; on a rectangle the
        block, a slice per axis), read from their chunks."""
        k = self.snapshot_count
        if k == 0:
            raise StoreError(f"store '{self.path}' has no complete snapshot to resume from")
        f = self.group["f"]
        where = (k - 1,) + (cells if isinstance(cells, tuple) else (cells,))
        return (f[k - 1] if cells is None else f[where],
                float(self.group["time"][k - 1]))

    def array_names(self) -> list[str]:
        """The names of the arrays in the store, sorted."""
        return sorted(self.group.array_keys())

    def extent(self, name: str) -> int:
        """Committed entries of the array ``name`` along its first axis."""
        if name in SNAPSHOT_ARRAYS:
            return self.snapshot_count
        if name in self.record_arrays:
            return int(self.progress["records"])
        return self.group[name].shape[0]

    def absent_arrays(self) -> list[dict]:
        """Arrays of the layout that are not in the store at all (as :meth:`verify` lists
        them)."""
        expected = SNAPSHOT_ARRAYS + self.record_arrays + self.coordinate_arrays
        return absent_arrays(expected, self.array_names())

    def verify(self, names=None, snapshots=None, read: bool = True) -> list[dict]:
        """Every committed chunk of ``names`` (default: all arrays) read and checked.

        Returns the problems, each a dict: array, chunk (index), first (first entry along
        the first axis), kind ('missing array', 'missing' or 'damaged') and detail.
        ``snapshots`` limits the chunks of ``f`` read to those indices; ``read`` False
        only checks that the chunks are on disk.
        """
        problems = self.absent_arrays() if names is None else []
        for name in names or self.array_names():
            problems += chunk_problems(name, self.group[name], self.path, self.extent(name),
                                       read, snapshots if name == "f" else None)
        return problems

    def mark(self, status: str, **extra) -> None:
        """Set the status of the last commit (e.g. 'interrupted'), adding no data."""
        self._write_progress(dict(self.progress, status=status, **extra))

    def _write_progress(self, progress: dict) -> None:
        meta = self.metadata
        meta["progress"] = progress
        meta["updated"] = now()
        self.group.attrs["granframe"] = meta
        consolidate(self.location)
