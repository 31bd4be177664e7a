r"""The collision step of a space run with a hierarchy of collision models
(:mod:`granframe.space.hierarchy`): :class:`HybridCollisions`, and what the factories of its
levels receive, :class:`HierarchyContext`.
"""

from __future__ import annotations

import functools
import time

import attrs
import numpy

from granframe.backends import to_host
from granframe.space.hierarchy.choice import choose_levels
from granframe.space.hierarchy.indicators import equilibrium_distance, realizability
from granframe.space.hierarchy.levels import FluidParts
from granframe.space.hierarchy.rates import relaxation_rate, scaled_rates


@attrs.define(slots=False)
class HierarchyContext:
    """What a :class:`~granframe.abc.CollisionModel` factory receives: the run's
    ``equation`` (:class:`~granframe.space.collisions.CellCollisions`), its time
    ``integrator`` and ``temperature``, the mass-weighted mean temperature of f0."""

    equation: object
    integrator: object
    temperature: float

    def _coefficient(self, mode: str) -> float:
        operator = self.equation.operator
        kernel, d = operator.kernel, operator.grid.dimension
        rate = relaxation_rate(operator, mode, self.temperature)
        factor = (kernel.energy_factor(0.5 * d * self.temperature)
                  if kernel.energy_exponent else 1.0)
        return rate / (self.temperature ** (kernel.speed_exponent / 2) * factor)

    @functools.cached_property
    def shear_coefficient(self) -> float:
        """c of nu_s = c rho T^(lambda/2) E^gamma, from
        :func:`~granframe.space.hierarchy.rates.relaxation_rate` of the run's operator at
        :attr:`temperature` (computed once per run)."""
        return self._coefficient("shear")

    @functools.cached_property
    def heat_coefficient(self) -> float:
        """c of nu_q = c rho T^(lambda/2) E^gamma
        (:func:`~granframe.space.hierarchy.rates.relaxation_rate`, "heat")."""
        return self._coefficient("heat")


