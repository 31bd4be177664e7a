r"""d_t f + v_1 d_x f = Q(f, f)/eps + tau Delta_v f, split into transport and collisions.

One step of length dt is Strang's splitting (G. Strang, SIAM J. Numer. Anal. 5 (1968)
506-517)

.. math:: f^{n+1} = \mathcal T_{\Delta t/2}\, \mathcal C_{\Delta t}\, \mathcal T_{\Delta t/2}\, f^n,

second order when both parts are: T is the transport sub-step
(:mod:`granframe.space.transport`, three-stage SSP Runge-Kutta) and C one step of the
run's time integrator on the space-homogeneous equation d_t f = Q(f, f)/eps + tau Delta_v f
in every cell at once. Each stage of C is one batched call of the collision operator on
all cells (f of shape (blocks, block_cells, *grid.shape)). With a penalised integrator
(``penalised_euler``, ``penalised_ars222``) the collision step is stable for any dt/eps
(asymptotic preserving, Filbet & Jin 2010), so dt is set by the transport's CFL limit
alone; an explicit integrator keeps its own limit O(eps).
"""

from __future__ import annotations

import numpy

from granframe.backends import to_host
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.space.fields import maxwellians


class CellCollisions(HomogeneousBoltzmann):
    """d_t f = Q(f, f)/eps + tau Delta_v f in every cell: f of shape (..., *grid.shape).

    The collision operator and the heat bath act on the whole batch of cells at once;
    the stiffness is the largest over the cells, and the BGK penalisation of the
    penalised integrators is taken cell by cell (a rate and a Maxwellian per cell).
    """

    def _cells(self, f):
        """(f as cells x nodes, rho, momentum, temperature, energy density) per cell."""
        grid, xp = self.operator.grid, self.operator.backend.xp
        d = grid.dimension
        flat = f.reshape((-1,) + tuple(grid.shape))
        volume = grid.cell_volume
        axes = tuple(range(1, d + 1))
        rho = flat.sum(axis=axes) * volume
        points = xp.asarray(grid.points())
        momentum, second = [], 0.0
        for i in range(d):
            marginal = flat.sum(axis=tuple(a for a in axes if a != i + 1))
            momentum.append((marginal * points).sum(axis=1) * volume)
            second = second + (marginal * points * points).sum(axis=1) * volume
        momentum = xp.stack(momentum, axis=1)
        with numpy.errstate(divide="ignore", invalid="ignore"):
            temperature = (second - (momentum * momentum).sum(axis=1) / rho) / (d * rho)
        return flat, rho, momentum, temperature, 0.5 * second

    def stiffness(self, f) -> dict:
        """The largest spectral radii over the cells (:meth:`HomogeneousBoltzmann.stiffness`
        of each cell)."""
        xp = self.operator.backend.xp
        flat = f.reshape((-1,) + tuple(self.operator.grid.shape))
        rates = {}
        for cell in range(flat.shape[0]):
            for part, rate in super().stiffness(xp.ascontiguousarray(flat[cell])).items():
                rates[part] = max(rates.get(part, 0.0), rate)
        return rates

    def relaxation(self, f):
        r"""r (M[f] - f) per cell: rate r_c = penalty nu(rho_c, T_c)/eps and the grid
        Maxwellian of the cell's mass, momentum and temperature, scaled to its grid mass
        (:meth:`HomogeneousBoltzmann.relaxation`). Cells whose mass or temperature is not
        positive and finite get r = 0 (explicit there)."""
        grid, xp = self.operator.grid, self.operator.backend.xp
        d = grid.dimension
        flat, rho, momentum, temperature, energy = self._cells(f)
        host = [to_host(a) for a in (rho, temperature, energy)]
        valid = numpy.isfinite(host[0]) & (host[0] > 0) & numpy.isfinite(host[1]) & (host[1] > 0)
        frequency = numpy.zeros_like(host[0])
        for cell in numpy.flatnonzero(valid):
            frequency[cell] = self.collision_frequency(float(host[0][cell]),
                                                       float(host[1][cell]),
                                                       float(host[2][cell]))
        rate = self.penalty * frequency / self.knudsen
        safe_rho = xp.where(xp.asarray(valid), rho, 1.0)
        safe_t = xp.where(xp.asarray(valid), temperature, 1.0)
        target = maxwellians(grid, safe_rho, momentum / safe_rho[:, None], safe_t, xp)
        shape = f.shape[:-d] + (1,) * d
        return xp.asarray(rate).reshape(shape), target.reshape(f.shape)


class SplitStep:
    """One Strang step T(dt/2) C(dt) T(dt/2) on a block array (see the module notes).

    The object the run's :class:`~granframe.run.runner.Stepper` drives in place of a time
    integrator: ``step(equation, t, array, dt)`` with ``equation`` the
    :class:`CellCollisions`. ``integrator`` None: free transport only (a collisionless
    gas), T(dt/2) T(dt/2).
    """

    adaptive = False

    def __init__(self, integrator, transport, blocks):
        self.integrator, self.transport, self.blocks = integrator, transport, blocks

    def step(self, equation, t, array, dt):
        half = 0.5 * dt
        self.transport.advance(array, half)
        if self.integrator is not None:      # None: a collisionless gas
            inner = self.blocks.interior(array)
            inner[...] = self.integrator.step(equation, t, inner, dt)
        self.transport.advance(array, half)
        return array
