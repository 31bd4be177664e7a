"""The problem of every run: d_t f + v . grad_x f = Q(f, f)/eps (+ tau Delta_v f) on the cells
of a space of zero, one or two dimensions (docs/space.md, docs/architecture.md).

A space-homogeneous run is the case of zero space dimensions: one cell, no transport, one
process (:class:`~granframe.run.problems.spaces.Point`); a description with a ``space``
section has the cells of an interval (:class:`~granframe.run.problems.spaces.Interval`) or
of a rectangle (:class:`~granframe.run.problems.spaces.Rectangle`).
The collision operator, the equation (one per collision model, acting on a batch of cells:
a space-homogeneous run is a batch of none), its rescaled form, the hierarchy of collision
models, the step limits and the commit are built here once for both; the shape of the space
gives the state, the step around the collisions, the records, the store layout and the
output-point report.
"""

from __future__ import annotations

import numpy

from granframe.abc import Problem, deferred_checks
from granframe.backends import NumpyBackend
from granframe.equations.conservative import ConservativeCorrection
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.equations.rescaled import RescaledBoltzmann
from granframe.memory import check_run_memory
from granframe.parallel import in_every_process
from granframe.registry import default_registries
from granframe.run.description import RunDescription
from granframe.run.problems.parts import build_operator, check_step
from granframe.run.problems.spaces import (LEVEL_RECORDS, WALL_RECORDS, Interval, Point,
                                           Rectangle, space_layout)
from granframe.space.collisions import FreeFlight, LevelledModels, SingleModel
from granframe.space.hierarchy import HierarchyContext, HybridCollisions
from granframe.stepping.stability import OperatorOutline, step_limit
from granframe.validators import reject
from granframe.velocity.moments import FieldMoments

__all__ = ["LEVEL_RECORDS", "WALL_RECORDS", "SpaceProblem", "space_layout"]


