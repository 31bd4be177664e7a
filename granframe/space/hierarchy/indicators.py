r"""The indicators that choose the level of every cell (:mod:`granframe.space.hierarchy`):
the Navier-Stokes realizability indicator kappa (:func:`realizability`), the distance
delta of f from its local equilibrium and the cells each cell's level reaches
(:class:`CellIndicators`), and the distance delta_inf of the uniform state the full level
tends to (:func:`equilibrium_distance`), the floor of delta at the fluid levels.
"""

from __future__ import annotations

import math

import attrs
import numpy

from granframe.backends import to_host
from granframe.space.conserving import conserving_step
from granframe.space.hierarchy.levels import FluidParts
from granframe.space.hierarchy.rates import scaled_rates
from granframe.velocity.guard import guard_moments


def realizability(density, velocity, temperature, spacing, periodic, knudsen: float,
                  rate, xp=numpy, axes=(0,)):
    r"""The Navier-Stokes realizability indicator of every cell (see the package notes),

    .. math:: \kappa = \max\Bigl(\frac{\lVert\sigma\rVert_F}{p},
              \frac{|q|}{p\sqrt T}\Bigr),\qquad
              \sigma_{ij} = -\mu\bigl(\partial_i u_j + \partial_j u_i
              - \tfrac2d\,\delta_{ij}\,\partial_a u_a\bigr),\quad
              q = -\tfrac{d+2}{2}\,\mu\,\nabla T,

    with the derivatives along the cells' space axes only (the others are zero): the
    cells lie on a grid of D axes, shape (C_0, ..., C_{D-1}) for ``density`` and
    ``temperature``, (C_0, ..., d) for ``velocity``; cell axis k has the width
    ``spacing[k]``, is ``periodic[k]`` and lies along the velocity component ``axes[k]``
    (an interval along y: ``axes = (1,)``); one number for ``spacing`` and ``periodic``
    serves every axis. Each derivative is :func:`x_derivative` along its axis; p = rho T,
    mu = eps p / nu_s (``rate``: nu_s of every cell, the cells' shape) and the
    conductivity of a gas of Prandtl number 1 (the BGK closure's, as Filbet & Rey).
    Arrays in ``xp``; kappa has the cells' shape."""
    d = velocity.shape[-1]
    count = len(axes)
    spacing = (spacing,) * count if numpy.ndim(spacing) == 0 else tuple(spacing)
    periodic = (periodic,) * count if numpy.ndim(periodic) == 0 else tuple(periodic)
    gradient = {}                       # velocity component a -> d u / d x_a, (cells..., d)
    heat = 0.0
    for k, a in enumerate(axes):
        gradient[a] = x_derivative(velocity, spacing[k], periodic[k], xp, k)
        heat = heat + x_derivative(temperature, spacing[k], periodic[k], xp, k) ** 2
    divergence = sum(gradient[a][..., a] for a in axes)
    squares = 0.0                       # sum_ij (sigma_ij / mu)^2
    for i in range(d):
        for j in range(i, d):
            entry = (gradient[i][..., j] if i in gradient else 0.0) + \
                (gradient[j][..., i] if j in gradient else 0.0)
            if i == j:
                squares = squares + (entry - (2.0 / d) * divergence) ** 2
            else:
                squares = squares + 2.0 * entry ** 2
    scale = knudsen / rate                                 # mu / p
    stress = scale * xp.sqrt(squares)
    safe_t = xp.where(temperature > 0, temperature, 1.0)
    flux = scale * 0.5 * (d + 2) * xp.sqrt(heat) / xp.sqrt(safe_t)
    return xp.maximum(stress, flux)


