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

import math

import numpy

from granframe import validators as check
from granframe.abc import Part
from granframe.backends import to_host
from granframe.equations.conservative import ConservativeCorrection
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.equations.rescaled import (Rescaling, SelfSimilarDrift, check_drift_velocity,
                                          check_rescalable, cooling_rate)
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
    ``rescaling``: the :class:`~granframe.equations.rescaled.Rescaling` of a rescaled run,
    whose transport over a half step of s is that of
    :meth:`~granframe.equations.rescaled.Rescaling.transport_time`.
    """

    adaptive = False

    def __init__(self, integrator, transport, hierarchy=None, rescaling=None):
        self.integrator, self.transport, self.hierarchy = integrator, transport, hierarchy
        self.rescaling = rescaling

    def _transport(self, array, t, duration):
        if self.rescaling is not None:
            duration = self.rescaling.transport_time(t, duration)
        self.transport.advance(array, duration, t)

    def step(self, equation, t, array, dt):
        half = 0.5 * dt
        self._transport(array, t, half)
        if self.hierarchy is not None:
            inner = self.transport.domain.interior(array)
            cells = inner.reshape((-1,) + inner.shape[2:])
            inner[...] = self.hierarchy.advance(cells, t, dt).reshape(inner.shape)
        elif self.integrator is not None:      # None: a collisionless gas
            inner = self.transport.domain.interior(array)
            before = equation.conserved(inner) if equation.invariants else None
            inner[...] = equation.restore(self.integrator.step(equation, t, inner, dt), before)
        self._transport(array, t + half, half)
        return array


#: Largest mean velocity along x, relative to the thermal speed, of the cells of a rescaled
#: space run: 1e-10 admits the round-off of f0's samples (a sine's mean) and refuses any
#: flow, whose transport would not scale with the velocities.
DRIFT_TOLERANCE = 1e-10


class RescaledCellCollisions(CellCollisions):
    r"""d_s g = Q(g, g)/eps - a_0 div((xi - u) chi g) in every cell: the collision step of
    a rescaled space run (:mod:`granframe.equations.rescaled`).

    One scale \omega(s) = e^{a_0 s} for the whole interval, about the mean velocity u of
    all cells (its component along x must vanish, so that the transport stays
    \omega^{\kappa - 1} \xi_1 \partial_x g: :meth:`Rescaling.transport_time`), and a_0
    the rate that keeps the total energy of g stationary at s = 0,

    .. math:: a_0 = \frac{\sum_c \int Q(g_c, g_c) |\xi - u|^2 d\xi / \varepsilon}
                         {\sum_c \int \nabla_\xi\cdot((\xi - u)\chi g_c) |\xi - u|^2 d\xi},

    each sum over every cell in cell order (the same a_0 on any number of processes).
    The drift moves a cell's momentum towards (1 - a_0 ds) of its deviation from u: in
    self-similar variables velocity differences grow with \omega. So the collision step
    keeps only the mass of every cell (with the conservative correction) against
    round-off.

    Parameters
    ----------
    operator : CollisionOperator
        As for :class:`~granframe.equations.rescaled.RescaledBoltzmann`.
    cells : array
        g(0) of the owned cells (cells, *grid.shape), on the backend.
    knudsen, penalty : float
    communicator : Communicator
        The processes of the run; their cells in rank order are all the cells.
    dissipation : array or None
        int Q(g_c, g_c) |xi - u|^2 dxi of the owned cells (before 1/eps); None: from the
        operator, one batched call.
    """

    def __init__(self, operator, cells, knudsen: float = 1.0, penalty: float = 2.0,
                 communicator=None, dissipation=None):
        owner = "RescaledCellCollisions"
        degree = check_rescalable(operator.kernel, operator.restitution, 0.0, owner)
        super().__init__(operator, 0.0, knudsen, penalty)
        grid = operator.grid
        gather = ((lambda part: [part]) if communicator is None
                  else communicator.allgather_object)
        rho, velocity, temperature, _ = (to_host(a) for a in self.moments.primitives(cells))
        rho, momentum, heat = (numpy.concatenate(gather(part)) for part in
                               (rho, rho[:, None] * velocity, rho * temperature))
        along = float(momentum[:, 0].sum() / rho.sum())
        thermal = math.sqrt(float(heat.sum() / rho.sum()))
        if not abs(along) <= DRIFT_TOLERANCE * thermal:
            check.reject(owner, "initial", f"f0 with mean velocity u_1 = {along:.6g}",
                         f"must have mean velocity 0 along x (to {DRIFT_TOLERANCE:g} of the "
                         f"thermal speed {thermal:.6g}) in a rescaled space run: the "
                         "transport of g is then omega^(kappa - 1) xi_1 d_x g; take the frame "
                         "that moves with the gas")
        # the fixed point: 0 along x, where the transport needs it, and across x the mean
        # velocity (the same in the periodic grid's convention, which the homogeneous
        # formulation takes: the node -L shifts only the component along its own axis)
        mean = (0.0,) + tuple(float(m) for m in momentum[:, 1:].sum(axis=0) / rho.sum())
        check_drift_velocity(operator.kernel, mean, owner, "initial")
        self.drift = SelfSimilarDrift(grid, operator.backend, mean)
        if dissipation is None:
            dissipation = self._weighted(operator(cells))
        transport = self._weighted(self.drift(cells))
        dissipation = numpy.concatenate(gather(to_host(dissipation)))
        transport = numpy.concatenate(gather(transport))
        rate = cooling_rate(float(dissipation.sum()) / self.knudsen, float(transport.sum()),
                            is_elastic(operator.restitution, grid), owner)
        self.rescaling = Rescaling(rate, degree, mean)
        self._drift_radius = rate * self.drift.unit_radius
        self.invariants = ("mass",) if isinstance(operator, ConservativeCorrection) else ()

    def _weighted(self, f):
        """int f |xi - u|^2 dxi of every cell of f (cells, *grid.shape), on the host."""
        d = self.operator.grid.dimension
        axes = tuple(range(f.ndim - d, f.ndim))
        return to_host(self.operator.backend.xp.sum(f * self.drift.energy_weight, axis=axes))

    def nonlinear(self, t, g):
        return super().nonlinear(t, g) - self.drift(g) * self.rescaling.rate

    def stiffness(self, f) -> dict:
        """:meth:`CellCollisions.stiffness` and the drift's bound a_0 sum_j max|chi (xi_j -
        u_j)| k_max."""
        return {**super().stiffness(f), Part.DRIFT: self._drift_radius}
