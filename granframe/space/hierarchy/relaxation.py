r"""The relaxation equations of the fluid levels of the hierarchy
(:mod:`granframe.space.hierarchy`): the granular BGK equation (:class:`RelaxationEquation`)
and the ellipsoidal statistical BGK equation (:class:`EllipsoidalEquation`) of every cell,
with the anisotropic Gaussians of exact grid moments that the latter relaxes to
(:func:`discrete_gaussians`). Both are
:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann` equations for the run's own
time integrator; everything on the backend.
"""

from __future__ import annotations

import math

import numpy

from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.space.hierarchy.rates import scaled_rates
from granframe.velocity.equilibrium import discrete_maxwellians
from granframe.velocity.guard import guard_moments


class RelaxationEquation(HomogeneousBoltzmann):
    r"""The BGK equation of every cell, d_t f = nu_s (M[f] - f)/eps + tau Delta_v f, for the
    run's time integrator: M[f] the discrete Maxwellian of the cell's grid mass, momentum and
    energy, nu_s = c rho T^(lambda/2) E^gamma (``coefficient`` c from
    :func:`~granframe.space.hierarchy.rates.relaxation_rate`). The heat bath and the
    penalisation of the penalised schemes are those of the full equation
    (:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`). Cells without an
    equilibrium (rho or T not positive and finite, or no converged target) relax at the
    rate 0."""

    def __init__(self, equation, coefficient: float):
        super().__init__(equation.operator, equation.heat.tau, equation.knudsen,
                         equation.penalty)
        self.invariants = ("mass",) if self.heat.tau else ("mass", "momentum", "energy")
        self.coefficient = float(coefficient)

    def rates(self, rho, temperature, energy):
        """nu_s of every cell (arrays on the backend,
        :func:`~granframe.space.hierarchy.rates.scaled_rates`)."""
        return scaled_rates(self.coefficient, self.operator.kernel, rho, temperature, energy,
                            self.operator.backend.xp)

    def target(self, flat, guarded):
        """(M, converged): the discrete Maxwellian of every cell of ``flat`` (cells,
        *grid.shape) with the moments ``guarded``
        (:class:`~granframe.velocity.guard.GuardedMoments`)."""
        xp = self.operator.backend.xp
        return discrete_maxwellians(self.operator.grid, guarded.density, guarded.momentum,
                                    guarded.second, xp, self.moments.points)

    def nonlinear(self, t, f):
        r"""nu (G - f)/eps of every cell, G its :meth:`target` and nu its :meth:`rates`
        (0 where there is no target)."""
        grid, xp = self.operator.grid, self.operator.backend.xp
        flat = f.reshape((-1,) + tuple(grid.shape))
        guarded = guard_moments(*self.moments.primitives(flat, node="periodic"), xp)
        target, ok = self.target(flat, guarded)
        rate = xp.where(guarded.valid & ok, self.rates(guarded.density, guarded.temperature,
                                                       guarded.energy), 0.0)
        shape = (-1,) + (1,) * grid.dimension
        return ((rate / self.knudsen).reshape(shape) * (target - flat)).reshape(f.shape)


