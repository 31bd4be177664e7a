"""A space-inhomogeneous run: the runner's loop with the split step, fields and blocks.

:class:`SpaceSimulation` is what :class:`~granframe.run.runner.Simulation` makes of a
description with a ``space`` section. It keeps the runner's schedule, store, commits,
resume, lock and health checks, and replaces what is per distribution:

- the state is a block array (:class:`~granframe.space.transport.CellBlocks`), stepped by
  :class:`~granframe.space.collisions.SplitStep` (Strang: transport, collisions on all
  cells in one batched call per stage, transport);
- after every step the fields of every cell (:class:`~granframe.space.fields.FieldMoments`),
  the totals, and the mass and energy that entered through each wall over the step are
  recorded (:func:`space_layout`);
- a snapshot is f(x, v) of every cell, chunked by block;
- at each output point the accuracy monitors are the shares of mass and energy beyond the
  edge radius in the worst cell (:class:`~granframe.run.monitors.CellEdgeMonitors`).
"""

from __future__ import annotations

import numpy

from granframe.memory import check_run_memory
from granframe.model.initial import check_fits, check_projection
from granframe.run.monitors import CellEdgeMonitors
from granframe.run.runner import (HealthObserver, Observer, ProgressObserver, Simulation,
                                  StorageObserver, Stopped, _Records)
from granframe.run.storage import STEP_RECORDS, Layout, RecordArray
from granframe.space.collisions import CellCollisions, SplitStep
from granframe.space.fields import FIELDS, FieldMoments
from granframe.space.initial import cell_edges, initial_cells
from granframe.space.transport import CellBlocks, Transport
from granframe.validators import reject

#: the totals recorded after every step (scalars over the whole interval)
TOTALS = ("mass", "kinetic_energy", "min_f", "negative_mass_fraction")
#: what entered the interval through each wall over each step (mass, energy)
WALL_RECORDS = ("wall_mass", "wall_energy")


def space_layout(grid, space, block: int) -> Layout:
    """The store of a space run: f (time, x, v1, ..., vd) chunked by snapshot and block,
    the coordinates v1 ... vd and x (the cell centres), and after every step the totals,
    the fields (step_time, x, ...) and the wall records (step_time, wall)."""
    d = grid.dimension
    axes = tuple(f"v{i + 1}" for i in range(d))
    dx = space.length / space.cells
    centres = (numpy.arange(space.cells) + 0.5) * dx
    chunk = max(1, 4096 // space.cells)
    fields = tuple(RecordArray(name, (space.cells,) + tuple(d if c == "d" else c for c in shape),
                               ("x",) + dims, chunk=chunk)
                   for name, (shape, dims) in FIELDS.items())
    walls = tuple(RecordArray(name, (2,), ("wall",)) for name in WALL_RECORDS)
    points = grid.points()
    return Layout(tuple((name, points, (name,)) for name in axes) + (("x", centres, ("x",)),),
                  (space.cells,) + tuple(grid.shape), (block,) + tuple(grid.shape),
                  ("x",) + axes,
                  STEP_RECORDS + tuple(RecordArray(n) for n in TOTALS) + fields + walls,
                  space={"cells": space.cells, "length": space.length, "block_cells": block})


class _WallObserver(Observer):
    """After every step: the mass and energy that entered through each wall over it."""

    def __init__(self, transport):
        self.transport = transport

    def after_step(self, state):
        totals = self.transport.take_wall_totals()
        state.record["wall_mass"] = totals[:, 0]
        state.record["wall_energy"] = totals[:, 1]


class SpaceSimulation(Simulation):
    """Everything a space run needs, built once from a description with a ``space`` section.

    f0 is sampled as cell averages (:mod:`granframe.space.initial`; a space-homogeneous
    condition is uniform in x), checked in every cell against the grid (non-negative,
    finite, inside the box, its intended mass) and projected cell by cell onto the
    Nyquist-free modes, all before anything is written.
    """

    def __init__(self, description):
        if getattr(description, "space", None) is None:
            reject("SpaceSimulation", "description", description,
                   "must have a space section", error=TypeError)
        self.description = d = description
        self.grid = grid = d.grid
        space = d.space
        parts = d.build("space")
        self.reconstruction, self.left, self.right = (parts["reconstruction"], parts["left"],
                                                      parts["right"])
        self.backend = d.build("backend")
        xp = self.backend.xp
        collide = space.collisions
        check_run_memory(d, self.backend)
        self.operator = self._build_operator() if collide else None
        collision_integrator = d.build("integrator") if collide else None
        block = space.blocks(self.reconstruction.ghost)
        self.blocks = CellBlocks(space.cells, block, self.reconstruction.ghost, grid, xp)
        self.transport = Transport(self.blocks, self.reconstruction, self.left, self.right,
                                   space.length)
        self.edges = cell_edges(space)
        self.f0 = self._initial()
        self.equation = (CellCollisions(self.operator, d.heat_bath, d.knudsen) if collide
                         else None)
        if collide:
            self._check_step_limit(collision_integrator, self.equation, self.f0)
        self.integrator = SplitStep(collision_integrator, self.transport, self.blocks)
        self.fields = FieldMoments(grid, space.length / space.cells, xp)

    def _initial(self):
        """f0 as cell averages (cells, *grid.shape), checked and projected cell by cell.

        Sets :attr:`projection`, the moments before and after the Nyquist projection of
        the cell they change most (:func:`~granframe.model.initial.check_projection`, which
        refuses a cell the grid does not resolve).
        """
        d, grid = self.description, self.grid
        initial = d.build("initial")
        sampled, masses = initial_cells(d)
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
                                 f"{0.5 * (self.edges[index] + self.edges[index + 1]):.6g})"
                                 ) from None
            change = max(abs(m["after"] / m["before"] - 1.0) for m in moments.values())
            if change > worst:
                worst, self.projection = change, moments
        return numpy.stack(projected)

    # -- what differs from a space-homogeneous run -----------------------------------------
    def _layout(self):
        return space_layout(self.grid, self.description.space, self.blocks.block_cells)

    def _state(self, f_host):
        return self.blocks.from_cells(self.backend.asarray(f_host))

    def _snapshot(self, array):
        return self.backend.to_numpy(self.blocks.to_cells(array))

    def _record(self, array) -> dict:
        record = self.fields(self.blocks.to_cells(array))
        record.update({"wall_mass": numpy.zeros(2), "wall_energy": numpy.zeros(2)})
        return record

    def _new_records(self):
        return _Records(TOTALS + tuple(FIELDS) + WALL_RECORDS)

    def _observers(self, store, state, progress) -> list:
        d = self.description
        records = self._new_records()
        monitors = CellEdgeMonitors(d, store.progress.get("accuracy"))
        return [_FieldsObserver(self), _WallObserver(self.transport), _AddRecord(records),
                HealthObserver(d.health), _Progress(state, d.final_time, progress),
                _EdgeObserver(self, monitors), StorageObserver(store, records, self._snapshot)]