def x_derivative(values, dx: float, periodic: bool, xp=numpy, axis: int = 0):
    r"""d/dx of the cell values g (..., cells, ...) along their axis ``axis``: the central
    differences

    .. math:: g'_i = \frac{g_{i+1} - g_{i-1}}{2\,\Delta x},

    across the ends of a ``periodic`` axis, and at a wall the one-sided ones
    (g_1 - g_0)/dx and (g_{C-1} - g_{C-2})/dx (:func:`numpy.gradient`'s, by slices); 0 for
    one cell."""
    values = xp.moveaxis(values, axis, 0)
    if periodic:
        slope = (xp.roll(values, -1, axis=0) - xp.roll(values, 1, axis=0)) / (2 * dx)
    elif len(values) < 2:
        slope = 0.0 * values
    else:
        slope = xp.concatenate([(values[1:2] - values[:1]) / dx,
                                (values[2:] - values[:-2]) / (2.0 * dx),
                                (values[-1:] - values[-2:-1]) / dx])
    return xp.moveaxis(slope, 0, axis)


def equilibrium_distance(context, time_step: float, steps: int = 12) -> float:
    r"""delta_inf: the relative L1 distance from its Maxwellian of the uniform state the
    full level tends to, for an inelastic gas (the homogeneous cooling state) or under a
    heat bath (the heated state); the Maxwellian closure of the fluid levels leaves it out.

    One cell, the Maxwellian of the run's mean initial temperature, advanced by the full
    level (the run's integrator and operator) for ``steps`` steps of
    min(dt, eps / nu) (nu the mean loss frequency): about ``steps`` collision times, in
    which the shape relaxes to its self-similar one while the temperature falls by
    exp(-steps zeta/nu) only. Returns the distance after the last step,
    sum_j |f_j - M_j| h^d / rho. Measured once per run, on the run's backend."""
    equation, integrator = context.equation, context.integrator
    grid, backend = equation.operator.grid, equation.operator.backend
    xp = backend.xp
    temperature = float(context.temperature)
    cell = backend.asarray(numpy.asarray(grid.maxwellian(1.0, None, temperature))[None])
    frequency = float(to_host(equation.frequencies(
        xp.asarray([1.0]), xp.asarray([temperature]),
        xp.asarray([0.5 * grid.dimension * temperature]))).reshape(-1)[0])
    step = min(float(time_step), equation.knudsen / frequency)
    parts = FluidParts(equation, context.rates)
    for k in range(steps):
        cell = conserving_step(equation, integrator, k * step, cell, step)
    now, _, ok = parts.equilibria(cell, None)
    rho = parts.moments.primitives(cell, node="halves")[0]
    distance = xp.abs(cell - now).sum(axis=tuple(range(1, grid.dimension + 1)))
    value = float(to_host(distance * grid.cell_volume / rho).reshape(-1)[0])
    return value if bool(to_host(ok).reshape(-1)[0]) else 2.0


@attrs.frozen
class CellGrid:
    """The cells whose levels a hierarchy chooses: ``counts`` along the space axes ((C,) on
    an interval, (C_x, C_y) on a rectangle; the cells in C order, x slowest), the cell
    widths ``spacing``, whether each axis is ``periodic``, and the velocity component along
    each (``axes``: (0,) on an interval along x, (1,) along y, (0, 1) on a rectangle)."""

    counts: tuple = attrs.field(converter=tuple)
    spacing: tuple = attrs.field(converter=lambda v: tuple(float(h) for h in v))
    periodic: tuple = attrs.field(converter=lambda v: tuple(bool(p) for p in v))
    axes: tuple = attrs.field(default=(0,), converter=tuple)

    @property
    def total(self) -> int:
        """All cells."""
        return math.prod(self.counts)


