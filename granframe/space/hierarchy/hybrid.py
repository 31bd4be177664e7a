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
from granframe.space.hierarchy.indicators import CellGrid, CellIndicators
from granframe.space.hierarchy.rates import CoolingRate, StepRates, relaxation_rate


@attrs.define(slots=False)
class HierarchyContext:
    """What a :class:`~granframe.abc.CollisionModel` factory receives: the run's
    ``equation`` (:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`), its time
    ``integrator`` and ``temperature``, the mass-weighted mean temperature of f0; and the
    hierarchy's :attr:`rates`."""

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
    def rates(self) -> StepRates:
        """The fastest rates of the temperature law over the cells at the start of the step
        (:class:`~granframe.space.hierarchy.rates.StepRates`), one for all levels, which
        :meth:`HybridCollisions.follow` keeps up to date."""
        equation = self.equation
        operator = equation.operator
        cooling = CoolingRate(operator.kernel, operator.restitution, operator.grid)
        return StepRates(cooling, equation.knudsen, equation.heat.tau)

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

    Every ``interval`` steps the levels of all cells are chosen
    (:func:`~granframe.space.hierarchy.choice.choose_levels`) from the indicators of every
    cell (:class:`~granframe.space.hierarchy.indicators.CellIndicators`); then each level
    advances its own cells of this process, gathered into one batch (one batched call of
    the full operator per stage on the kinetic cells only).

    Indicators and choice run on the backend. The batches are a host decision (their
    sizes), so the levels come to the host: with the indicators of the step's result, and
    the levels of the next step chosen ahead from them when that step chooses, in one
    device->host copy of one vector per step (:meth:`advance`); that copy also gives
    :meth:`records`. Nothing is copied to the device: the cells of each level are slices of
    one stable argsort of the levels on the device. With several processes the rows of
    indicators are gathered on the host (one
    :meth:`~granframe.abc.Communicator.allgather_object` of a few numbers per cell), so that
    every process decides the same levels, and the choice runs there.

    Parameters
    ----------
    settings : granframe.run.description.Hierarchy
    models : list of CollisionModel
        The levels, from the cheapest to the full operator.
    context : HierarchyContext
    cells : CellGrid
        All cells of the interval or the rectangle.
    owned : slice or integer array
        Those of this process, in the order of its f, as indices into all cells in C order
        (a slice on an interval; on a rectangle the block's cells, an array unless the
        process owns them all).
    communicator : Communicator
    time_step : float
    """

    def __init__(self, settings, models, context, cells: CellGrid, owned, communicator,
                 time_step: float):
        self.settings, self.models, self.equation = settings, models, context.equation
        self.owned, self.communicator, self.context = owned, communicator, context
        #: kappa, delta and the reach of every cell, on the backend
        self.cells = CellIndicators(settings, context, cells, time_step)
        # where the rows of each process go among all cells (None: in rank order already)
        self._places = None
        if communicator.size > 1:
            places = numpy.concatenate(communicator.allgather_object(
                numpy.arange(cells.total)[owned]))
            if not numpy.array_equal(places, numpy.arange(cells.total)):
                self._places = places
        self.xp = self.cells.parts.xp
        #: where the choice runs: the backend, or the host with several processes
        self.choice_xp = numpy if communicator.size > 1 else self.xp
        top = len(models) - 1
        #: the level of every cell in the last step (all at the top before the first), on
        #: the host
        self.levels = numpy.full(cells.total, top, dtype=numpy.int64)
        #: collision steps taken (decisions fall on multiples of the interval)
        self.steps = 0
        #: the indicators of all cells after the last collision step and the cells each
        #: one's level reaches, on the host (None before)
        self.kappa = self.delta = self.reach = None
        #: wall seconds spent measuring the indicators and choosing the levels
        self.choice_seconds = 0.0
        self._levels = self.choice_xp.full(cells.total, top, dtype=numpy.int64)
        self._measured = None       # (kappa, delta, reach) in choice_xp, or None
        self._next = None           # the levels chosen ahead for the next step, or None
        self._order = None          # the owned cells sorted by level, on the backend
        self._pending = None        # what the last step leaves to bring to the host, or None
        self._chosen = None         # the levels it chose for the next step, in choice_xp

    @property
    def owned_levels(self) -> numpy.ndarray:
        return self.levels[self.owned]

    def _measure(self, f):
        """(kappa, delta, reach) of all cells in :attr:`choice_xp` from f of this process's
        cells (:class:`~granframe.space.hierarchy.indicators.CellIndicators`), the rows of
        all processes gathered and put in the order of the cells."""
        rows = self.cells.rows(f)
        if self.communicator.size > 1:
            rows = numpy.concatenate(self.communicator.allgather_object(to_host(rows)))
            if self._places is not None:
                placed = numpy.empty_like(rows)
                placed[self._places] = rows
                rows = placed
        fluid = self._levels < len(self.models) - 1
        return self.cells.measure(rows, fluid, self.choice_xp)

    def _choose(self):
        """The levels chosen from :attr:`_levels` and the measured indicators
        (:func:`~granframe.space.hierarchy.choice.choose_levels`), in
        :attr:`choice_xp`."""
        s, xp = self.settings, self.choice_xp
        kappa, delta, reach = self._measured
        realizable = xp.isfinite(kappa) & xp.isfinite(delta)
        cells = self.cells.grid_of_cells
        return choose_levels(self._levels, xp.where(realizable, kappa, 0.0),
                             xp.where(realizable, delta, 0.0), realizable, s.realizability,
                             s.distance, s.hysteresis, reach, cells.periodic, xp,
                             cells.counts)

    def _fetch(self, **arrays) -> dict:
        """The arrays (in :attr:`choice_xp`) on the host, in one copy of one vector; the
        integer ones (levels, reach) come back as int64."""
        return self._split(arrays, to_host(self._joined(arrays)))

    def _joined(self, arrays: dict):
        """The arrays (in :attr:`choice_xp`) as one float vector, in :attr:`choice_xp`."""
        return self.choice_xp.concatenate([a.astype(float) for a in arrays.values()])

    @staticmethod
    def _split(arrays: dict, vector) -> dict:
        """The host ``vector`` of :meth:`_joined` cut back into the arrays, each with its
        own dtype."""
        parts = numpy.split(vector, numpy.cumsum([len(a) for a in arrays.values()])[:-1])
        return {name: part.astype(a.dtype) for (name, a), part in zip(arrays.items(), parts)}

    def pending(self):
        """What the last step leaves to bring to the host (its indicators and, when the next
        step chooses, the levels chosen), as one device vector for the caller to take to
        the host with its own copy and hand back to :meth:`receive`; None when nothing is
        left (with several processes the choice runs on the host and nothing is left)."""
        return None if self._pending is None else self._joined(self._pending)

    def receive(self, vector) -> None:
        """Take the host copy of :meth:`pending`'s vector: the indicators, reach and the
        levels chosen for the next step."""
        arrays, self._pending = self._pending, None
        self._take(self._split(arrays, numpy.asarray(vector, dtype=float)), "levels" in arrays)

    def _settle(self) -> None:
        """Bring what the last step left to the host now (one copy), if no one took it."""
        if self._pending is not None:
            self.receive(to_host(self.pending()))

    def _take(self, host: dict, chosen: bool) -> None:
        """The indicators and reach of ``host`` as the last measured ones on the host, and
        its levels (with ``chosen``) as those of the next step."""
        self._take_measured(host)
        self._next = (self._chosen, host["levels"]) if chosen else None

    def _take_measured(self, host: dict) -> None:
        """The indicators and reach of ``host`` as the last measured ones on the host."""
        self.kappa, self.delta, self.reach = host["kappa"], host["delta"], host["reach"]

    def _bring(self, measured: bool, chosen=None):
        """One copy to the host: with ``measured`` the indicators last measured
        (:attr:`kappa`, :attr:`delta`, :attr:`reach`), and the levels ``chosen`` (in
        :attr:`choice_xp`), whose host copy is returned (None without)."""
        arrays = dict(zip(("kappa", "delta", "reach"), self._measured)) if measured else {}
        if chosen is not None:
            arrays["levels"] = chosen
        host = self._fetch(**arrays)
        if measured:
            self._take_measured(host)
        return host.get("levels")

    def _adopt(self, levels, host) -> None:
        """Take ``levels`` (in :attr:`choice_xp`) and their ``host`` copy as the levels of
        the cells, and the owned cells sorted by level (stable: each level's cells in
        increasing order) on the backend."""
        self._levels, self.levels = levels, host
        owned = levels[self.owned]
        if self.choice_xp is not self.xp:
            owned = self.xp.asarray(owned)
        self._order = self.xp.argsort(owned, kind="stable")

    def measure(self, f) -> None:
        """The indicators kappa and delta of all cells (:attr:`kappa`, :attr:`delta`;
        delta is NaN where there is no equilibrium) and the reach of every cell from f of
        this process's cells, on the host."""
        self._settle()
        self._measured, self._next = self._measure(f), None
        self._bring(True)

    def choose(self) -> None:
        """The levels of all cells (:attr:`levels`) from the indicators of the last
        :meth:`measure` or step."""
        self._settle()
        levels, self._next = self._choose(), None
        self._adopt(levels, self._bring(False, levels))

    def records(self) -> dict:
        """The level of every owned cell in the last step and its indicators and reach after
        it: what the store keeps (``level``, ``realizability``, ``distance``, ``reach``)
        and a resumed run takes up (:meth:`take_up`); NaN indicators and the buffer as
        reach before the first step."""
        self._settle()
        owned = self.owned
        count = len(self.levels[owned])
        if self.kappa is None:
            return {"level": self.levels[owned].copy(),
                    "realizability": numpy.full(count, numpy.nan),
                    "distance": numpy.full(count, numpy.nan),
                    "reach": numpy.full(count, self.settings.buffer, dtype=numpy.int64)}
        return {"level": self.levels[owned].copy(), "realizability": self.kappa[owned].copy(),
                "distance": self.delta[owned].copy(), "reach": self.reach[owned].copy()}

    def follow(self, density, velocity, temperature) -> None:
        """The fields of the owned cells of a step's record (on the host) as the start of
        the next step: the fastest rates of the temperature law, from which the fluid levels
        take their substeps (:class:`~granframe.space.hierarchy.rates.StepRates`)."""
        self.context.rates.follow(density, velocity, temperature, self.communicator)

    def take_up(self, steps: int, levels, kappa, delta, reach) -> None:
        """Continue after ``steps`` steps with the recorded levels, indicators and reach of
        all cells (NaN indicators: none measured yet), copied to the device at the resume."""
        xp = self.choice_xp
        self._pending = None
        self.steps = int(steps)
        self.levels = numpy.asarray(levels, dtype=numpy.int64)
        self._adopt(xp.asarray(self.levels), self.levels)
        kappa = numpy.asarray(kappa, dtype=float)
        measured = not numpy.isnan(kappa).all()
        self.kappa = kappa if measured else None
        self.delta = numpy.asarray(delta, dtype=float) if measured else None
        self.reach = numpy.asarray(reach, dtype=numpy.int64) if measured else None
        self._measured = (tuple(xp.asarray(a) for a in (self.kappa, self.delta, self.reach))
                          if measured else None)
        self._next = None

    def advance(self, f, t: float, dt: float):
        """f (owned cells, *grid.shape) after the collision step: on a multiple of the
        interval the levels are taken (chosen ahead at the end of the previous step; at the
        first step, or after :meth:`take_up`, chosen now from the indicators measured after
        the previous collision step, of f itself before the first), then each level
        advances its cells, the indicators of the result are measured and, when the next
        step chooses, its levels chosen from them. All of it comes to the host in one copy:
        the record's, when the caller takes :meth:`pending` with it (a space run's record,
        which follows every step), else its own at the next step or :meth:`records`.
        """
        began = time.perf_counter()
        self._settle()
        if self.steps % self.settings.interval == 0:
            if self._next is not None:
                self._adopt(*self._next)
            else:
                if self._measured is None:
                    self._measured = self._measure(f)
                self.choose()
        self.choice_seconds += time.perf_counter() - began
        self.steps += 1
        out = self._advance_levels(f, t, dt)
        began = time.perf_counter()
        self._measured = self._measure(out)
        chosen = self._choose() if self.steps % self.settings.interval == 0 else None
        arrays = dict(zip(("kappa", "delta", "reach"), self._measured))
        if chosen is not None:
            arrays["levels"] = chosen
        self._pending, self._chosen = arrays, chosen
        if self.choice_xp is not self.xp:        # on the host already: nothing to carry
            self._settle()
        self.choice_seconds += time.perf_counter() - began
        return out

    def _advance_levels(self, f, t: float, dt: float):
        """f after each level has advanced its own cells, gathered into one batch per
        level in use (all of f when every cell is at the top)."""
        levels = self.owned_levels
        top = len(self.models) - 1
        if (levels == top).all():
            return self.models[top].advance(f, t, dt)
        out = f.copy()
        bounds = numpy.cumsum(numpy.bincount(levels, minlength=len(self.models)))
        for model, start, stop in zip(self.models, numpy.r_[0, bounds[:-1]], bounds):
            if stop > start:
                index = self._order[int(start):int(stop)]
                out[index] = model.advance(f[index], t, dt)
        return out