class _FieldsObserver(Observer):
    """After every step: the fields and totals of every cell into ``state.record``."""

    def __init__(self, simulation):
        self.simulation = simulation

    def after_step(self, state):
        state.record = self.simulation._record(state.f)


class _EdgeObserver(Observer):
    """At every output point: the largest edge shares over the cells
    (:class:`~granframe.run.monitors.CellEdgeMonitors`) into ``state.accuracy``, which the
    next commit keeps; with ``health.stop_on_accuracy`` one above
    ``health.accuracy_tolerance`` stops the run."""

    def __init__(self, simulation, monitors):
        self.simulation, self.monitors = simulation, monitors

    def at_output(self, state, final):
        simulation, monitors = self.simulation, self.monitors
        cells = simulation.blocks.to_cells(state.f)
        problem = monitors.update(monitors.shape(cells, state.record["velocity"],
                                                 simulation.backend.xp), state.step, state.t)
        state.accuracy = monitors.report()
        if problem is not None:
            raise Stopped(f"health check failed at step {state.step}, t = {state.t:.6g}: "
                          f"{problem}")


class _AddRecord(Observer):
    """After every step: the step's record into the records of the next commit."""

    def __init__(self, records):
        self.records = records

    def after_step(self, state):
        self.records.add(state.step, state.t, state.dt, state.record)


def _cell(condition, mass):
    """One cell of ``condition`` for :func:`check_fits`: its intended mass, under the
    condition's name (which the messages show)."""
    return type(type(condition).__name__, (), {"intended_mass": mass})()


class _Progress(ProgressObserver):
    """The progress bar of a space run: t, step, the range of T over the cells and the
    drift of the total mass."""

    def after_step(self, state):
        self.bar.update(min(state.t, self.bar.total) - self.bar.n)
        t = state.record["temperature"]
        self.bar.set_postfix_str(f"step {state.step}, T in [{numpy.nanmin(t):.4g}, "
                                 f"{numpy.nanmax(t):.4g}], mass drift "
                                 f"{state.record['mass'] / state.mass0 - 1:+.1e}", refresh=False)