class CellIndicators:
    """The indicators of every cell that the level choice takes (see the package notes):
    kappa, delta and the reach, computed on the backend from f of a batch of cells.

    Parameters
    ----------
    settings : granframe.run.description.Hierarchy
        ``free_paths`` and ``buffer``.
    context : HierarchyContext
        The run's equation, integrator and mean initial temperature.
    cells : CellGrid
        All cells, along which kappa differentiates.
    time_step : float
        The run's dt, for :func:`equilibrium_distance`.
    """

    def __init__(self, settings, context, cells: CellGrid, time_step: float):
        equation = context.equation
        self.grid_of_cells = cells
        self.parts = FluidParts(equation, context.rates)
        self.kernel, self.knudsen = equation.operator.kernel, equation.knudsen
        self.shear_coefficient = context.shear_coefficient
        self.free_paths, self.buffer = settings.free_paths, settings.buffer
        #: delta_inf, the distance from its Maxwellian of the uniform state the full level
        #: tends to (:func:`equilibrium_distance`): 0 for an elastic gas without heat bath
        self.floor = (0.0 if self.parts.cooling.elastic and not self.parts.heat_bath
                      else equilibrium_distance(context, time_step))

    def rows(self, f):
        r"""(rho, u, T, delta, ok) of every cell of f (cells, *grid.shape) as the rows of one
        array (cells, d + 4) on the backend: the moments (the node -L as its two halves),
        the distance from the discrete Maxwellian M of the cell's moments,

        .. math:: \delta = \frac{h^d}{\rho}\sum_j |f_j - M_j|,

        and 1 where M exists (0 elsewhere)."""
        xp, grid = self.parts.xp, self.parts.grid
        moments = self.parts.moments.primitives(f, node="halves")
        rho, velocity, temperature, _ = moments
        now, _, ok = self.parts.equilibria(f, None)
        guarded = guard_moments(*moments, xp)
        axes = tuple(range(1, grid.dimension + 1))
        distance = xp.abs(f - now).sum(axis=axes) * grid.cell_volume / guarded.density
        return xp.concatenate([rho[:, None], velocity, temperature[:, None],
                               distance[:, None], ok[:, None].astype(float)], axis=1)

    def measure(self, rows, fluid, xp):
        r"""(kappa, delta, reach) of the cells of ``rows`` (:meth:`rows` of all cells, in
        ``xp``), ``fluid`` where a cell is at a fluid level:

        - kappa of :func:`realizability` with nu_s of :func:`scaled_rates`, inf where
          there is no equilibrium;
        - delta = max(delta, delta_inf) at a fluid level, delta at the full level, NaN
          where there is no equilibrium;
        - the reach max(buffer, ceil(free_paths eps sqrt(2T) / (nu_s h))), the cells on
          each side that particles of the thermal speed reach in ``free_paths`` free
          paths, h the smallest cell width: on a rectangle the same number of cells along
          both axes, at least that path along each."""
        d = self.parts.grid.dimension
        cells = self.grid_of_cells
        rho, velocity, temperature = rows[:, 0], rows[:, 1:1 + d], rows[:, 1 + d]
        distance = rows[:, 2 + d]
        guarded = guard_moments(rho, velocity, temperature, None, xp,
                                where=rows[:, 3 + d] > 0.5)
        rho, temperature = guarded.density, guarded.temperature
        energy = 0.5 * rho * ((velocity ** 2).sum(axis=1) + d * temperature)
        rate = scaled_rates(self.shear_coefficient, self.kernel, rho, temperature, energy, xp)
        shape = cells.counts
        kappa = realizability(rho.reshape(shape), velocity.reshape(shape + (d,)),
                              temperature.reshape(shape), cells.spacing, cells.periodic,
                              self.knudsen, rate.reshape(shape), xp, cells.axes).reshape(-1)
        kappa = xp.where(guarded.valid, kappa, xp.inf)
        path = self.free_paths * self.knudsen * xp.sqrt(2 * temperature) / rate
        reach = xp.maximum(self.buffer, xp.ceil(path / min(cells.spacing) - 1e-9)).astype(
            xp.int64)
        delta = xp.where(guarded.valid, xp.where(fluid, xp.maximum(distance, self.floor),
                                                  distance), xp.nan)
        return kappa, delta, reach
