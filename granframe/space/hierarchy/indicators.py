r"""The indicators that choose the level of every cell (:mod:`granframe.space.hierarchy`):
the Navier-Stokes realizability indicator kappa (:func:`realizability`), the distance
delta of f from its local equilibrium and the cells each cell's level reaches
(:class:`CellIndicators`), and the distance delta_inf of the uniform state the full level
tends to (:func:`equilibrium_distance`), the floor of delta at the fluid levels.
"""

from __future__ import annotations

import numpy

from granframe.backends import to_host
from granframe.space.conserving import conserving_step
from granframe.space.hierarchy.levels import FluidParts
from granframe.space.hierarchy.rates import scaled_rates
from granframe.velocity.guard import guard_moments


def realizability(density, velocity, temperature, dx: float, periodic: bool, knudsen: float,
                  rate, xp=numpy, axis: int = 0):
    r"""The Navier-Stokes realizability indicator of every cell (see the package notes),

    .. math:: \kappa = \max\Bigl(\frac{\lVert\sigma\rVert_F}{p},
              \frac{|q_a|}{p\sqrt T}\Bigr),\qquad
              \sigma_{ij} = -\mu\bigl(\partial_i u_j + \partial_j u_i
              - \tfrac2d\,\delta_{ij}\,\partial_a u_a\bigr),\quad
              q_a = -\tfrac{d+2}{2}\,\mu\,\partial_a T,

    with only the derivatives along the cells' space axis a = ``axis`` (0: x;
    :func:`x_derivative`), p = rho T, mu = eps p / nu_s (``rate``: nu_s of every cell) and
    the conductivity of a gas of Prandtl number 1 (the BGK closure's, as Filbet & Rey).
    Arrays over all cells in ``xp``."""
    d = velocity.shape[1]
    if axis:                            # the normal component first; sigma is symmetric
        velocity = velocity[:, [axis] + [j for j in range(d) if j != axis]]
    du = x_derivative(velocity, dx, periodic, xp)
    dT = x_derivative(temperature, dx, periodic, xp)
    scale = knudsen / rate                                 # mu / p
    normal = 2.0 * (1.0 - 1.0 / d) * du[:, 0]               # sigma_11 / mu (up to sign)
    across = (2.0 / d) * du[:, 0]                           # sigma_jj / mu, j > 1
    shear = (du[:, 1:] ** 2).sum(axis=1)                    # sum_j sigma_1j^2 / mu^2
    stress = scale * xp.sqrt(normal ** 2 + (d - 1) * across ** 2 + 2.0 * shear)
    safe_t = xp.where(temperature > 0, temperature, 1.0)
    heat = scale * 0.5 * (d + 2) * xp.abs(dT) / xp.sqrt(safe_t)
    return xp.maximum(stress, heat)


def x_derivative(values, dx: float, periodic: bool, xp=numpy):
    r"""d/dx of the cell values g (cells, ...): the central differences

    .. math:: g'_i = \frac{g_{i+1} - g_{i-1}}{2\,\Delta x},

    across the ends of a ``periodic`` interval, and at a wall the one-sided ones
    (g_1 - g_0)/dx and (g_{C-1} - g_{C-2})/dx (:func:`numpy.gradient`'s, by slices); 0 for
    one cell."""
    if periodic:
        return (xp.roll(values, -1, axis=0) - xp.roll(values, 1, axis=0)) / (2 * dx)
    if len(values) < 2:
        return 0.0 * values
    return xp.concatenate([(values[1:2] - values[:1]) / dx,
                           (values[2:] - values[:-2]) / (2.0 * dx),
                           (values[-1:] - values[-2:-1]) / dx])


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


class CellIndicators:
    """The indicators of every cell that the level choice takes (see the package notes):
    kappa, delta and the reach, computed on the backend from f of a batch of cells.

    Parameters
    ----------
    settings : granframe.run.description.Hierarchy
        ``free_paths`` and ``buffer``.
    context : HierarchyContext
        The run's equation, integrator and mean initial temperature.
    dx : float
    periodic : bool
    time_step : float
        The run's dt, for :func:`equilibrium_distance`.
    axis : int, optional
        The space axis the cells lie along (0: x), along which kappa differentiates.
    """

    def __init__(self, settings, context, dx: float, periodic: bool, time_step: float,
                 axis: int = 0):
        equation = context.equation
        self.axis = axis
        self.parts = FluidParts(equation, context.rates)
        self.kernel, self.knudsen = equation.operator.kernel, equation.knudsen
        self.shear_coefficient = context.shear_coefficient
        self.free_paths, self.buffer = settings.free_paths, settings.buffer
        self.dx, self.periodic = float(dx), periodic
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
        - the reach max(buffer, ceil(free_paths eps sqrt(2T) / (nu_s dx))), the cells on
          each side that particles of the thermal speed reach in ``free_paths`` free
          paths."""
        d = self.parts.grid.dimension
        rho, velocity, temperature = rows[:, 0], rows[:, 1:1 + d], rows[:, 1 + d]
        distance = rows[:, 2 + d]
        guarded = guard_moments(rho, velocity, temperature, None, xp,
                                where=rows[:, 3 + d] > 0.5)
        rho, temperature = guarded.density, guarded.temperature
        energy = 0.5 * rho * ((velocity ** 2).sum(axis=1) + d * temperature)
        rate = scaled_rates(self.shear_coefficient, self.kernel, rho, temperature, energy, xp)
        kappa = realizability(rho, velocity, temperature, self.dx, self.periodic, self.knudsen,
                              rate, xp, self.axis)
        kappa = xp.where(guarded.valid, kappa, xp.inf)
        path = self.free_paths * self.knudsen * xp.sqrt(2 * temperature) / rate
        reach = xp.maximum(self.buffer, xp.ceil(path / self.dx - 1e-9)).astype(xp.int64)
        delta = xp.where(guarded.valid, xp.where(fluid, xp.maximum(distance, self.floor),
                                                  distance), xp.nan)
        return kappa, delta, reach
