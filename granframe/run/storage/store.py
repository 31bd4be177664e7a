"""The run store: a run's zarr store opened for writing or reading.

:class:`RunStore` opens a store, new (:meth:`RunStore.create`, staged beside its path
until :meth:`RunStore.publish` puts it in place), continued (:meth:`RunStore.resume`) or
read (:meth:`RunStore.open`), holding the writer lock while it writes. What it reads of
an open store and its checks come from :class:`~granframe.run.storage.state.StoreState`,
its commits from :class:`~granframe.run.storage.commits.StoreCommits`; the safety of its
path from :mod:`~granframe.run.storage.paths` and the cut back of a resumed store from
:mod:`~granframe.run.storage.resumption`.
"""

from __future__ import annotations

import os
import pathlib
import shutil
import uuid

import zarr

from granframe._version import __version__
from granframe.run.storage.commits import StoreCommits
from granframe.run.storage.errors import StoreDamagedError, StoreError
from granframe.run.storage.integrity import summarise
from granframe.run.storage.layout import Layout, homogeneous_layout
from granframe.run.storage.locks import WriterLock
from granframe.run.storage.paths import (STAGING, TRASH, check_creatable, recover, sibling,
                                         siblings, store_kind)
from granframe.run.storage.resumption import prepare
from granframe.run.storage.schema import SCHEMA, now, root_attributes


class RunStore(StoreCommits):
    """A run's store, opened for writing (:meth:`create`, :meth:`resume`) or reading (:meth:`open`).

    A store opened for writing holds the :class:`WriterLock` until :meth:`close`. A store
    created with ``path`` None is held in memory (a :class:`zarr.storage.MemoryStore`):
    the same layout, commits and metadata, no file, no lock; its ``path`` is None. Its
    commits (:meth:`commit`, :meth:`commit_together` and their four phases) are those of
    :class:`~granframe.run.storage.commits.StoreCommits`, whose notes describe them.

    Parameters
    ----------
    path : str, os.PathLike or None
        Where the store is (None: in memory).
    group : zarr.Group
        Its root group.
    lock : WriterLock or None
        The lock a writer holds on ``path``.
    """

    def __init__(self, path, group: zarr.Group, lock: WriterLock | None = None):
        super().__init__(path, group)
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
        layout = homogeneous_layout(grid) if layout is None else layout
        meta = _new_metadata(layout, description, description_toml, provenance, rescaling,
                             projection)
        if path is None:
            group = zarr.create_group(zarr.storage.MemoryStore(), zarr_format=3)
            return cls(None, _initialised(group, layout, meta))
        return cls._staged(pathlib.Path(path), overwrite, protect, layout, meta)

    @classmethod
    def _staged(cls, path: pathlib.Path, overwrite: bool, protect, layout: Layout,
                meta: dict) -> "RunStore":
        """A new store of ``layout`` and ``meta`` staged beside ``path`` under its writer
        lock, for :meth:`publish` to put in place (:meth:`create`)."""
        check_creatable(path, overwrite, protect)   # refused before anything is written
        lock, staging = WriterLock(path).acquire(), None
        try:
            recover(path)
            kind = store_kind(path)
            check_creatable(path, overwrite, protect)
            token = uuid.uuid4().hex[:12]
            staging = sibling(path, STAGING, token)
            group = _initialised(zarr.create_group(str(staging), zarr_format=3), layout, meta)
        except BaseException:
            if staging is not None:
                shutil.rmtree(staging, ignore_errors=True)
            lock.release()
            raise
        store = cls(staging, group, lock)
        store._target, store._token, store._old = path, token, kind in ("run", "sweep")
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
        trash = sibling(target, TRASH, self._token)
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
            not os.path.lexists(path) and bool(siblings(path, TRASH)))

    @classmethod
    def open(cls, path, mode: str = "r", complete: bool = True) -> "RunStore":
        """An existing run store (``mode`` 'r' or 'r+').

        ``complete``: refuse a store with a committed chunk missing
        (:class:`StoreDamagedError`).
        """
        path = pathlib.Path(path)
        if not path.exists():
            if siblings(path, TRASH):
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
        missing = store.verify(read=False) if complete else store.absent_arrays()
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
            prepare(store, path, description, rollback)
        except BaseException:
            lock.release()
            raise
        return store

    def close(self) -> None:
        """Release the writer lock (a store opened for writing)."""
        if self.lock is not None:
            self.lock.release()


def _new_metadata(layout: Layout, description: dict, description_toml: str, provenance: dict,
                  rescaling: dict | None, projection: dict | None) -> dict:
    """The ``granframe`` metadata of a new store of ``layout`` (:meth:`RunStore.create`)."""
    return {
        "schema": SCHEMA, "version": __version__, "description": description,
        "record_arrays": [spec.name for spec in layout.records],
        **({} if layout.space is None else {
            "coordinate_arrays": [name for name, _, _ in layout.coordinates],
            "space": layout.space}),
        "description_toml": description_toml, "provenance": provenance,
        "created": now(),
        "progress": {"snapshots": 0, "records": 0, "status": "created"},
        **({} if rescaling is None else {"rescaling": rescaling}),
        **({} if projection is None else {"f0_projection": projection}),
    }


def _initialised(group: zarr.Group, layout: Layout, meta: dict) -> zarr.Group:
    """``group`` with the (empty) arrays of ``layout`` and the root attributes of ``meta``
    (the CF ones beside granframe's own, in one write)."""
    layout.create(group)
    group.attrs.put({**root_attributes(meta), "granframe": meta})
    return group
