"""How a run store's arrays are made in zarr: codecs, fill values, chunks and shapes.

Every array is compressed with zstd and ends each chunk in a CRC-32C (:func:`codecs`),
is filled with NaN or -1 (:func:`fill_value`), and is created from a :class:`Layout`:
the coordinates, the snapshots of f and the :class:`RecordArray` recorded after every
step (:func:`homogeneous_layout` for a space-homogeneous run; a space run builds its own).
:func:`consolidate` writes the consolidated metadata that ends each commit.
"""

from __future__ import annotations

import math
import os
import warnings

import attrs
import numpy
import zarr

from granframe.run.storage.schema import (CELL_AXES, MOMENT_CHUNK, RECORDED_MOMENTS, SNAPSHOT_CHUNK,
                                          array_attributes)
from granframe.validators import is_integer, reject

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
    cells_chunk : int, tuple of int, or None
        Cells per chunk along its first dimension after ``step_time``, which must then be
        the cells axis (``x``, or ``y`` or ``z`` for cells along those axes); a tuple: along
        each of its first dimensions, which must then be cell axes (``x``, ``y`` of a
        rectangle): a space run's fields are chunked by block of cells
        (``cells_chunk = block_cells``), so that the owner of a block writes chunk files
        no other block touches (:meth:`RunStore.write_block`). None: one chunk spans
        each dimension after ``step_time`` whole.
    """

    name: str
    shape: tuple = ()
    dimensions: tuple = ()
    dtype: str = "f8"
    chunk: int = MOMENT_CHUNK
    cells_chunk: int | tuple | None = attrs.field(default=None)

    @cells_chunk.validator
    def _check_cells_chunk(self, attribute, value):
        if value is None:
            return
        widths = value if isinstance(value, tuple) else (value,)
        if (len(self.dimensions) < len(widths) or len(self.shape) < len(widths)
                or not all(name in CELL_AXES for name in self.dimensions[:len(widths)])):
            reject("RecordArray", "cells_chunk", value, f"is only allowed for a record whose "
                   f"first dimension after step_time is the cells axis 'x' (or 'y', 'z' "
                   f"for cells along those axes; x and y of a rectangle for a tuple) (record "
                   f"'{self.name}' has dimensions {tuple(self.dimensions)}); leave it None")
        if not all(is_integer(w) and 1 <= w <= n for w, n in zip(widths, self.shape)):
            reject("RecordArray", "cells_chunk", value, f"must be None or a whole number of "
                   f"cells from 1 to {self.shape[0]} (the cells of record '{self.name}'), "
                   "or one for each cell axis")

    @property
    def chunks(self) -> tuple:
        """The chunk shape of the array in the store (``step_time`` first)."""
        if self.cells_chunk is None:
            return (self.chunk,) + tuple(self.shape)
        widths = self.cells_chunk if isinstance(self.cells_chunk, tuple) else \
            (self.cells_chunk,)
        return (self.chunk,) + widths + tuple(self.shape[len(widths):])


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


def _create(group, name, shape, chunks, dtype, dimension_names, space=False):
    """An empty array ``name`` of ``group`` with granframe's codecs, fill value and CF
    attributes."""
    return group.create_array(name, shape=shape, chunks=chunks, dtype=dtype,
                              fill_value=fill_value(dtype), dimension_names=dimension_names,
                              attributes=array_attributes(name, space), **codecs())
