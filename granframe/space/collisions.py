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
from granframe.equations.conservative import ConservativeCorrection
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.model.restitution import is_elastic
from granframe.space.fields import FieldMoments
from granframe.velocity.equilibrium import discrete_maxwellians


class CellCollisions(HomogeneousBoltzmann):
    """d_t f = Q(f, f)/eps + tau Delta_v f in every cell: f of shape (..., *grid.shape).

    The collision operator and the heat bath act on the whole batch of cells at once;
    the stiffness is the largest over the cells, and the BGK penalisation of the
    penalised integrators is taken cell by cell (a rate and a Maxwellian per cell), all
    from the moments of :class:`~granframe.space.fields.FieldMoments` on the backend.
    """

    def __init__(self, operator, heat_bath: float = 0.0, knudsen: float = 1.0,
                 penalty: float = 2.0):
        super().__init__(operator, heat_bath, knudsen, penalty)
        grid = operator.grid
        self.moments = FieldMoments(grid, 1.0, operator.backend.xp)
        #: what the collision step conserves exactly in every cell, which :meth:`restore`
        #: keeps against round-off: with the conservative correction the mass, and without
        #: a heat bath (whose periodic Laplacian moves momentum by the grid's edge terms)
        #: the momentum and, for an elastic gas, the energy; nothing without the correction
        self.invariants = ()
        if isinstance(operator, ConservativeCorrection):
            elastic = is_elastic(operator.restitution, grid)
            self.invariants = (("mass",) if self.heat.tau else
                               ("mass", "momentum") + (("energy",) if elastic else ()))

    def frequencies(self, density, temperature, energy):
        r""":meth:`HomogeneousBoltzmann.collision_frequency` of every cell at once, on the
        arrays' device: nu_c = C int b dsigma rho_c <s(|g|)>(T_c) phi(E_c)
        (:func:`~granframe.equations.homogeneous.collision_frequency`), with
        :meth:`~granframe.abc.CollisionKernel.mean_speed_parts`."""
        kernel, d = self.operator.kernel, self.operator.grid.dimension
        speed = kernel.mean_speed_parts(d, temperature, self.operator.backend.xp)
        return self._frequency_constant * density * speed * kernel.energy_factors(energy)

    def stiffness(self, f) -> dict:
        """The largest spectral radii over the cells (:meth:`HomogeneousBoltzmann.stiffness`
        of each cell, whose rates grow with rho phi(E): the cell where that is largest)."""
        grid = self.operator.grid
        flat = f.reshape((-1,) + tuple(grid.shape))
        rho, _, _, energy = (to_host(a) for a in self.moments.primitives(flat, node="periodic"))
        kernel = self.operator.kernel
        weight = rho * (kernel.energy_factors(numpy.where(energy > 0, energy, 1.0))
                        if kernel.energy_exponent else 1.0)
        return super().stiffness(flat[int(numpy.argmax(weight))])

    def relaxation(self, f):
        r"""r (M[f] - f) per cell: rate r_c = penalty nu(rho_c, T_c)/eps and M[f] the
        discrete Maxwellian with exactly the cell's grid mass, momentum and energy
        (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`), so that the
        penalisation conserves them to round-off however large r dt is. Cells whose mass
        or temperature is not positive and finite get r = 0 (explicit there). On the
        device, no transfer."""
        grid, xp = self.operator.grid, self.operator.backend.xp
        d = grid.dimension
        flat = f.reshape((-1,) + tuple(grid.shape))
        rho, velocity, temperature, energy = self.moments.primitives(flat, node="periodic")
        valid = xp.isfinite(rho) & (rho > 0) & xp.isfinite(temperature) & (temperature > 0)
        safe_rho = xp.where(valid, rho, 1.0)
        safe_t = xp.where(valid, temperature, 1.0)
        safe_e = xp.where(valid & (energy > 0), energy, 1.0)
        rate = xp.where(valid, self.penalty * self.frequencies(safe_rho, safe_t, safe_e), 0.0)
        target, _ = discrete_maxwellians(
            grid, safe_rho, safe_rho[:, None] * xp.where(valid[:, None], velocity, 0.0),
            xp.where(valid, 2.0 * energy, d * safe_t), xp, self.moments.points)
        shape = f.shape[:-d] + (1,) * d
        return (rate * (1.0 / self.knudsen)).reshape(shape), target.reshape(f.shape)


    def conserved(self, f):
        """The grid mass, momentum (node -L at -L) and second moment h^d sum |v|^2 f of every
        cell of f (..., *grid.shape), on the device: what :meth:`restore` takes."""
        grid = self.operator.grid
        flat = f.reshape((-1,) + tuple(grid.shape))
        rho, velocity, _, energy = self.moments.primitives(flat, node="periodic")
        return rho, rho[:, None] * velocity, 2.0 * energy

    def restore(self, f, before):
        r"""f with the cell moments in :attr:`invariants` set back to ``before``
        (:meth:`conserved` of the data of the collision step).

        The stages of a penalised step sum terms of size dt |Q|/eps whose round-off,
        u dt |Q|/eps with u the unit round-off, shows in the moments that the step
        conserves exactly: 1e-7 of the mass per step at eps = 1e-10 and dt/eps = 1e8.
        The correction adds the difference of two discrete Maxwellians,

        .. math:: f \leftarrow f + \mathcal M[\rho^0, J^0, S^0] - \mathcal M[\rho, J, S],

        (with J^0 = J and S^0 = S for what is not conserved), whose moments are exactly the
        defect: it is of the size of the round-off and changes nothing else. Cells where
        either Maxwellian does not converge are left as they are.
        """
        if not self.invariants:
            return f
        grid, xp = self.operator.grid, self.operator.backend.xp
        flat = f.reshape((-1,) + tuple(grid.shape))
        now = self.conserved(flat)
        goal = (before[0], before[1] if "momentum" in self.invariants else now[1],
                before[2] if "energy" in self.invariants else now[2])
        points = self.moments.points
        wanted, ok_wanted = discrete_maxwellians(grid, *goal, xp, points)
        present, ok_present = discrete_maxwellians(grid, *now, xp, points)
        ok = (ok_wanted & ok_present).reshape((-1,) + (1,) * grid.dimension)
        return (flat + xp.where(ok, wanted - present, 0.0)).reshape(f.shape)


class SplitStep:
    """One Strang step T(dt/2) C(dt) T(dt/2) on a block array (see the module notes).

    The time integrator of a space problem: ``step(equation, t, array, dt)`` with
    ``equation`` the :class:`CellCollisions`. ``integrator`` None: free transport only (a
    collisionless gas), T(dt/2) T(dt/2). ``hierarchy``: a
    :class:`~granframe.space.hierarchy.HybridCollisions` that takes the collision step
    of every cell at its own level instead. The walls see the time of each transport stage.
    """

    adaptive = False

    def __init__(self, integrator, transport, hierarchy=None):
        self.integrator, self.transport, self.hierarchy = integrator, transport, hierarchy

    def step(self, equation, t, array, dt):
        half = 0.5 * dt
        self.transport.advance(array, half, t)
        if self.hierarchy is not None:
            inner = self.transport.domain.interior(array)
            cells = inner.reshape((-1,) + inner.shape[2:])
            inner[...] = self.hierarchy.advance(cells, t, dt).reshape(inner.shape)
        elif self.integrator is not None:      # None: a collisionless gas
            inner = self.transport.domain.interior(array)
            before = equation.conserved(inner) if equation.invariants else None
            inner[...] = equation.restore(self.integrator.step(equation, t, inner, dt), before)
        self.transport.advance(array, half, t + half)
        return array
