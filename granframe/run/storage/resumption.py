"""Resuming a run store: what may be continued, and the store cut back to a commit to continue from.

A store is resumed only for the description it holds and a status that may be continued
(:func:`check_resumable`). It is then cut back to its last commit, dropping what a commit
cut short left (:func:`truncate`), and what the run continues from is checked: the last
snapshot and the moment records must be intact, or, when asked, the store is rolled back
to its last intact commit, the records of damaged chunks dropped (:func:`roll_back`).
"""

from __future__ import annotations

import math
import pathlib

import numpy

from granframe.run.storage.errors import StoreDamagedError, StoreError
from granframe.run.storage.integrity import chunk_file, chunk_grid, summarise
from granframe.run.storage.layout import fill_value
from granframe.run.storage.schema import RESUMABLE, SNAPSHOT_ARRAYS


def differences(a, b, prefix=""):
    """Dotted keys where two nested dicts differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            yield from differences(a.get(key), b.get(key), f"{prefix}{key}.")
    elif a != b:
        yield prefix.rstrip(".") or "(root)"


def check_resumable(store, path, description: dict) -> str:
    """The status of the run in ``store`` (at ``path``), refused (:class:`StoreError`)
    unless the store holds a run of ``description`` with a status that may be resumed or
    'finished'."""
    stored = store.metadata["description"]
    if stored != description:
        changed = sorted(differences(stored, description))
        raise StoreError(f"store '{path}' holds a run of another description (differs "
                         f"in: {', '.join(changed)}); it is never appended to: "
                         "choose another --out, or --overwrite to replace it")
    status = store.progress.get("status")
    if status == "failed":
        raise StoreError(f"store '{path}' holds a run stopped by a health check "
                         f"({store.progress.get('message')}); resuming would fail "
                         "again: change the description and start afresh")
    if status not in RESUMABLE + ("finished",):
        raise StoreError(f"store '{path}' has status '{status}', which cannot be "
                         f"resumed (resumable: {', '.join(RESUMABLE)})")
    return status


def prepare(store, path, description: dict, rollback: bool) -> None:
    """Make ``store`` (at ``path``, its writer lock held) ready to continue the run of
    ``description``: checked (:func:`check_resumable`), the files of writes a kill cut
    short removed, cut back to its last commit (:func:`truncate`) and, unless the run
    finished, checked to continue from intact data (:func:`roll_back`); a finished run
    with ``rollback`` is checked whole (every snapshot of f, as ``granframe check``) and,
    where damaged, taken back to the snapshot before the first damage, from which the
    run is made again: the store ends finished and intact."""
    status = check_resumable(store, path, description)
    for partial in pathlib.Path(path).rglob("*.partial"):   # writes cut by a kill
        partial.unlink()
    truncate(store)
    if status != "finished":
        roll_back(store, rollback)
    elif rollback:           # a finished run is taken back only where it is damaged
        roll_back(store, rollback, whole=True)


def truncate(store) -> None:
    """Drop whatever lies beyond the last commit (a commit cut short).

    Chunk files wholly beyond it are deleted too, so that no stale chunk is ever
    merged into a later write.
    """
    for name in SNAPSHOT_ARRAYS + store.record_arrays:
        array = store.group[name]
        extent = store.extent(name)
        if array.shape[0] != extent:
            first_gone = math.ceil(extent / array.chunks[0])
            for index in chunk_grid(array, array.shape[0]):
                if index[0] >= first_gone:
                    chunk_file(store.path, name, index).unlink(missing_ok=True)
            array.resize((extent,) + array.shape[1:])


def roll_back(store, rollback: bool, whole: bool = False) -> None:
    """Check what a resumed run reads; roll back to the last intact commit if asked.

    The run continues from the last snapshot whose f and snapshot entries are intact.
    A damaged chunk of the moment records before it does not stop that: with
    ``rollback`` its records are dropped (NaN; the step numbers, record i being step i,
    are written again) and listed in the metadata's ``dropped_records``
    (:func:`~granframe.run.storage.describe` shows them). Without ``rollback``, any
    damage raises :class:`StoreDamagedError` naming the last intact commit. With
    ``whole`` every snapshot of f is checked, and the run continues from the last snapshot
    before the first damaged one.
    """
    k = store.snapshot_count
    intact, problems = _last_intact(store, whole)
    if not problems:
        return
    if intact is None:
        raise StoreDamagedError(f"store '{store.path}' is damaged ({summarise(problems)}) and "
                                "holds no intact commit to continue from; start afresh with "
                                "--overwrite", problems)
    t = float(store.group["time"][intact])
    step = int(store.group["snapshot_step"][intact])
    records = [p for p in problems if p["array"] in store.record_arrays
               and p["first"] <= step and p["kind"] != "missing array"]
    dropped = [drop_records(store, p["array"], tuple(p["chunk"]), step + 1) for p in records]
    if not rollback:
        lost = (f"; the moment records of the damaged chunks ({sum(d['count'] for d in dropped)}"
                " records) are dropped (NaN)" if dropped else "")
        raise StoreDamagedError(
            f"store '{store.path}' is damaged ({summarise(problems)}); the last intact commit "
            f"is snapshot {intact} at t = {t:.6g} (step {step}): run again with --resume "
            f"--rollback to continue from it (the {k - 1 - intact} snapshots after it are "
            f"dropped{lost})", problems)
    for problem in records:
        drop_records(store, problem["array"], tuple(problem["chunk"]), step + 1, write=True)
    _commit_rollback(store, intact, dropped)


def _last_intact(store, whole: bool = False) -> tuple[int | None, list[dict]]:
    """``(j, problems)``: the last snapshot j of ``store`` whose f and snapshot entries are
    intact (None when none is), and the problems of every array but f and the coordinates
    and of the snapshots of f after j; with ``whole`` of every snapshot of f, j before
    the first damaged one."""
    k = store.snapshot_count
    small = [n for n in store.array_names() if n != "f" and n not in store.coordinate_arrays]
    problems = store.verify(small + (["f"] if whole else []))
    bad_snapshot = min((p["first"] for p in problems if p["array"] in SNAPSHOT_ARRAYS),
                       default=k)
    for j in range(min(k, bad_snapshot) - 1, -1, -1):
        damage = store.verify(["f"], snapshots={j})
        if not damage:
            return j, problems
        problems += damage
    return None, problems


def _commit_rollback(store, intact: int, dropped: list[dict]) -> None:
    """Make snapshot ``intact`` the last commit of ``store`` and list the ``dropped``
    records in its metadata; the snapshots and records after it are dropped."""
    if dropped:
        meta = store.metadata
        meta["dropped_records"] = meta.get("dropped_records", []) + dropped
        store.group.attrs["granframe"] = meta
    step = int(store.group["snapshot_step"][intact])
    store.mark("running", snapshots=intact + 1, records=step + 1, step=step,
               time=float(store.group["time"][intact]),
               dt_next=float(store.group["snapshot_dt_next"][intact]),
               rollbacks=store.progress.get("rollbacks", []) + [store.snapshot_count - 1])
    truncate(store)


def drop_records(store, name: str, index: tuple, extent: int, write: bool = False) -> dict:
    """The records of the chunk ``index`` of the record array ``name`` of ``store`` up to
    entry ``extent``: ``{"array", "first", "count"}``; with ``write`` its damaged file is
    replaced by NaN (-1 in integer arrays), and ``step`` by the step numbers."""
    array = store.group[name]
    region = tuple(slice(i * c, min((i + 1) * c, n))
                   for i, c, n in zip(index, array.chunks, (extent,) + array.shape[1:]))
    if write:
        shape = tuple(r.stop - r.start for r in region)
        values = (numpy.arange(region[0].start, region[0].stop).reshape(shape)
                  if name == "step" else numpy.full(shape, fill_value(array.dtype)))
        chunk_file(store.path, name, index).unlink(missing_ok=True)
        array.with_config({"write_empty_chunks": True})[region] = values   # NaN: the fill
    return {"array": name, "first": region[0].start, "count": region[0].stop - region[0].start}
