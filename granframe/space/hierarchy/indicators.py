r"""The indicators that choose the level of every cell (:mod:`granframe.space.hierarchy`):
the Navier-Stokes realizability indicator kappa (:func:`realizability`) and the distance
delta_inf of the uniform state the full level tends to (:func:`equilibrium_distance`),
the floor of the distance delta at the fluid levels.
"""

from __future__ import annotations

import numpy

from granframe.backends import to_host
from granframe.space.conserving import conserving_step
from granframe.space.hierarchy.levels import FluidParts


def realizability(density, velocity, temperature, dx: float, periodic: bool, knudsen: float,
                  rate):
    r"""The Navier-Stokes realizability indicator of every cell (see the package notes),

    .. math:: \kappa = \max\Bigl(\frac{\lVert\sigma\rVert_F}{p},
              \frac{|q_1|}{p\sqrt T}\Bigr),\qquad
              \sigma_{ij} = -\mu\bigl(\partial_i u_j + \partial_j u_i
              - \tfrac2d\,\delta_{ij}\,\partial_1 u_1\bigr),\quad
              q_1 = -\tfrac{d+2}{2}\,\mu\,\partial_1 T,

    with only x-derivatives (central differences of the cell values, one-sided at a wall),
    p = rho T, mu = eps p / nu_s (``rate``: nu_s of every cell) and the conductivity of
    a gas of Prandtl number 1 (the BGK closure's, as Filbet & Rey). NumPy arrays over all
    cells, on the host."""
    d = velocity.shape[1]

    def gradient(values):
        if periodic:
            return (numpy.roll(values, -1, axis=0) - numpy.roll(values, 1, axis=0)) / (2 * dx)
        return numpy.gradient(values, dx, axis=0) if len(values) > 1 else 0.0 * values

    du = gradient(velocity)
    dT = gradient(temperature)
    scale = knudsen / rate                                 # mu / p
    normal = 2.0 * (1.0 - 1.0 / d) * du[:, 0]               # sigma_11 / mu (up to sign)
    across = (2.0 / d) * du[:, 0]                           # sigma_jj / mu, j > 1
    shear = (du[:, 1:] ** 2).sum(axis=1)                    # sum_j sigma_1j^2 / mu^2
    stress = scale * numpy.sqrt(normal ** 2 + (d - 1) * across ** 2 + 2.0 * shear)
    safe_t = numpy.where(temperature > 0, temperature, 1.0)
    heat = scale * 0.5 * (d + 2) * numpy.abs(dT) / numpy.sqrt(safe_t)
    return numpy.maximum(stress, heat)


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
    parts = FluidParts(equation)
    for k in range(steps):
        cell = conserving_step(equation, integrator, k * step, cell, step)
    now, _, ok = parts.equilibria(cell, None)
    rho = parts.moments.primitives(cell, node="halves")[0]
    distance = xp.abs(cell - now).sum(axis=tuple(range(1, grid.dimension + 1)))
    value = float(to_host(distance * grid.cell_volume / rho).reshape(-1)[0])
    return value if bool(to_host(ok).reshape(-1)[0]) else 2.0