class SpaceProblem(Problem):
    """A run, built once from a description (:class:`granframe.abc.Problem`; see the module
    notes): of zero space dimensions without a ``space`` section, else of one.

    f0 is sampled as cell averages (:mod:`granframe.space.initial`; a space-homogeneous
    condition is uniform in x), checked in every cell against the grid (non-negative,
    finite, inside the box, its intended mass) and projected cell by cell onto the
    Nyquist-free modes, all before anything is written. With ``outline`` the operator is
    an :class:`~granframe.stepping.stability.OperatorOutline` (nothing precomputed, on
    NumPy), which is all that :meth:`step_limit` reads; f0 is then not checked. A run in
    space is spread over the processes of ``communicator`` (by default
    :func:`granframe.parallel.world`), ``partition_cells`` the cells of each
    (:func:`granframe.parallel.partition`); one of zero dimensions runs in one process.
    """

    def __init__(self, description, outline: bool = False, communicator=None,
                 partition_cells=None):
        if not isinstance(description, RunDescription):
            reject("SpaceProblem", "description", description, "must be a RunDescription",
                   error=TypeError)
        self.description = d = description
        self.grid = grid = d.grid
        shape = Point if d.space is None else Interval if d.space.dimension == 1 else Rectangle
        #: the space the cells fill (:mod:`granframe.run.problems.spaces`)
        self.space = space = shape(d, outline, communicator, partition_cells)
        self.communicator = comm = space.communicator
        self.ranges = space.ranges
        collide = space.collisions
        if outline:          # its f0 alone is a copy of every cell's f: the run's check first
            check_run_memory(d, None, cells=space.owned_cells)
            self.backend = NumpyBackend(threads=1)
            self.operator = OperatorOutline(grid, d.build("kernel"), d.build("restitution"),
                                            self.backend) if collide else None
        else:
            self.backend = d.build("backend").for_process(comm.local_rank)
            check_run_memory(d, self.backend, cells=space.owned_cells, share=comm.local_size)
            self.operator = build_operator(d, self.backend) if collide else None
        self.collision_integrator = d.build("integrator") if collide else None
        space.build(grid, self.backend)
        self.domain, self.transport, self.fields = space.domain, space.transport, space.fields
        self.left, self.right = space.left, space.right
        self.reconstruction, self.cell_layout = space.reconstruction, space.cell_layout
        # the initial data are the user's code, which may fail in one process only
        self.f0, self.projection = in_every_process(
            comm, lambda: space.initial(check=not outline))
        self.equation = (None if not collide else self._rescaled(outline) if d.rescaled
                         else HomogeneousBoltzmann(self.operator, d.heat_bath, d.knudsen))
        #: the map of a rescaled run to physical variables (kept in the store), or None
        self.rescaling = self.equation.rescaling if collide and d.rescaled else None
        #: the hierarchy of collision models (None: the full operator in every cell)
        self.hierarchy = None if outline else self._hierarchy()
        stage = (FreeFlight() if not collide else
                 SingleModel(self.collision_integrator, self.equation) if self.hierarchy is None
                 else LevelledModels(self.hierarchy))
        self.integrator = space.integrator(stage, self.collision_integrator, self.rescaling)

    @property
    def reduction_seconds(self) -> float:
        """Wall seconds of the reductions of the records over the processes (settable: a
        timing resets it after the warm-up steps)."""
        return self.space.reduction_seconds

    @reduction_seconds.setter
    def reduction_seconds(self, seconds: float) -> None:
        self.space.reduction_seconds = float(seconds)

    def _rescaled(self, outline: bool):
        """The :class:`~granframe.equations.rescaled.RescaledBoltzmann` of the owned cells of
        f0 (u = 0 along the space axes); with ``outline`` its a_0 from the closed-form
        dissipation of every cell
        (:meth:`~granframe.equations.conservative.ConservativeCorrection.dissipation` of
        the :class:`~granframe.stepping.stability.OperatorOutline`)."""
        d, xp = self.description, self.backend.xp
        cells = self.f0[self.owned]
        dissipation = None
        if outline:
            correction = ConservativeCorrection(self.operator)
            dissipation = numpy.array([float(correction.dissipation(f)) for f in
                                       cells.reshape((-1,) + tuple(self.grid.shape))])
        return RescaledBoltzmann(self.operator, xp.asarray(cells), d.knudsen,
                                 dissipation=dissipation, communicator=self.communicator,
                                 transport_axes=self.space.dimension)

    def _hierarchy(self):
        """The :class:`~granframe.space.hierarchy.HybridCollisions` of ``space.hierarchy``,
        its levels built from the registry with the run's equation, integrator and the
        mass-weighted mean temperature of f0."""
        space = self.description.space
        settings = None if space is None else space.hierarchy
        if settings is None or self.equation is None:
            return None
        cells = self.f0.reshape((-1,) + tuple(self.grid.shape))
        moments = FieldMoments(self.grid, 1.0)(cells)
        rho, temperature = moments["density"], moments["temperature"]
        context = HierarchyContext(self.equation, self.collision_integrator,
                                   float((rho * temperature).sum() / rho.sum()))
        registries = default_registries()
        models = [registries.create("collision_models", level.name, context=context,
                                    **level.params) for level in settings.levels]
        cells, owned = self.space.hierarchy_cells()
        return HybridCollisions(settings, models, context, cells, owned, self.communicator,
                                self.description.time_step)

    @property
    def owned(self) -> slice:
        """The cells this process owns and steps: all of them in a serial run,
        ``slice(None)`` (the whole f) in a run of zero space dimensions."""
        return self.space.owned

    def layout(self):
        return self.space.layout(self.grid, self._levelled)

    @property
    def _levelled(self) -> bool:
        """Whether the description asks for a hierarchy (an outline builds none)."""
        space = self.description.space
        return space is not None and space.hierarchy is not None

    @property
    def record_names(self) -> tuple:
        return self.space.record_names(self._levelled)

    def resume(self, store, step: int) -> None:
        """Take up the levels of the hierarchy where the store's run left them: the level of
        every owned cell in ``step`` (its ``level`` record), the step count that sets when
        the levels are chosen next, and the fields of the owned cells that the substeps of
        the fluid levels follow (:meth:`HybridCollisions.follow
        <granframe.space.hierarchy.HybridCollisions.follow>`), so that a resumed run is the
        uninterrupted one."""
        if self.hierarchy is None:
            return
        records = int(store.progress["records"])
        steps = numpy.asarray(store.group["step"][:records])
        row = int(numpy.flatnonzero(steps == step)[-1])
        axes = self.space.dimension

        def every_cell(name):                  # (cells, ...) in C order, x slowest
            values = numpy.asarray(store.group[name][row])
            return values.reshape((-1,) + values.shape[axes:])

        self.hierarchy.take_up(step, *(every_cell(name) for name in LEVEL_RECORDS))
        owned = self.hierarchy.owned
        self.hierarchy.follow(*(every_cell(name)[owned]
                                for name in ("density", "velocity", "temperature")))

    def state(self, f_host):
        """The stepped state from f on the host: every cell (f0) or the owned ones."""
        return self.space.state(f_host, self.backend)

    def snapshot(self, state):
        """f of the owned cells on the host."""
        return self.space.snapshot(state, self.backend)

    def step(self, t: float, state, dt: float):
        """One step; spread over processes, no check inside it raises in one process alone
        (:func:`~granframe.abc.deferred_checks`): a non-finite f shows in the reduced
        record, and every process stops at that step."""
        with deferred_checks(everywhere=self.communicator.size > 1):
            return self.integrator.step(self.equation, t, state, dt)

    def record(self, state) -> dict:
        """What the store keeps of ``state`` after a step, in one device->host transfer
        (:meth:`Point.record <granframe.run.problems.spaces.Point.record>`,
        :meth:`Interval.record <granframe.run.problems.spaces.Interval.record>`)."""
        return self.space.record(state, self.backend, self.hierarchy)

    def monitors(self, store):
        return self.space.monitors(store, self.operator)

    def report(self, state, record, monitors):
        return self.space.report(state, record, monitors, self.backend)

    def progress_text(self, record, mass0) -> str:
        return self.space.progress_text(record, mass0)

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
