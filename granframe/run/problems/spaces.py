"""The space a run's cells fill: a point (zero space dimensions), an interval (one) or a
rectangle (two).

A run is one :class:`~granframe.run.problems.space.SpaceProblem`; what depends on the
number of space dimensions is here, behind one interface, so that a further axis is a
further shape and not a further problem:

===============  ========================  =========================  ============================
member           :class:`Point`            :class:`Interval`          :class:`Rectangle`
===============  ========================  =========================  ============================
cells, owned     one, f itself             ``cells`` along x, a range  C_x x C_y, a block per
                                           per process                process (P_x x P_y)
state            f on the backend          the blocks of a            the block of a
                                           :class:`Domain`            :class:`Box`
step             the run's integrator      Strang: transport,         the same, the transport
                                           collisions, transport      on both axes at once
record           the moments of f          fields, totals, 2 walls    fields on (x, y), totals,
                                                                      4 walls
store            f (time, v)               f (time, x, v)             f (time, x, y, v)
report           f's indicators            every cell's, the worst    the same, named by (x, y)
                                           named
===============  ========================  =========================  ============================

Each takes f0 as cells from :meth:`initial` (the point's one cell has no cell axis), checks
it against the grid and projects it onto the Nyquist-free modes before anything is written.
"""

from __future__ import annotations

import math
import time

import numpy

from granframe.backends import to_host
from granframe.model.initial import check_fits, check_projection
from granframe.parallel import (BoxHalo, CellLayout, Halo, SerialCommunicator,
                                check_store_chunks, process_grid, world)
from granframe.run.monitors import (CELL_INDICATORS, AccuracyMonitors, CellEdgeMonitors,
                                    cell_resolution_report)
from granframe.run.storage import (RECORDED_MOMENTS, STEP_RECORDS, Layout, RecordArray,
                                   homogeneous_layout)
from granframe.space.collisions import SplitStep
from granframe.space.domain import Box, Domain
from granframe.space.hierarchy import CellGrid
from granframe.space.initial import initial_cells
from granframe.space.transport import BoxTransport, Transport
from granframe.validators import reject
from granframe.velocity.estimators import resolution_report
from granframe.velocity.moments import FIELDS, TOTALS, FieldMoments

#: what entered the interval through each wall over each step: mass, energy, and the d
#: components of momentum (normal v1, tangential v2 .. vd)
WALL_RECORDS = ("wall_mass", "wall_energy", "wall_momentum")

#: with a hierarchy of collision models, after every step for every cell: its level (the
#: index in the hierarchy's levels), the indicators that choose the next levels, measured
#: after the collision step, and how many cells each side its level reaches
#: (:class:`~granframe.space.hierarchy.HybridCollisions`)
LEVEL_RECORDS = {"level": "i8", "realizability": "f8", "distance": "f8", "reach": "i8"}


def moments(grid, f, xp) -> dict:
    """Mass, momentum, temperature, energy, min f, negative-mass share, kurtosis, a2,
    pressure tensor and heat flux of f.

    One fused pass over f and one transfer to the host (:meth:`VelocityGrid.moments`);
    NaN where a moment is undefined (a zero mass).
    """
    fused = grid.moments(f, xp)
    return {name: fused[name] for name in RECORDED_MOMENTS}