class HybridCollisions:
    """The collision step of a space run with a hierarchy (see the package notes).

    Every ``interval`` steps the levels of all cells are chosen (:func:`~granframe.space.hierarchy.choice.choose_levels`)
    from the indicators of every cell, gathered over the processes (one
    :meth:`~granframe.abc.Communicator.allgather_object` of a few numbers per cell), so that
    every process decides the same levels; then each level advances its own cells of this
    process, gathered into one batch (one batched call of the full operator per stage on
    the kinetic cells only).

    Parameters
    ----------
    settings : granframe.run.description.Hierarchy
    models : list of CollisionModel
        The levels, from the cheapest to the full operator.
    equation : CellCollisions
    cells, owned : int, slice
        All cells of the interval, those of this process.
    dx : float
    periodic : bool
    communicator : Communicator
    """

    def __init__(self, settings, models, context, cells: int, owned: slice, dx: float,
                 periodic: bool, communicator, time_step: float):
        equation = context.equation
        self.settings, self.models, self.equation = settings, models, equation
        self.owned, self.dx, self.periodic = owned, float(dx), periodic
        self.communicator = communicator
        self.parts = FluidParts(equation)
        self.kernel = equation.operator.kernel
        self.shear_coefficient = context.shear_coefficient
        #: delta_inf, the distance from its Maxwellian of the uniform state the full level
        #: tends to (:func:`~granframe.space.hierarchy.indicators.equilibrium_distance`): 0 for an elastic gas without heat bath
        self.floor = (0.0 if self.parts.cooling.elastic and not self.parts.heat_bath
                      else equilibrium_distance(context, time_step))
        #: the level of every cell in the last step (all at the top before the first)
        self.levels = numpy.full(cells, len(models) - 1, dtype=numpy.int64)
        #: collision steps taken (decisions fall on multiples of the interval)
        self.steps = 0
        #: the indicators of all cells after the last collision step and the cells each
        #: one's level reaches (None before)
        self.kappa = self.delta = self.reach = None
        #: wall seconds spent choosing the levels, and per level advancing cells
        self.choice_seconds = 0.0

    @property
    def owned_levels(self) -> numpy.ndarray:
        return self.levels[self.owned]

    def indicators(self, f):
        """(rho, u, T, delta, realizable) of every cell of this process, on the host in one
        transfer: the moments and delta = sum |f - M[f]| h^d / rho."""
        xp, d, grid = self.parts.xp, self.parts.grid.dimension, self.parts.grid
        rho, velocity, temperature, _ = self.parts.moments.primitives(f, node="halves")
        now, _, ok = self.parts.equilibria(f, None)
        axes = tuple(range(1, d + 1))
        distance = xp.abs(f - now).sum(axis=axes) * grid.cell_volume / xp.where(
            rho > 0, rho, 1.0)
        return to_host(xp.concatenate([rho[:, None], velocity, temperature[:, None],
                                       distance[:, None], ok[:, None].astype(float)],
                                      axis=1))

    def measure(self, f) -> None:
        """The indicators kappa and delta of all cells (:attr:`kappa`, :attr:`delta`;
        delta is NaN where there is no equilibrium) from f of this process's cells, the
        rows of all processes gathered in rank order."""
        rows = self.indicators(f)
        if self.communicator.size > 1:
            rows = numpy.concatenate(self.communicator.allgather_object(rows))
        d = self.parts.grid.dimension
        rho, velocity, temperature = rows[:, 0], rows[:, 1:1 + d], rows[:, 1 + d]
        valid = (rows[:, 3 + d] > 0.5) & (rho > 0) & (temperature > 0)
        safe_rho = numpy.where(valid, rho, 1.0)
        safe_t = numpy.where(valid, temperature, 1.0)
        energy = 0.5 * safe_rho * ((velocity ** 2).sum(axis=1) + d * safe_t)
        rate = scaled_rates(self.shear_coefficient, self.kernel, safe_rho, safe_t, energy)
        kappa = realizability(safe_rho, velocity, safe_t, self.dx, self.periodic,
                              self.equation.knudsen, rate)
        self.kappa = numpy.where(valid, kappa, numpy.inf)
        #: the cells each cell's level reaches on each side: the buffer, or the distance
        #: free_paths x eps sqrt(2T)/nu_s that particles of the thermal speed fly between
        #: collisions, whichever is larger
        path = self.settings.free_paths * self.equation.knudsen * numpy.sqrt(2 * safe_t) / rate
        self.reach = numpy.maximum(self.settings.buffer, numpy.ceil(path / self.dx - 1e-9)
                                   ).astype(numpy.int64)
        fluid = self.levels < len(self.models) - 1
        self.delta = numpy.where(valid, numpy.where(fluid, numpy.maximum(rows[:, 2 + d],
                                                                          self.floor),
                                                    rows[:, 2 + d]), numpy.nan)

    def choose(self) -> None:
        """The levels of all cells from :attr:`kappa` and :attr:`delta`
        (:func:`~granframe.space.hierarchy.choice.choose_levels`)."""
        s = self.settings
        realizable = numpy.isfinite(self.kappa) & numpy.isfinite(self.delta)
        self.levels = choose_levels(self.levels, numpy.where(realizable, self.kappa, 0.0),
                                    numpy.where(realizable, self.delta, 0.0), realizable,
                                    s.realizability, s.distance, s.hysteresis, self.reach,
                                    self.periodic)

    def records(self) -> dict:
        """The level of every owned cell in the last step and its indicators and reach after
        it: what the store keeps (``level``, ``realizability``, ``distance``, ``reach``)
        and a resumed run takes up (:meth:`take_up`); NaN indicators and the buffer as
        reach before the first step."""
        owned = self.owned
        count = owned.stop - owned.start
        if self.kappa is None:
            return {"level": self.levels[owned].copy(),
                    "realizability": numpy.full(count, numpy.nan),
                    "distance": numpy.full(count, numpy.nan),
                    "reach": numpy.full(count, self.settings.buffer, dtype=numpy.int64)}
        return {"level": self.levels[owned].copy(), "realizability": self.kappa[owned].copy(),
                "distance": self.delta[owned].copy(), "reach": self.reach[owned].copy()}

    def take_up(self, steps: int, levels, kappa, delta, reach) -> None:
        """Continue after ``steps`` steps with the recorded levels, indicators and reach of
        all cells (NaN indicators: none measured yet)."""
        self.steps = int(steps)
        self.levels = numpy.asarray(levels, dtype=numpy.int64)
        kappa = numpy.asarray(kappa, dtype=float)
        measured = not numpy.isnan(kappa).all()
        self.kappa = kappa if measured else None
        self.delta = numpy.asarray(delta, dtype=float) if measured else None
        self.reach = numpy.asarray(reach, dtype=numpy.int64) if measured else None

    def advance(self, f, t: float, dt: float):
        """f (owned cells, *grid.shape) after the collision step: on a multiple of the
        interval the levels are chosen from the indicators measured after the previous
        collision step (of f itself before the first), then each level advances its cells,
        and the indicators of the result are measured for the next choice."""
        xp = self.parts.xp
        began = time.perf_counter()
        if self.steps % self.settings.interval == 0:
            if self.kappa is None:
                self.measure(f)
            self.choose()
        self.choice_seconds += time.perf_counter() - began
        self.steps += 1
        levels = self.owned_levels
        top = len(self.models) - 1
        if (levels == top).all():
            out = self.models[top].advance(f, t, dt)
        else:
            out = f.copy()
            for k, model in enumerate(self.models):
                cells = numpy.flatnonzero(levels == k)
                if cells.size:
                    index = xp.asarray(cells)
                    out[index] = model.advance(f[index], t, dt)
        began = time.perf_counter()
        self.measure(out)
        self.choice_seconds += time.perf_counter() - began
        return out
