"""Appending to a run store: a commit of snapshots of f and moment records, in four phases.

A commit is planned (:class:`CommitPlan`), written block by block and then what no block
owns, and made visible by one write of ``progress`` (the notes of
:class:`StoreCommits`). :meth:`StoreCommits.commit_together` runs the four phases with
every process of a space run writing its own cells (:func:`collective` for what process
0, the holder of the writer lock, does alone); :meth:`StoreCommits.commit` is its
one-process case.
"""

from __future__ import annotations

import functools

import attrs
import numpy
import zarr

from granframe.parallel import SerialCommunicator, raised_everywhere
from granframe.run.storage.errors import StoreError
from granframe.run.storage.schema import CELL_AXES, SNAPSHOT_ARRAYS
from granframe.run.storage.state import StoreState
from granframe.validators import is_integer, reject


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
        raise raised_everywhere(value)
    return value


class StoreCommits(StoreState):
    """The commits of a run store opened for writing (the base of
    :class:`~granframe.run.storage.RunStore`, which opens it).

    Notes
    -----
    A commit appends snapshots of f and moment records and makes them visible at once.
    :meth:`commit` (one process) and :meth:`commit_together` (every process its cells)
    do it in one call, as four phases which several writers can share when the store has
    a cells axis (a space run, whose f and fields are chunked by block of cells:
    :attr:`cell_arrays`):

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
    ``progress``, and :meth:`~granframe.run.storage.RunStore.resume` drops whatever lies
    beyond them, so a commit cut short in any phase, with its blocks written in any order
    or some not at all, is never seen. zarr writes each chunk file whole, to a temporary
    file renamed into place, so a kill leaves every file old or new.

    A writer in another process writes its blocks into a store on disk that it opens
    with ``RunStore.open(path, mode="r+")`` (it takes no lock: it writes under the lock
    of the writer that begins and ends the commits), with the plan that writer sends
    it. ``path`` is where the store is then: a new store is staged beside its final
    path until :meth:`~granframe.run.storage.RunStore.publish` puts it in place after
    its first commit, so the other writers open it again after that.

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

    @functools.cached_property
    def cell_arrays(self) -> tuple:
        """The arrays split by cells, which :meth:`write_block` writes: those whose first
        dimension after ``time`` or ``step_time`` is the cells axis (:data:`CELL_AXES`; a
        space run's f and fields); empty in a space-homogeneous run's store."""
        def split(name):
            dimensions = tuple(self.group[name].metadata.dimension_names or ())
            return len(dimensions) > 1 and dimensions[1] in CELL_AXES

        return tuple(filter(split, SNAPSHOT_ARRAYS[:1] + self.record_arrays))

    def commit(self, snapshots, records: dict, progress: dict) -> None:
        """Append snapshots [(t, f)] and moment records (name -> arrays along step_time),
        then mark them.

        Records that the store's layout lacks (:attr:`record_arrays`: the pressure tensor
        and heat flux of a store written before granframe recorded them) are left out.
        ``progress`` (JSON-ready) is stored together with the new counts; the
        store is consistent before and after, whatever happens in between. Each
        snapshot is stored with the step and the proposed next step size of
        ``progress`` (the state a run continues from). It is :meth:`commit_together` of
        one process (:class:`~granframe.parallel.SerialCommunicator`) owning every cell.
        """
        self.commit_together(SerialCommunicator(), slice(None), snapshots, records, progress)

    def commit_together(self, communicator, cells: slice, snapshots, records: dict,
                        progress: dict) -> None:
        """One commit written by all the processes of a run
        (:class:`granframe.abc.Communicator`; a serial run is the case of one): the four
        phases of the class notes, collective.

        Process 0, the holder of the writer lock, begins the commit and sends the plan;
        every process writes its ``cells`` (whole chunks: the range it owns) of the new
        snapshots of f and of the field records (:meth:`write_block`); once all have
        written, process 0 writes the shared records and ends the commit. A write that
        fails in any process fails the commit in all of them, before it is made visible
        (:class:`StoreError` naming the process), so the store keeps its last one. In a
        store without a cells axis (a space-homogeneous run) no process writes a block:
        process 0 writes f with the shared records, and ``cells`` is ``slice(None)``.

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
        fs = [f for _, f in snapshots]
        split = "f" in self.cell_arrays
        plan = collective(communicator, lambda: self.begin_commit(len(snapshots), count))
        self._write_cells(communicator, plan, cells, fs, owned)

        def end():
            self.write_shared(plan, times=[t for t, _ in snapshots], step=progress.get("step"),
                              dt_next=progress.get("dt_next"), records=shared,
                              f=None if split else fs)
            self.end_commit(plan, progress)

        collective(communicator, end)

    def _write_cells(self, communicator, plan: CommitPlan, cells: slice, f,
                     records: dict) -> None:
        """Phase 2 of :meth:`commit_together` in every process: :meth:`write_block` of its
        ``cells`` of the snapshots ``f`` and of the field ``records``, skipped in a store
        without a cells axis when ``cells`` is ``slice(None)``. A write that fails in any
        process raises :class:`StoreError` in all, naming each failure."""
        try:
            if communicator.rank != 0:       # the arrays were resized by process 0
                self.group = zarr.open_group(str(self.path), mode="r+", use_consolidated=False)
            if "f" in self.cell_arrays or cells != slice(None):
                self.write_block(plan, cells, f=f, records=records)
            failure = None
        except Exception as exc:      # reported to every process below
            failure = f"process {communicator.rank}: {type(exc).__name__}: {exc}"
        failures = [text for text in communicator.allgather_object(failure) if text]
        if failures:
            raise StoreError(f"store '{self.path}': the commit was not made, the store keeps "
                             f"its last one ({'; '.join(failures)})")

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
        cells : slice or tuple of slice
            The cells a..b (``slice(a, b)``; ``slice(None)`` for all of them); on a
            rectangle a slice along each cell axis (x, y), the block a process owns. a and
            b must be multiples of the chunk width along that axis of every array in
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
        region = self._region(cells)
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
        writes += self._snapshot_entry_writes(owner, plan, times, step, dt_next)
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

    def _region(self, cells) -> tuple:
        """The slices of ``cells`` (one slice: along the first cell axis; a tuple of
        slices: along each cell axis of a rectangle), checked by :meth:`_block`."""
        if not isinstance(cells, tuple):
            return (slice(*self._block(cells)),)
        axes = self._cell_axes()
        if len(cells) != axes:
            reject("RunStore.write_block", "cells", cells, f"must give a slice for each of "
                   f"the {axes} cell axes of the store")
        return tuple(slice(*self._block(part, axis)) for axis, part in enumerate(cells))

    def _cell_axes(self) -> int:
        """How many cell axes f has after ``time`` (1 on an interval, 2 on a rectangle)."""
        dimensions = tuple(self.group["f"].metadata.dimension_names or ())
        return sum(1 for name in dimensions[1:] if name in CELL_AXES)

    def _block(self, cells, axis: int = 0) -> tuple[int, int]:
        """The first and the end cell of ``cells`` along the cell axis ``axis``, checked
        against the chunks along that axis of every array of :attr:`cell_arrays`."""
        owner, split = "RunStore.write_block", self.cell_arrays
        if "f" not in split:
            reject(owner, "cells", cells, "has no use: the store has no cells axis (a "
                   "space-homogeneous run); write f and every record with write_shared")
        total = self.group["f"].shape[1 + axis]
        if not isinstance(cells, slice) or cells.step not in (None, 1) or not all(
                bound is None or is_integer(bound) for bound in (cells.start, cells.stop)):
            reject(owner, "cells", cells, f"must be a slice a:b of the {total} cells (step 1)")
        start = 0 if cells.start is None else int(cells.start)
        stop = total if cells.stop is None else int(cells.stop)
        if not 0 <= start < stop <= total:
            reject(owner, "cells", cells, f"must be a slice a:b of the {total} cells with "
                   f"0 <= a < b <= {total}")
        for name in split:
            width = self.group[name].chunks[1 + axis]
            if start % width or (stop % width and stop != total):
                reject(owner, "cells", cells, f"is not aligned with the blocks of array "
                       f"'{name}', chunked by {width} cells along {CELL_AXES[axis]} "
                       f"({total} cells): a and b "
                       f"must be multiples of {width} (b may be {total}), so that no chunk "
                       "file is shared with the owner of other cells")
        return start, stop

    def _planned(self, owner: str, plan: CommitPlan, name: str):
        """The array ``name``, checked to be resized by :meth:`begin_commit` for ``plan``,
        writing every chunk it is given, those all at the fill value too (zarr leaves those
        out by default, and a committed chunk that is not there reads as damage: the
        hierarchy's indicators are NaN in the first record)."""
        array = self.group[name].with_config({"write_empty_chunks": True})
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

    def _snapshot_entry_writes(self, owner: str, plan: CommitPlan, times, step, dt_next) -> list:
        """The writes (array, selection, values) of the time, step and proposed step size
        of the new snapshots of ``plan`` (``time``, ``snapshot_step``,
        ``snapshot_dt_next``), checked."""
        count = len(plan.snapshots)
        times = _shaped(owner, "times", numpy.asarray(times, dtype=float), (count,))
        if not count:
            return []
        for name, value in (("step", step), ("dt_next", dt_next)):
            if value is None:
                reject(owner, name, value, f"must be given with the {count} new "
                       "snapshot(s) of the plan: the step and the step size proposed "
                       "after it, from which a run continues")
        where = (slice(plan.snapshots.start, plan.snapshots.stop),)
        return [(self._planned(owner, plan, name), where, values) for name, values in
                (("time", times), ("snapshot_step", int(step)),
                 ("snapshot_dt_next", float(dt_next)))]

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