class Point:
    """Zero space dimensions: one cell, f itself, in one process, without transport.

    The run's step is its time integrator on the equation (Strang's splitting of a step
    without transport is the collision step), fixed or adaptive; the record is the moments
    of f (:func:`moments`), the store f (time, v) (:func:`homogeneous_layout`).
    """

    dimension = 0
    collisions = True
    owned = slice(None)
    owned_cells = None
    ranges = ((0, 1),)
    domain = transport = fields = left = right = reconstruction = cell_layout = None
    #: no reductions over processes: one process
    reduction_seconds = 0.0

    def __init__(self, description, outline: bool = False, communicator=None,
                 partition_cells=None):
        processes = (communicator or (SerialCommunicator() if outline else world())).size
        if processes > 1 or partition_cells is not None:
            reject("make_problem", "processes", processes, "must be 1 for a "
                   "space-homogeneous run (it has no cells to share): run it without "
                   "mpiexec, or give the description a space section")
        self.description = description
        self.communicator = SerialCommunicator()

    def build(self, grid, backend) -> None:
        """Nothing to build: the point has no cells to lay out."""

    def initial(self, check: bool):
        """f0 sampled on the grid, checked (:func:`check_fits`) and projected; with the
        moments before and after the projection (:func:`check_projection`, which refuses
        f0 the grid does not resolve), or None without ``check``."""
        d = self.description
        grid, initial = d.grid, d.build("initial")
        sampled = initial.sample(grid)
        if check:
            check_fits(grid, sampled, initial, d.health.edge_tolerance,
                       d.health.initial_mass_tolerance)
        f0 = grid.project(sampled)
        projection = None if not check else check_projection(
            grid, sampled, f0, initial, d.health.projection_tolerance,
            d.health.projection_kurtosis_tolerance, d.health.positivity_tolerance)
        return f0, projection

    def integrator(self, stage, collision_integrator, rescaling):
        """The run's time integrator itself."""
        return collision_integrator

    def layout(self, grid, hierarchy: bool):
        return homogeneous_layout(grid)

    def record_names(self, hierarchy: bool) -> tuple:
        return RECORDED_MOMENTS

    def state(self, f_host, backend):
        return backend.asarray(f_host)

    def snapshot(self, state, backend):
        return backend.to_numpy(state)

    def record(self, state, backend, hierarchy) -> dict:
        """The moments of f (:func:`moments`: one fused pass, one transfer)."""
        return moments(self.description.grid, state, backend.xp)

    def monitors(self, store, operator) -> AccuracyMonitors:
        """The accuracy monitors from the store's first record (t = 0) and, for a resumed
        run, their state at its last commit."""
        group = store.group
        initial = {name: group[name][0] for name in ("mass", "momentum", "temperature")}
        return AccuracyMonitors(self.description, operator, initial,
                                store.progress.get("accuracy"))

    def report(self, state, record, monitors, backend):
        """The resolution indicators of f (an FFT of f and one of |f| padded to 2N,
        :func:`~granframe.velocity.estimators.resolution_report`), then the edge shares and
        the spectral tail into the accuracy monitors."""
        xp = backend.xp
        d = self.description
        resolution = resolution_report(d.grid, state.f, record["negative_mass_fraction"],
                                       d.health.resolution_tolerance, xp)
        problem = monitors.update(monitors.shape(state.f, record, resolution, xp),
                                  state.step, state.t)
        return resolution, problem

    def progress_text(self, record, mass0) -> str:
        return (f"T={record['temperature']:.6g}, "
                f"mass drift {record['mass'] / mass0 - 1:+.1e}")


