r"""The levels of the hierarchy (:mod:`granframe.space.hierarchy`), from the cheapest to the
full operator: :class:`EulerLevel`, :class:`RelaxationLevel`, :class:`EllipsoidalLevel` and
:class:`BoltzmannLevel`, the :class:`~granframe.abc.CollisionModel` plugins registered as
``euler``, ``bgk``, ``esbgk`` and ``boltzmann``, and what the fluid levels share
(:class:`FluidParts`). Each advances the batch of cells it is given on the backend.
"""

from __future__ import annotations

from granframe.abc import CollisionModel
from granframe.space.conserving import conserving_step
from granframe.space.hierarchy.rates import CoolingRate
from granframe.space.hierarchy.relaxation import EllipsoidalEquation, RelaxationEquation
from granframe.velocity.equilibrium import discrete_maxwellians
from granframe.velocity.guard import guard_moments


class FluidParts:
    """What the fluid levels share: the moments of a batch of cells (the ``moments`` of the
    run's equation), their discrete Maxwellians and the cooled temperature, all on the
    backend; ``rates`` (:class:`~granframe.space.hierarchy.rates.StepRates`, the
    hierarchy's), where the cooling takes its substeps from."""

    def __init__(self, equation, rates=None):
        operator = equation.operator
        self.grid, self.xp = operator.grid, operator.backend.xp
        self.moments = equation.moments
        # the hierarchy's levels share its cooling rate (its table is built once)
        self.cooling = (CoolingRate(operator.kernel, operator.restitution, self.grid)
                        if rates is None else rates.cooling)
        self.knudsen, self.heat_bath = equation.knudsen, equation.heat.tau
        self.rates = rates

    def equilibria(self, f, dt: float, heat: bool = True):
        r"""(M, M', ok) for f (cells, *grid.shape): the discrete Maxwellian of every cell's
        mass, momentum (node -L at -L, as Q conserves it) and second moment, the one of its
        mass, momentum and second moment after dt of cooling (and of the heat bath's
        heating with ``heat``),

        .. math:: S' = S + \rho d\,(T' - T),

        and where both exist; with ``dt`` None, M twice (no cooling is integrated)."""
        xp, d = self.xp, self.grid.dimension
        guarded = guard_moments(*self.moments.primitives(f, node="periodic"), xp)
        rho, momentum = guarded.density, guarded.momentum
        now, ok_now = discrete_maxwellians(self.grid, rho, momentum, guarded.second, xp,
                                           self.moments.points)
        if dt is None:
            return now, now, ok_now & guarded.valid
        tau = self.heat_bath if heat else 0.0
        later = self.cooling.cooled(rho, guarded.temperature, guarded.energy, dt,
                                    self.knudsen, tau, xp,
                                    None if self.rates is None else self.rates.fastest(tau))
        cooled = guarded.second + rho * d * (later - guarded.temperature)
        after, ok_after = discrete_maxwellians(self.grid, rho, momentum, cooled, xp,
                                               self.moments.points)
        return now, after, ok_now & ok_after & guarded.valid


class EulerLevel(CollisionModel):
    r"""The granular Euler level: every cell set to its local equilibrium after cooling,

    .. math:: f \leftarrow \mathcal M[\rho, \rho u, S'],\qquad
              S' = S + \rho d\,(T(t+\Delta t) - T),

    the discrete Maxwellian with exactly the cell's grid mass and momentum and the second
    moment of dT/dt = -zeta T/eps + 2 tau over the step
    (:class:`~granframe.space.hierarchy.rates.CoolingRate`). Between two transport half
    steps this is the kinetic flux-vector splitting scheme of the granular Euler equations
    of the velocity grid (B. Perthame, SIAM J. Numer. Anal. 29 (1992) 1-19). Cells without
    an equilibrium are left as they are and reported."""

    name = "euler"
    full = False

    def __init__(self, context):
        self.parts = FluidParts(context.equation, context.rates)

    def advance(self, f, t, dt):
        xp = self.parts.xp
        _, after, ok = self.parts.equilibria(f, dt)
        self.converged = ok
        return xp.where(ok.reshape((-1,) + (1,) * self.parts.grid.dimension), after, f)


class RelaxationLevel(CollisionModel):
    r"""The granular BGK level: d_t f = nu_s (M[f] - f)/eps (+ tau Delta_v f) stepped by the
    run's own time integrator
    (:class:`~granframe.space.hierarchy.relaxation.RelaxationEquation`, its invariants
    restored: :func:`~granframe.space.conserving.conserving_step`), so that it shares the
    full level's time discretisation and differs from it only by the model, then cooled:

    .. math:: f \leftarrow f + \mathcal M[\rho, \rho u, S'] - \mathcal M[\rho, \rho u, S],

    with S' the second moment after dt of dT/dt = -zeta T/eps
    (:class:`~granframe.space.hierarchy.rates.CoolingRate`): mass and momentum are kept to
    round-off, the energy to the cooling. nu_s = c rho T^(lambda/2) E^gamma with c from
    :func:`~granframe.space.hierarchy.rates.relaxation_rate` of the run's operator at the
    run's mean initial temperature: the level has the full operator's shear viscosity in
    the first Sonine approximation (its Prandtl number is 1, the full operator's about
    2/3)."""

    name = "bgk"
    full = False

    def __init__(self, context):
        self.parts = FluidParts(context.equation, context.rates)
        self.equation = RelaxationEquation(context.equation, context.shear_coefficient)
        self.integrator = context.integrator

    def advance(self, f, t, dt):
        out = conserving_step(self.equation, self.integrator, t, f, dt)
        if self.parts.cooling.elastic:
            return out
        xp, d = self.parts.xp, self.parts.grid.dimension
        now, after, ok = self.parts.equilibria(out, dt, heat=False)
        self.converged = ok
        return out + xp.where(ok.reshape((-1,) + (1,) * d), after - now, 0.0)


class EllipsoidalLevel(RelaxationLevel):
    """The granular ES-BGK level:
    :class:`~granframe.space.hierarchy.relaxation.EllipsoidalEquation` stepped by the run's
    own time integrator, then cooled as the BGK level (:class:`RelaxationLevel`): the full
    operator's viscosity and conductivity in the first Sonine approximation."""

    name = "esbgk"

    def __init__(self, context):
        self.parts = FluidParts(context.equation, context.rates)
        self.equation = EllipsoidalEquation(context.equation, context.shear_coefficient,
                                            context.heat_coefficient)
        self.integrator = context.integrator


class BoltzmannLevel(CollisionModel):
    """The full level: the run's time integrator on the run's collision operator (with the
    conservative correction and the round-off restoration of
    :meth:`~granframe.equations.homogeneous.HomogeneousBoltzmann.restore`:
    :func:`~granframe.space.conserving.conserving_step`)."""

    name = "boltzmann"
    full = True

    def __init__(self, context):
        self.equation, self.integrator = context.equation, context.integrator

    def advance(self, f, t, dt):
        return conserving_step(self.equation, self.integrator, t, f, dt)
