"""The space problem d_t f + v_1 d_x f = Q(f, f)/eps (+ tau Delta_v f) on [0, ell].

:class:`SpaceProblem` is what a description with a ``space`` section runs
(docs/space.md):

- the state is the block array of a :class:`~granframe.space.domain.Domain` (the owned
  cells, each block with its ghost cells), stepped by
  :class:`~granframe.space.collisions.SplitStep` (Strang: transport, collisions on all
  cells in one batched call per stage, transport);
- after every step the fields of every cell, the totals, and the mass, momentum and
  energy that entered through each wall over the step are recorded (:func:`space_layout`), all from
  one device vector (:class:`~granframe.velocity.moments.FieldMoments`) and one transfer;
- a snapshot is f(x, v) of every cell, chunked by block;
- at each output point the resolution indicators of every cell (those of a homogeneous
  run and the heat flux of the outermost shell of modes) and the accuracy monitors (the
  shares of mass and energy beyond the edge radius), computed for every cell at once on
  the backend; the worst cells are reported and kept with the commit
  (:func:`~granframe.run.monitors.cell_resolution_report`,
  :class:`~granframe.run.monitors.CellEdgeMonitors`).
"""

from __future__ import annotations

import time

import numpy

from granframe.abc import Problem, deferred_checks
from granframe.backends import NumpyBackend, to_host
from granframe.equations.conservative import ConservativeCorrection
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.equations.rescaled import RescaledBoltzmann
from granframe.memory import check_run_memory
from granframe.model.initial import check_fits, check_projection
from granframe.parallel import CellLayout, Halo, SerialCommunicator, world
from granframe.run.monitors import CELL_INDICATORS, CellEdgeMonitors, cell_resolution_report
from granframe.run.problems.parts import build_operator, check_step
from granframe.run.storage import STEP_RECORDS, Layout, RecordArray
from granframe.space.collisions import FreeFlight, LevelledModels, SingleModel, SplitStep
from granframe.space.domain import Domain
from granframe.registry import default_registries
from granframe.velocity.moments import FIELDS, TOTALS, FieldMoments
from granframe.space.hierarchy import HierarchyContext, HybridCollisions
from granframe.space.initial import initial_cells
from granframe.space.transport import Transport
from granframe.stepping.stability import OperatorOutline, step_limit
from granframe.validators import reject

#: what entered the interval through each wall over each step: mass, energy, and the d
#: components of momentum (normal v1, tangential v2 .. vd)
WALL_RECORDS = ("wall_mass", "wall_energy", "wall_momentum")

#: with a hierarchy of collision models, after every step for every cell: its level (the
#: index in the hierarchy's levels), the indicators that choose the next levels, measured
#: after the collision step, and how many cells each side its level reaches
#: (:class:`~granframe.space.hierarchy.HybridCollisions`)
LEVEL_RECORDS = {"level": "i8", "realizability": "f8", "distance": "f8", "reach": "i8"}