def space_layout(grid, domain, block, levels: bool = False) -> Layout:
    """The store of a space run: f (time, x, v1, ..., vd) chunked by snapshot and by
    ``block`` cells along x, the coordinates v1 ... vd and x (the cell centres), and after
    every step the totals, the fields (step_time, x, ...) chunked by ``block`` along x,
    and the wall records (step_time, wall; ``wall_momentum`` (step_time, wall, axis));
    with ``levels`` (a hierarchy of collision models) the level of every cell,
    ``level`` (step_time, x), an integer: its index in the hierarchy's levels. The cell
    axes and their coordinates are the domain's (:attr:`Domain.axes`,
    :meth:`Domain.coordinates`). On a rectangle (a :class:`Box` and ``block`` a pair of
    chunk widths) f is (time, x, y, v1, ..., vd) and the fields (step_time, x, y, ...),
    chunked along both axes, and the wall records have its four sides (left, right,
    bottom, top)."""
    d = grid.dimension
    axes = tuple(f"v{i + 1}" for i in range(d))
    plane = isinstance(domain.cells, tuple)
    cells, widths = ((domain.cells, tuple(block)) if plane
                     else ((domain.cells,), (block,)))
    space = tuple(domain.axes)
    chunk = max(1, 4096 // math.prod(widths))
    cells_chunk = widths if plane else block
    fields = tuple(RecordArray(name, cells + tuple(d if c == "d" else c for c in shape),
                               space + dims, chunk=chunk, cells_chunk=cells_chunk)
                   for name, (shape, dims) in FIELDS.items())
    sides = len(domain.sides)
    walls = tuple(RecordArray(name, (sides, d) if name == "wall_momentum" else (sides,),
                              ("wall", "axis") if name == "wall_momentum" else ("wall",))
                  for name in WALL_RECORDS)
    if levels:
        walls += tuple(RecordArray(name, cells, space, dtype=dtype, chunk=chunk,
                                   cells_chunk=cells_chunk)
                       for name, dtype in LEVEL_RECORDS.items())
    points = grid.points()
    stored = ({"cells": list(cells), "length": list(domain.length), "block_cells": list(widths)}
              if plane else {"cells": domain.cells, "length": domain.length,
                             "block_cells": block})
    return Layout(tuple((name, points, (name,)) for name in axes)
                  + tuple((name, values, (name,))
                          for name, values in domain.coordinates().items()),
                  cells + tuple(grid.shape), widths + tuple(grid.shape),
                  space + axes,
                  STEP_RECORDS + tuple(RecordArray(n) for n in TOTALS) + fields + walls,
                  space=stored)


def _cell(condition, mass):
    """One cell of ``condition`` for :func:`check_fits`: its intended mass, under the
    condition's name (which the messages show)."""
    return type(type(condition).__name__, (), {"intended_mass": mass})()


class Interval:
    """One space dimension: the cells of [0, ell] along x, spread over the processes of
    ``communicator`` (by default :func:`granframe.parallel.world`; serial for an outline),
    ``partition_cells`` the cells of each (:func:`granframe.parallel.partition`).

    The state is the block array of a :class:`~granframe.space.domain.Domain` (the owned
    cells, each block with its ghost cells), stepped by
    :class:`~granframe.space.collisions.SplitStep`; after every step the fields of every
    cell, the totals, and the mass, momentum and energy that entered through each wall over
    the step are recorded (:func:`space_layout`), all from one device vector
    (:class:`~granframe.velocity.moments.FieldMoments`) and one transfer; a snapshot is
    f(x, v) of every cell, chunked by block; at each output point the resolution
    indicators of every cell and the accuracy monitors, computed for every cell at once on
    the backend; the worst cells are reported and kept with the commit
    (:func:`~granframe.run.monitors.cell_resolution_report`,
    :class:`~granframe.run.monitors.CellEdgeMonitors`).
    """

    dimension = 1

    def __init__(self, description, outline: bool = False, communicator=None,
                 partition_cells=None):
        self._take_parts(description, outline, communicator)
        space, comm = description.space, self.communicator
        #: the store's chunks, the cells (start, stop) of every process in rank order and
        #: this one's batch blocks
        self.cell_layout = CellLayout(space.cells, self.reconstruction.ghost, comm.size,
                                      comm.rank, space.block_cells, partition_cells)
        self.ranges = self.cell_layout.ranges
        self.owned_cells = self.cell_layout.stop - self.cell_layout.start
        self.domain = self.transport = self.fields = None
        #: wall seconds of the reductions of the records over the processes
        self.reduction_seconds = 0.0

    def _take_parts(self, description, outline: bool, communicator) -> None:
        """The description, its reconstruction, its walls (:attr:`walls`, in the order of
        the space's sides; ``left`` and ``right`` the first two), whether it collides, and
        the processes it runs on (serial for an outline)."""
        self.description = description
        parts = description.build("space")
        self.reconstruction = parts["reconstruction"]
        self.walls = tuple(parts[side] for side in description.space.sides)
        self.left, self.right = self.walls[:2]
        self.collisions = description.space.collisions
        self.communicator = (SerialCommunicator() if outline else
                             world() if communicator is None else communicator)

    @property
    def owned(self) -> slice:
        """The cells this process owns and steps (all of them in a serial run)."""
        return slice(self.cell_layout.start, self.cell_layout.stop)

    def hierarchy_cells(self):
        """The cells as a hierarchy of collision models sees them
        (:class:`~granframe.space.hierarchy.CellGrid`) and this process's among them."""
        cells = CellGrid((self.description.space.cells,), (self.domain.dx,),
                         (self.left.periodic,), (self.domain.axis,))
        return cells, self.owned

    def build(self, grid, backend) -> None:
        """The domain of the owned cells on the array namespace of ``backend``, its ghost
        exchange with the other processes, the transport (its face values through the
        backend's :meth:`~granframe.abc.ArrayBackend.faces`) and the moment service."""
        xp = backend.xp
        d, layout = self.description, self.cell_layout
        self.domain = Domain(d.space.cells, d.space.length, layout.block,
                             self.reconstruction.ghost, grid, xp,
                             owned=(layout.start, layout.stop), axis=layout.axis)
        if self.communicator.size > 1:
            self.domain.neighbours = Halo.of(self.communicator, self.ranges,
                                             self.left.periodic)
        self.transport = Transport(self.domain, self.reconstruction, self.left, self.right,
                                   backend)
        self.fields = FieldMoments(grid, self.domain.dx, xp,
                                   transport_axes=(self.transport.axis,))

    def initial(self, check: bool):
        """f0 as cell averages (cells, *grid.shape), checked and projected cell by cell,
        with the moments before and after the Nyquist projection of the cell they change
        most (:func:`~granframe.model.initial.check_projection`, which refuses a cell the
        grid does not resolve), or None without ``check``."""
        return self._checked_cells(check)

    def _checked_cells(self, check: bool):
        """f0 (cells, *grid.shape) and the projection's moments of :meth:`initial`."""
        d = self.description
        grid = d.grid
        sampled, masses = initial_cells(d)
        if not check:
            return numpy.stack([grid.project(f) for f in sampled]), None
        initial = d.build("initial")
        projected, worst, projection = [], -1.0, None
        for index, (f, mass) in enumerate(zip(sampled, masses)):
            cell = _cell(initial, mass)
            try:
                check_fits(grid, f, cell, d.health.edge_tolerance,
                           d.health.initial_mass_tolerance)
                projected.append(grid.project(f))
                moments = check_projection(grid, f, projected[-1], cell,
                                           d.health.projection_tolerance,
                                           d.health.projection_kurtosis_tolerance)
            except ValueError as exc:
                raise ValueError(f"{exc} ({self._where(index)})") from None
            change = max(abs(m["after"] / m["before"] - 1.0) for m in moments.values())
            if change > worst:
                worst, projection = change, moments
        projected = numpy.stack(projected)
        self._check_positivity(projected)
        return projected, projection

    def _where(self, index: int) -> str:
        """Where cell ``index`` is, for a message."""
        edges = self.domain.edges()
        return (f"in cell {index} of {self.description.space.cells}, x = "
                f"{0.5 * (edges[index] + edges[index + 1]):.6g}")

    def _check_positivity(self, f0) -> None:
        """Refuse f0 whose negative mass share over all cells, sum max(-f, 0) / sum |f| (what
        the health check takes after every step), is above ``health.positivity_tolerance``,
        naming the cell where it is largest."""
        d = self.description
        grid = d.grid
        flat = f0.reshape(len(f0), -1)
        negative = numpy.maximum(-flat, 0.0).sum(axis=1)
        absolute = numpy.abs(flat).sum(axis=1)
        share = float(negative.sum() / absolute.sum())
        if share <= d.health.positivity_tolerance:
            return
        worst = int(numpy.argmax(negative / absolute))
        reject(f"initial condition {type(d.build('initial')).__name__}",
               "negative mass share of f0 after the Nyquist projection", share,
               f"must be <= health.positivity_tolerance = {d.health.positivity_tolerance:g}, "
               f"which the run checks after every step (largest {self._where(worst)}: "
               f"{negative[worst] / absolute[worst]:.3g}): N = {grid.n_modes} modes (spacing "
               f"h = {grid.spacing:.4g}) do not resolve f0, whose projection rings below zero; "
               "use a larger grid.n_modes, or a smaller grid.support_radius if f0 is "
               "negligible well inside the faces of the box (h = 2L/N falls with it)")

    def integrator(self, stage, collision_integrator, rescaling):
        """Strang's splitting of the transport and the collision ``stage``
        (:class:`~granframe.space.collisions.SplitStep`)."""
        return SplitStep(stage, self.transport, rescaling)

    def layout(self, grid, hierarchy: bool):
        return space_layout(grid, self.domain, self.cell_layout.chunk, levels=hierarchy)

    def record_names(self, hierarchy: bool) -> tuple:
        return TOTALS + tuple(FIELDS) + WALL_RECORDS + (tuple(LEVEL_RECORDS) if hierarchy
                                                        else ())

    def state(self, f_host, backend):
        """The block array of the owned cells from f on the host: every cell (f0), or the
        owned ones (a snapshot read by ``owned``)."""
        f_host = f_host if len(f_host) == self.domain.owned_cells else f_host[self.owned]
        return self.domain.from_cells(backend.asarray(f_host))

    def snapshot(self, state, backend):
        """f of the owned cells on the host."""
        return backend.to_numpy(self.domain.to_cells(state))

    def record(self, state, backend, hierarchy) -> dict:
        """The fields of the owned cells, the totals over all cells and the wall totals
        since the last record, with what the hierarchy's step left to bring to the host
        (:meth:`~granframe.space.hierarchy.HybridCollisions.pending`): one device vector
        (:meth:`FieldMoments.packed`) and one device->host transfer, then one reduction over
        the processes (:meth:`~granframe.abc.Communicator.allgather` of the partial totals,
        combined in rank order by :meth:`FieldMoments.combine`, the same in every
        process). The hierarchy follows the fields it records
        (:meth:`~granframe.space.hierarchy.HybridCollisions.follow`: the substeps of its
        fluid levels in the next step, from numbers on the host)."""
        cells = self.domain.to_cells(state)
        extra = self.transport.take_wall_totals().reshape(-1)
        carried = None if hierarchy is None else hierarchy.pending()
        if carried is not None:          # the hierarchy's step vector rides along
            extra = backend.xp.concatenate([extra, carried])
        vector = to_host(self.fields.packed(cells, extra))
        if carried is not None:
            hierarchy.receive(vector[len(vector) - len(carried):])
            vector = vector[:len(vector) - len(carried)]
        record = self.fields.unpack(vector, len(cells))
        began = time.perf_counter()
        rows = self.communicator.allgather(self.fields.partial_totals(vector, record))
        self.reduction_seconds += time.perf_counter() - began
        record.update(self.fields.combine(rows))
        extra = record.pop("walls").reshape(len(self.domain.sides), -1)
        record["wall_mass"], record["wall_energy"] = extra[:, 0], extra[:, -1]
        record["wall_momentum"] = extra[:, 1:-1]
        if hierarchy is not None:
            hierarchy.follow(record["density"], record["velocity"], record["temperature"])
            record.update(hierarchy.records())
        return record

    def monitors(self, store, operator) -> CellEdgeMonitors:
        return CellEdgeMonitors(self.description, store.progress.get("accuracy"))

    def report(self, state, record, monitors, backend):
        """The resolution indicators of every cell
        (:meth:`~granframe.velocity.moments.FieldMoments.resolution`) and the edge shares of
        every cell about its own velocity, computed on the backend and taken to the host in
        one transfer; the report names the worst cells
        (:func:`~granframe.run.monitors.cell_resolution_report`), the largest values go into
        the monitors."""
        xp = backend.xp
        cells = self.domain.to_cells(state.f)
        count = cells.shape[0]
        parts = [self.fields.resolution(cells, backend).reshape(-1)]
        if monitors.radius > 0.0:
            velocity = self.fields.primitives(cells)[1]
            parts.append(self.fields.edge_shares(cells, velocity, monitors.radius).reshape(-1))
        values = to_host(xp.concatenate(parts))
        indicators = values[:count * len(CELL_INDICATORS)].reshape(count, -1)
        shares = (values[count * len(CELL_INDICATORS):].reshape(count, 2)
                  if monitors.radius > 0.0 else None)
        indicators = self._gather_cells(indicators)     # every cell's, in every process
        shares = None if shares is None else self._gather_cells(shares)
        resolution = cell_resolution_report(self.description.grid, indicators,
                                            self._positions(),
                                            self.description.health.resolution_tolerance)
        return resolution, monitors.update(monitors.shape(shares, resolution), state.step,
                                           state.t)

    def _positions(self):
        """The centre of every cell, in cell order."""
        return self.domain.centres()

    def _gather_cells(self, values):
        """Every cell's ``values`` (owned cells, ...) in every process, in cell order."""
        if self.communicator.size == 1:
            return values
        return numpy.concatenate(self.communicator.allgather_object(values))

    def check_chunks(self, space: dict, path) -> None:
        """Refuse to resume a store whose chunks along x do not fall on the boundaries of
        the processes' cells (a store made with another ``block_cells``), before anything
        is written."""
        if len(self.ranges) == 1:
            return
        check_store_chunks(self.ranges, int(space.get("block_cells", 1)),
                           space.get("cells", "?"), path)

    def progress_text(self, record, mass0) -> str:
        low, high = record["temperature_range"]
        return f"T in [{low:.4g}, {high:.4g}], mass drift {record['mass'] / mass0 - 1:+.1e}"


class Rectangle(Interval):
    """Two space dimensions: the cells of [0, L_x] x [0, L_y], in blocks over a P_x x P_y
    grid of the processes of ``communicator`` (:func:`granframe.parallel.process_grid`,
    near square; rank r at place (r // P_y, r % P_y)), each block whole store chunks along
    both axes.

    The state is the block array of a :class:`~granframe.space.domain.Box` (the owned
    cells with their ghost strips), stepped by
    :class:`~granframe.space.collisions.SplitStep` with the unsplit transport
    (:class:`~granframe.space.transport.BoxTransport`) and the collision step on every cell
    of the block at once; the records are those of the interval, on (x, y), and what
    entered through each of the four sides (:func:`space_layout`). Everything else is the
    interval's (:class:`Interval`): the fields and the totals from one device vector and one
    transfer, the resolution indicators of every cell, the monitors.
    """

    dimension = 2

    def __init__(self, description, outline: bool = False, communicator=None,
                 partition_cells=None):
        self._take_parts(description, outline, communicator)
        d, space, comm = description, description.space, self.communicator
        if partition_cells is not None:
            reject("make_problem", "partition_cells", partition_cells, "must be None on a "
                   "rectangle: its blocks are whole store chunks shared as evenly as the "
                   "process grid allows")
        ghost = self.reconstruction.ghost
        chunks = space.blocks(ghost)
        #: the processes along x and y
        self.process_counts = process_grid(comm.size, space.counts, chunks, ghost)
        place = [int(i) for i in numpy.unravel_index(comm.rank, self.process_counts)]
        self.layouts = [CellLayout(n, ghost, p, i, b, axis=a) for a, (n, p, i, b) in
                        enumerate(zip(space.counts, self.process_counts, place, chunks))]
        self.cell_layout = None
        #: the block (start, stop) along x and y of every process, in rank order
        self.ranges = [tuple(layout.ranges[i] for layout, i in zip(
            self.layouts, numpy.unravel_index(r, self.process_counts)))
            for r in range(comm.size)]
        self.chunks = tuple(chunks)
        self.owned_cells = math.prod(layout.stop - layout.start for layout in self.layouts)
        self.domain = self.transport = self.fields = None
        self.reduction_seconds = 0.0

    @property
    def owned(self) -> tuple:
        """The block this process owns and steps: a slice along x and one along y."""
        return tuple(layout.owned for layout in self.layouts)

    def hierarchy_cells(self):
        """The cells as a hierarchy sees them (:class:`~granframe.space.hierarchy.CellGrid`,
        C_x x C_y in C order) and the owned block's among them, in the order of its cells
        (x slowest): a slice when this process owns every cell."""
        counts = tuple(self.description.space.counts)
        block = numpy.arange(math.prod(counts)).reshape(counts)[self.owned].reshape(-1)
        owned = slice(0, len(block)) if len(block) == math.prod(counts) else block
        cells = CellGrid(counts, self.domain.spacing,
                         (self.walls[0].periodic, self.walls[2].periodic), (0, 1))
        return cells, owned

    def build(self, grid, backend) -> None:
        """The box of the owned block on the backend, its ghost exchange with the other
        processes, the transport and the moment service (totals over dx dy)."""
        xp = backend.xp
        space = self.description.space
        self.domain = Box(space.counts, space.lengths, self.reconstruction.ghost, grid, xp,
                          owned=[(layout.start, layout.stop) for layout in self.layouts])
        if self.communicator.size > 1:
            periodic = (self.walls[0].periodic, self.walls[2].periodic)
            self.domain.neighbours = BoxHalo.of(self.communicator, self.process_counts,
                                                periodic)
        self.transport = BoxTransport(self.domain, self.reconstruction, self.walls, backend)
        self.fields = FieldMoments(grid, self.domain.cell_volume, xp, transport_axes=(0, 1))

    def initial(self, check: bool):
        """f0 as cell averages (C_x, C_y, *grid.shape), checked and projected cell by cell
        (:meth:`Interval.initial`, the cells named by (i, j) and (x, y))."""
        d = self.description
        counts = d.space.counts
        f, projection = self._checked_cells(check)
        return f.reshape(counts + f.shape[1:]), projection

    def _where(self, index: int) -> str:
        i, j = numpy.unravel_index(index, self.description.space.counts)
        x, y = self.domain.centres(0)[i], self.domain.centres(1)[j]
        return (f"in cell ({i}, {j}) of {list(self.description.space.counts)}, (x, y) = "
                f"({x:.6g}, {y:.6g})")

    def layout(self, grid, hierarchy: bool):
        return space_layout(grid, self.domain, self.chunks, levels=hierarchy)

    def state(self, f_host, backend):
        """The block array of the owned cells from f on the host: every cell
        (C_x, C_y, ...), or the owned block."""
        if f_host.shape[:2] != tuple(self.domain.sizes):
            f_host = f_host[self.owned]
        return self.domain.from_cells(backend.asarray(f_host))

    def snapshot(self, state, backend):
        """f of the owned block on the host, (n_x, n_y, *grid.shape)."""
        cells = backend.to_numpy(self.domain.to_cells(state))
        return cells.reshape(tuple(self.domain.sizes) + cells.shape[1:])

    def record(self, state, backend, hierarchy) -> dict:
        """The interval's record (:meth:`Interval.record`) with the fields of the owned
        block on (x, y) and the wall records of the four sides."""
        record = super().record(state, backend, hierarchy)
        for name in tuple(FIELDS) + (tuple(LEVEL_RECORDS) if hierarchy is not None else ()):
            values = numpy.asarray(record[name])
            record[name] = values.reshape(tuple(self.domain.sizes) + values.shape[1:])
        return record

    def _positions(self):
        """The centre (x, y) of every cell, in C order."""
        x, y = numpy.meshgrid(self.domain.centres(0), self.domain.centres(1), indexing="ij")
        return numpy.stack([x.ravel(), y.ravel()], axis=1)

    def _gather_cells(self, values):
        """Every cell's ``values`` (owned cells in C order, ...) in every process, in the
        global C order of the cells."""
        counts = self.description.space.counts
        if self.communicator.size == 1:
            return values
        parts = self.communicator.allgather_object(values)
        whole = numpy.empty(counts + parts[0].shape[1:])
        for (xs, ys), part in zip(self.ranges, parts):
            whole[xs[0]:xs[1], ys[0]:ys[1]] = part.reshape(
                (xs[1] - xs[0], ys[1] - ys[0]) + part.shape[1:])
        return whole.reshape((-1,) + whole.shape[2:])

    def check_chunks(self, space: dict, path) -> None:
        """Refuse to resume a store whose chunks along x or y do not fall on the block
        boundaries of these processes, before anything is written."""
        if self.communicator.size == 1:
            return
        widths = space.get("block_cells", [1, 1])
        cells = space.get("cells", ["?", "?"])
        for axis, layout in enumerate(self.layouts):
            check_store_chunks(layout.ranges, int(widths[axis]), cells[axis], path, axis)
