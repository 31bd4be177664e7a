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
  :class:`~granframe.run.storage.commits.StoreCommits`), so that in a space run, whose f
  and fields are chunked by block of cells, the owner of each block writes its own chunk
  files; :meth:`RunStore.commit` is the one-process case of
  :meth:`RunStore.commit_together`.
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

The package is split by concern, each module importing only those above it in this list:
:mod:`~granframe.run.storage.errors` (the errors), :mod:`~granframe.run.storage.schema`
(array names, long names, CF attributes), :mod:`~granframe.run.storage.layout` (codecs,
fill values, :class:`Layout`), :mod:`~granframe.run.storage.locks` (:class:`WriterLock`),
:mod:`~granframe.run.storage.paths` (what a path holds, staging and replacement,
:func:`recover`), :mod:`~granframe.run.storage.integrity` (missing and damaged chunks),
:mod:`~granframe.run.storage.state` (an open store's metadata, extents and
:meth:`~RunStore.verify`), :mod:`~granframe.run.storage.commits` (:class:`CommitPlan`, the
four phases, :meth:`~RunStore.commit_together`), :mod:`~granframe.run.storage.resumption`
(what a resumed store continues from, the rollback), :mod:`~granframe.run.storage.store`
(:class:`RunStore`) and :mod:`~granframe.run.storage.reports` (``granframe check`` and
``granframe info``). The names below are those of the modules, gathered here.
"""

from __future__ import annotations

import warnings

from granframe.run.storage.commits import CommitPlan, collective
from granframe.run.storage.errors import (StoreDamagedError, StoreError, StoreExistsError,
                                          StoreLockedError)
from granframe.run.storage.integrity import summarise
from granframe.run.storage.layout import (STEP_RECORDS, Layout, RecordArray, codecs, consolidate,
                                          fill_value, homogeneous_layout)
from granframe.run.storage.locks import WriterLock, lock_path
from granframe.run.storage.paths import (TRASH, check_replaceable, recover, sibling,
                                         store_kind)
from granframe.run.storage.reports import check, describe, dropped_note, stray_entries
from granframe.run.storage.resumption import differences
from granframe.run.storage.schema import (CELL_AXES, CONVENTIONS, FIRST_RECORD_ARRAYS,
                                          LEVEL_LONG_NAMES, LONG_NAMES, MOMENT_CHUNK,
                                          NONDIMENSIONALISATION, RECORD_ARRAYS,
                                          RECORDED_MOMENTS, REFERENCES, RESCALED_NOTE,
                                          RESUMABLE, SCALAR_MOMENTS, SCHEMA, SNAPSHOT_ARRAYS,
                                          SNAPSHOT_CHUNK, SWEEP_SCHEMA_KEY,
                                          TENSOR_MOMENTS, array_attributes, flat_attributes,
                                          now, root_attributes)
from granframe.run.storage.store import RunStore

#: zarr warns of every entry of a store that is not a zarr array or group (a directory left
#: by a write a kill cut short, a file a user dropped in); granframe reads only the arrays of
#: its layout, and ``granframe check`` names those entries in one line (:func:`stray_entries`)
warnings.filterwarnings("ignore", message="Object at .* is not recognized as a component of a "
                        "Zarr hierarchy", category=UserWarning)

__all__ = ["CELL_AXES", "CONVENTIONS", "FIRST_RECORD_ARRAYS", "LEVEL_LONG_NAMES", "LONG_NAMES",
           "MOMENT_CHUNK", "NONDIMENSIONALISATION", "RECORD_ARRAYS", "RECORDED_MOMENTS",
           "REFERENCES", "RESCALED_NOTE", "RESUMABLE", "SCALAR_MOMENTS", "SCHEMA",
           "SNAPSHOT_ARRAYS", "SNAPSHOT_CHUNK", "STEP_RECORDS", "SWEEP_SCHEMA_KEY",
           "TENSOR_MOMENTS", "TRASH", "CommitPlan", "Layout", "RecordArray", "RunStore",
           "StoreDamagedError", "StoreError", "StoreExistsError", "StoreLockedError",
           "WriterLock", "array_attributes", "check", "check_replaceable", "codecs",
           "collective", "consolidate", "describe", "differences", "dropped_note", "fill_value",
           "flat_attributes", "homogeneous_layout", "lock_path", "now", "recover",
           "root_attributes", "sibling", "store_kind", "stray_entries", "summarise"]