def space_layout(grid, domain: Domain, block: int, levels: bool = False) -> Layout:
    """The store of a space run: f (time, x, v1, ..., vd) chunked by snapshot and by
    ``block`` cells along x, the coordinates v1 ... vd and x (the cell centres), and after
    every step the totals, the fields (step_time, x, ...) chunked by ``block`` along x,
    and the wall records (step_time, wall; ``wall_momentum`` (step_time, wall, axis));
    with ``levels`` (a hierarchy of collision models) the level of every cell,
    ``level`` (step_time, x), an integer: its index in the hierarchy's levels."""
    d = grid.dimension
    axes = tuple(f"v{i + 1}" for i in range(d))
    cells = domain.cells
    chunk = max(1, 4096 // block)
    fields = tuple(RecordArray(name, (cells,) + tuple(d if c == "d" else c for c in shape),
                               ("x",) + dims, chunk=chunk, cells_chunk=block)
                   for name, (shape, dims) in FIELDS.items())
    walls = tuple(RecordArray(name, (2, d) if name == "wall_momentum" else (2,),
                              ("wall", "axis") if name == "wall_momentum" else ("wall",))
                  for name in WALL_RECORDS)
    if levels:
        walls += tuple(RecordArray(name, (cells,), ("x",), dtype=dtype, chunk=chunk,
                                   cells_chunk=block) for name, dtype in LEVEL_RECORDS.items())
    points = grid.points()
    return Layout(tuple((name, points, (name,)) for name in axes)
                  + (("x", domain.centres(), ("x",)),),
                  (cells,) + tuple(grid.shape), (block,) + tuple(grid.shape),
                  ("x",) + axes,
                  STEP_RECORDS + tuple(RecordArray(n) for n in TOTALS) + fields + walls,
                  space={"cells": cells, "length": domain.length, "block_cells": block})


def _cell(condition, mass):
    """One cell of ``condition`` for :func:`check_fits`: its intended mass, under the
    condition's name (which the messages show)."""
    return type(type(condition).__name__, (), {"intended_mass": mass})()


class SpaceProblem(Problem):
    """A space run, built once from a description with a ``space`` section
    (:class:`granframe.abc.Problem`; see the module notes).

    f0 is sampled as cell averages (:mod:`granframe.space.initial`; a space-homogeneous
    condition is uniform in x), checked in every cell against the grid (non-negative,
    finite, inside the box, its intended mass) and projected cell by cell onto the
    Nyquist-free modes, all before anything is written. With ``outline`` the operator is
    an :class:`~granframe.stepping.stability.OperatorOutline` (nothing precomputed, on
    NumPy), which is all that :meth:`step_limit` reads; f0 is then not checked.
    """

    def __init__(self, description, outline: bool = False, communicator=None,
                 partition_cells=None):
        if getattr(description, "space", None) is None:
            reject("SpaceProblem", "description", description, "must have a space section",
                   error=TypeError)
        self.description = d = description
        self.grid = grid = d.grid
        space = d.space
        parts = d.build("space")
        self.reconstruction, self.left, self.right = (parts["reconstruction"], parts["left"],
                                                      parts["right"])
        ghost = self.reconstruction.ghost
        self.communicator = comm = (SerialCommunicator() if outline else
                                    world() if communicator is None else communicator)
        #: the store's chunks, the cells (start, stop) of every process in rank order and
        #: this one's batch blocks
        self.cell_layout = CellLayout(space.cells, ghost, comm, space.block_cells, partition_cells)
        self.ranges = self.cell_layout.ranges
        start, stop = self.cell_layout.start, self.cell_layout.stop
        collide = space.collisions
        if outline:
            self.backend = NumpyBackend(threads=1)
            self.operator = OperatorOutline(grid, d.build("kernel"), d.build("restitution"),
                                            self.backend) if collide else None
        else:
            self.backend = d.build("backend").for_process(comm.local_rank)
            check_run_memory(d, self.backend, cells=stop - start, share=comm.local_size)
            self.operator = build_operator(d, self.backend) if collide else None
        xp = self.backend.xp
        self.collision_integrator = d.build("integrator") if collide else None
        self.domain = Domain(space.cells, space.length, self.cell_layout.block, ghost, grid, xp,
                             owned=(start, stop))
        if comm.size > 1:
            self.domain.neighbours = Halo.of(comm, self.ranges, self.left.periodic)
        #: wall seconds of the reductions of the records over the processes
        self.reduction_seconds = 0.0
        self.transport = Transport(self.domain, self.reconstruction, self.left, self.right)
        self.projection = None
        self.f0 = self._initial(check=not outline)
        self.equation = (None if not collide else self._rescaled(outline) if d.rescaled
                         else HomogeneousBoltzmann(self.operator, d.heat_bath, d.knudsen))
        #: the map of a rescaled run to physical variables (kept in the store), or None
        self.rescaling = self.equation.rescaling if collide and d.rescaled else None
        self.fields = FieldMoments(grid, self.domain.dx, xp)
        #: the hierarchy of collision models (None: the full operator in every cell)
        self.hierarchy = None if outline else self._hierarchy()
        stage = (FreeFlight() if not collide else
                 SingleModel(self.collision_integrator, self.equation) if self.hierarchy is None
                 else LevelledModels(self.hierarchy))
        self.integrator = SplitStep(stage, self.transport, self.rescaling)

    def _rescaled(self, outline: bool):
        """The :class:`~granframe.equations.rescaled.RescaledBoltzmann` of the owned cells of
        f0 (u = 0 along x); with ``outline`` its a_0 from the closed-form dissipation of
        every cell
        (:meth:`~granframe.equations.conservative.ConservativeCorrection.dissipation` of the
        :class:`~granframe.stepping.stability.OperatorOutline`)."""
        d, xp = self.description, self.backend.xp
        cells = self.f0[self.owned]
        dissipation = None
        if outline:
            correction = ConservativeCorrection(self.operator)
            dissipation = numpy.array([float(correction.dissipation(f)) for f in cells])
        return RescaledBoltzmann(self.operator, xp.asarray(cells), d.knudsen,
                                 dissipation=dissipation, communicator=self.communicator,
                                 transport_axes=1)

    def _hierarchy(self):
        """The :class:`~granframe.space.hierarchy.HybridCollisions` of ``space.hierarchy``,
        its levels built from the registry with the run's equation, integrator and the
        mass-weighted mean temperature of f0."""
        settings = self.description.space.hierarchy
        if settings is None or self.equation is None:
            return None
        moments = FieldMoments(self.grid, 1.0)(self.f0)
        rho, temperature = moments["density"], moments["temperature"]
        context = HierarchyContext(self.equation, self.collision_integrator,
                                   float((rho * temperature).sum() / rho.sum()))
        registries = default_registries()
        models = [registries.create("collision_models", level.name, context=context,
                                    **level.params) for level in settings.levels]
        return HybridCollisions(settings, models, context, self.description.space.cells,
                                self.domain.owned, self.domain.dx, self.left.periodic,
                                self.communicator, self.description.time_step)

    def _initial(self, check: bool):
        """f0 as cell averages (cells, *grid.shape), checked and projected cell by cell.

        Sets :attr:`projection`, the moments before and after the Nyquist projection of
        the cell they change most (:func:`~granframe.model.initial.check_projection`, which
        refuses a cell the grid does not resolve).
        """
        d, grid = self.description, self.grid
        sampled, masses = initial_cells(d)
        if not check:
            return numpy.stack([grid.project(f) for f in sampled])
        initial = d.build("initial")
        edges = self.domain.edges()
        projected, worst = [], -1.0
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
                raise ValueError(f"{exc} (in cell {index} of {d.space.cells}, x = "
                                 f"{0.5 * (edges[index] + edges[index + 1]):.6g})") from None
            change = max(abs(m["after"] / m["before"] - 1.0) for m in moments.values())
            if change > worst:
                worst, self.projection = change, moments
        projected = numpy.stack(projected)
        self._check_positivity(projected, edges)
        return projected

    def _check_positivity(self, f0, edges) -> None:
        """Refuse f0 whose negative mass share over all cells, sum max(-f, 0) / sum |f| (what
        the health check takes after every step), is above ``health.positivity_tolerance``,
        naming the cell where it is largest."""
        d, grid = self.description, self.grid
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
               f"which the run checks after every step (largest in cell {worst} of "
               f"{d.space.cells}, x = {0.5 * (edges[worst] + edges[worst + 1]):.6g}: "
               f"{negative[worst] / absolute[worst]:.3g}): N = {grid.n_modes} modes (spacing "
               f"h = {grid.spacing:.4g}) do not resolve f0, whose projection rings below zero; "
               "use a larger grid.n_modes, or a smaller grid.support_radius if f0 is "
               "negligible well inside the faces of the box (h = 2L/N falls with it)")

    def layout(self):
        return space_layout(self.grid, self.domain, self.cell_layout.chunk,
                            levels=self.description.space.hierarchy is not None)

    @property
    def owned(self) -> slice:
        """The cells this process owns and steps (all of them in a serial run)."""
        return self.domain.owned

    @property
    def record_names(self) -> tuple:
        return (TOTALS + tuple(FIELDS) + WALL_RECORDS
                + (tuple(LEVEL_RECORDS) if self.description.space.hierarchy is not None
                   else ()))

    def resume(self, store, step: int) -> None:
        """Take up the levels of the hierarchy where the store's run left them: the level of
        every owned cell in ``step`` (its ``level`` record), and the step count that sets
        when the levels are chosen next, so that a resumed run is the uninterrupted one."""
        if self.hierarchy is None:
            return
        records = int(store.progress["records"])
        steps = numpy.asarray(store.group["step"][:records])
        row = int(numpy.flatnonzero(steps == step)[-1])
        self.hierarchy.take_up(step, *(store.group[name][row] for name in LEVEL_RECORDS))

    def state(self, f_host):
        """The block array of the owned cells from f on the host: every cell (f0), or the
        owned ones (a snapshot read by :meth:`owned`)."""
        f_host = f_host if len(f_host) == self.domain.owned_cells else f_host[self.owned]
        return self.domain.from_cells(self.backend.asarray(f_host))

    def snapshot(self, state):
        """f of the owned cells on the host."""
        return self.backend.to_numpy(self.domain.to_cells(state))

    def step(self, t: float, state, dt: float):
        """One step; spread over processes, no check inside it raises in one process alone
        (:func:`~granframe.abc.deferred_checks`): a non-finite f shows in the reduced
        record, and every process stops at that step."""
        with deferred_checks(everywhere=self.communicator.size > 1):
            return self.integrator.step(self.equation, t, state, dt)

    def record(self, state) -> dict:
        """The fields of the owned cells, the totals over all cells and the wall totals
        since the last record, with what the hierarchy's step left to bring to the host
        (:meth:`~granframe.space.hierarchy.HybridCollisions.pending`): one device vector
        (:meth:`FieldMoments.packed`) and one device->host transfer, then one reduction over
        the processes
        (:meth:`~granframe.abc.Communicator.allgather` of the partial totals, combined in
        rank order by :meth:`FieldMoments.combine`, the same in every process)."""
        cells = self.domain.to_cells(state)
        extra = self.transport.take_wall_totals().reshape(-1)
        carried = None if self.hierarchy is None else self.hierarchy.pending()
        if carried is not None:          # the hierarchy's step vector rides along
            extra = self.backend.xp.concatenate([extra, carried])
        vector = to_host(self.fields.packed(cells, extra))
        if carried is not None:
            self.hierarchy.receive(vector[len(vector) - len(carried):])
            vector = vector[:len(vector) - len(carried)]
        record = self.fields.unpack(vector, len(cells))
        began = time.perf_counter()
        rows = self.communicator.allgather(self.fields.partial_totals(vector, record))
        self.reduction_seconds += time.perf_counter() - began
        record.update(self.fields.combine(rows))
        extra = record.pop("walls").reshape(2, -1)
        record["wall_mass"], record["wall_energy"] = extra[:, 0], extra[:, -1]
        record["wall_momentum"] = extra[:, 1:-1]
        if self.hierarchy is not None:
            record.update(self.hierarchy.records())
        return record

    def monitors(self, store) -> CellEdgeMonitors:
        return CellEdgeMonitors(self.description, store.progress.get("accuracy"))

    def report(self, state, record, monitors):
        """The resolution indicators of every cell
        (:meth:`~granframe.velocity.moments.FieldMoments.resolution`) and the edge shares of
        every cell about its own velocity, computed on the backend and taken to the host in
        one transfer; the report names the worst cells
        (:func:`~granframe.run.monitors.cell_resolution_report`), the largest values go into
        the monitors."""
        xp = self.backend.xp
        cells = self.domain.to_cells(state.f)
        count = cells.shape[0]
        parts = [self.fields.resolution(cells, self.backend).reshape(-1)]
        if monitors.radius > 0.0:
            velocity = self.fields.primitives(cells)[1]
            parts.append(self.fields.edge_shares(cells, velocity, monitors.radius).reshape(-1))
        values = to_host(xp.concatenate(parts))
        indicators = values[:count * len(CELL_INDICATORS)].reshape(count, -1)
        shares = (values[count * len(CELL_INDICATORS):].reshape(count, 2)
                  if monitors.radius > 0.0 else None)
        if self.communicator.size > 1:     # every cell's, in every process, in cell order
            gathered = self.communicator.allgather_object((indicators, shares))
            indicators = numpy.concatenate([part[0] for part in gathered])
            shares = None if shares is None else numpy.concatenate([p[1] for p in gathered])
        resolution = cell_resolution_report(self.grid, indicators, self.domain.centres(),
                                            self.description.health.resolution_tolerance)
        return resolution, monitors.update(monitors.shape(shares, resolution), state.step,
                                           state.t)

    def progress_text(self, record, mass0) -> str:
        low, high = record["temperature_range"]
        return f"T in [{low:.4g}, {high:.4g}], mass drift {record['mass'] / mass0 - 1:+.1e}"

    def step_limit(self):
        """The collisions' explicit limit in the stiffest cell (None for a collisionless
        gas); the transport's CFL limit is
        :meth:`~granframe.run.description.Space.transport_limit`."""
        if self.equation is None:
            return None
        return step_limit(self.collision_integrator, self.equation, self.f0)

    def check_step(self) -> None:
        if self.equation is not None:
            check_step(self.description, self.collision_integrator, self.equation, self.f0)