def discrete_gaussians(grid, density, momentum, second, tensor, xp, points, nodes):
    r"""Anisotropic Gaussians on the grid with exactly the grid mass ``density``, momentum and
    second moment of each cell: the sampled Gaussian of mean u = J/rho and covariance
    ``tensor`` (cells, d, d),

    .. math:: G = \frac{\rho}{(2\pi)^{d/2}\sqrt{\det\Lambda}}
              e^{-\frac12 (v - u)^T\Lambda^{-1}(v - u)}
              + \mathcal M[\rho, J, S] - \mathcal M[\text{moments of the sample}],

    the difference of two discrete Maxwellians
    (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`) putting back the
    moments the sampling misses (a round-off of the spectral accuracy for a resolved G).
    Lambda^{-1} and det Lambda are batched over the cells on the backend (d x d each).
    Returns (G, ok); ``nodes`` (d, N^d) on the backend."""
    d = grid.dimension
    cells = density.shape[0]
    u = momentum / density[:, None]
    inverse = xp.linalg.inv(tensor)
    determinant = xp.linalg.det(tensor)
    centred = nodes[None, :, :] - u[:, :, None]                      # (cells, d, N^d)
    quadratic = xp.einsum("cin,cij,cjn->cn", centred, inverse, centred)
    sample = (density / ((2 * math.pi) ** (d / 2) * xp.sqrt(xp.abs(determinant))))[:, None] \
        * xp.exp(-0.5 * quadratic)
    volume = grid.cell_volume
    mass = sample.sum(axis=1) * volume
    first = (sample[:, None, :] * nodes[None]).sum(axis=2) * volume
    squared = (sample * (nodes * nodes).sum(axis=0)[None]).sum(axis=1) * volume
    wanted, ok_wanted = discrete_maxwellians(grid, density, momentum, second, xp, points)
    present, ok_present = discrete_maxwellians(grid, mass, first, squared, xp, points)
    gaussian = sample.reshape((cells,) + tuple(grid.shape)) + wanted - present
    ok = ok_wanted & ok_present & (determinant > 0)
    return gaussian, ok


class EllipsoidalEquation(RelaxationEquation):
    r"""The ellipsoidal statistical BGK equation (L. H. Holway, Phys. Fluids 9 (1966) 1658;
    P. Andries, P. Le Tallec, J.-P. Perlat, B. Perthame, Eur. J. Mech. B 19 (2000) 813) of
    every cell, d_t f = nu (G[f] - f)/eps + tau Delta_v f: G the Gaussian with the cell's
    mass, momentum and energy and covariance

    .. math:: \Lambda = \tfrac{1}{\Pr}\,T\,I + \bigl(1 - \tfrac1{\Pr}\bigr)\,\Theta,
              \qquad \Theta = P/\rho,

    (:func:`discrete_gaussians`), nu = nu_q and Pr = nu_q / nu_s: the heat flux relaxes at
    nu_q and the stress at nu/Pr = nu_s, the rates of the run's own operator
    (:func:`~granframe.space.hierarchy.rates.relaxation_rate`), so that the level has its
    viscosity and its conductivity in the first Sonine approximation. Pr is kept at
    (d - 1)/d or more (2/3 in 3D, 1/2 in 2D), where Lambda is positive definite for every
    positive f (Andries et al.: its eigenvalues are T/Pr + (1 - 1/Pr) theta_k with
    0 < theta_k < d T)."""

    def __init__(self, equation, shear: float, heat: float):
        super().__init__(equation, heat)
        d = self.operator.grid.dimension
        self.prandtl = max(heat / shear, (d - 1) / d)
        grid = self.operator.grid
        mesh = [numpy.broadcast_to(m, grid.shape).reshape(-1) for m in grid.mesh()]
        self.nodes = self.operator.backend.xp.asarray(numpy.stack(mesh))

    def target(self, flat, guarded):
        r"""(G, converged): the Gaussian of every cell of ``flat`` with the covariance
        Lambda (see the class notes), Theta_ij = M_ij / rho - u_i u_j from the raw second
        moments M_ij; the identity where the moments are not ``guarded.valid``."""
        xp, d = self.operator.backend.xp, self.operator.grid.dimension
        raw = self.moments.raw(flat)
        second = xp.zeros((flat.shape[0], d, d))
        for k, (i, j) in enumerate(self.moments.pairs):
            column = raw[:, 1 + d + k]
            second[:, i, j] = column
            second[:, j, i] = column
        u = guarded.velocity
        theta = second / guarded.density[:, None, None] - u[:, :, None] * u[:, None, :]
        identity = xp.eye(d)[None]
        inverse = 1.0 / self.prandtl
        tensor = (inverse * guarded.temperature[:, None, None] * identity
                  + (1.0 - inverse) * theta)
        tensor = xp.where(guarded.valid[:, None, None], tensor, identity)
        return discrete_gaussians(self.operator.grid, guarded.density, guarded.momentum,
                                  guarded.second, tensor, xp, self.moments.points,
                                  self.nodes)
