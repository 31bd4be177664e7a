r"""A hierarchy of collision models chosen cell by cell (docs/space.md, "The hierarchy").

In a space run every cell pays for the collision step. Where f is close to its local
Maxwellian a cheaper model gives the same answer: this module keeps the transport
kinetic in every cell (the same upwind fluxes of f everywhere, so mass, momentum and
energy cross the interfaces between levels exactly as between any two cells) and lets
the collision step of each cell be one of the registered
:class:`~granframe.abc.CollisionModel` levels, from the cheapest to the full operator,
following F. Filbet & T. Rey, SIAM J. Sci. Comput. 37 (2015) A1218-A1247
(arXiv:1402.6304) and G. Caparello, L. Pareschi & T. Rey (arXiv:2505.03360, 2025):

- ``euler``: f set to the discrete Maxwellian of its mass, momentum and cooled energy
  (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`): between two transport
  half steps this is the kinetic flux-vector scheme of the granular Euler equations;
- ``bgk``: the granular BGK model d_t f = nu_s (M[f] - f)/eps, stepped by the run's own
  time integrator and then cooled, with nu_s the rate at which the run's own operator
  relaxes a shear stress (:func:`relaxation_rate`), so that the level has the
  shear viscosity of the full operator in the first Sonine approximation;
- ``esbgk``: the ellipsoidal statistical BGK model, stepped and cooled as ``bgk``, with the
  operator's shear and heat-flux relaxation rates: its viscosity and its conductivity;
- ``boltzmann``: the run's integrator on the run's collision operator.

The fluid levels cool their equilibrium at the granular cooling rate of the run's kernel
and restitution law (:class:`CoolingRate`), the ``euler`` level also heats it at 2 tau per
unit time under a heat bath (the relaxation levels get the heat bath from the run's
integrator); mass and momentum are kept to round-off, the energy to the cooling the
formula gives.

Which level a cell takes is decided every ``interval`` steps from two indicators per cell
(:class:`HybridCollisions`, :func:`choose_levels`):

- from fluid to kinetic, the Navier-Stokes realizability indicator of Levermore,
  Morokoff & Nadiga (Phys. Fluids 10 (1998) 3214), as Filbet & Rey use it: the stress and
  heat flux of the Navier-Stokes closure computed from the gradients of rho, u, T, relative
  to the pressure, kappa = max(|sigma|_F / p, |q| / (p sqrt T)). The Chapman-Enskog f is
  M (1 + phi) with phi of the size of these ratios at thermal speeds; it stops being
  a positive distribution (the closure loses its meaning) when they approach one.
- from kinetic to fluid, the distance of f from its local equilibrium in the relative
  L1 norm, delta = sum |f - M[f]| h^d / rho: dimensionless, at most 2, and a bound for
  the error of every bounded observable when f is replaced by M[f]; it measures the
  non-equilibrium in every moment at once, including those no indicator of rho, u, T sees
  (a Knudsen layer's velocity distribution at a wall).

A cell at level l rises to level k > l when an indicator exceeds the threshold of k; it
falls below k only when both are under ``hysteresis`` times that threshold, and every
cell lifts its neighbours to its level as far as ``buffer`` cells or ``free_paths`` mean
free paths eps sqrt(2T)/nu_s on each side, whichever is larger, so that a wave, or the
particles that fly ahead of it, never reach a cell still at a lower level, and cells do not
flicker. The fluid levels hold f at a Maxwellian or relax it to a Gaussian, so their
distance after the step says nothing of what they leave out: for an inelastic gas or
under a heat bath their cells take at least the distance delta_inf of the uniform state
the full level tends to (:func:`equilibrium_distance`).
"""

from __future__ import annotations

import functools
import math
import time

import attrs
import numpy
import scipy.special

from granframe.abc import CollisionModel
from granframe.backends import to_host
from granframe.model.restitution import is_elastic
from granframe.space.collisions import CellCollisions
from granframe.space.fields import FieldMoments
from granframe.velocity.equilibrium import discrete_maxwellians

#: Gauss-Laguerre nodes of the averages over the relative speeds of a Maxwellian
_LAGUERRE = 96


def speed_average(function, dimension: int, temperature: float) -> float:
    r"""<F(s)> over the relative speeds s = |v - v_*| of two particles of a Maxwellian at
    temperature T (s is the speed of a d-dimensional Maxwellian at 2T):

    .. math:: \langle F\rangle = \frac{\int_0^\infty F(s)\, s^{d-1} e^{-s^2/4T}\,ds}
                                      {\int_0^\infty s^{d-1} e^{-s^2/4T}\,ds}
              = \frac{1}{\Gamma(d/2)}\sum_i w_i F\bigl(2\sqrt{T y_i}\bigr),

    with (y_i, w_i) the generalised Gauss-Laguerre rule of weight y^{d/2-1} e^{-y}."""
    y, w = scipy.special.roots_genlaguerre(_LAGUERRE, dimension / 2 - 1)
    return float(w @ function(2.0 * numpy.sqrt(temperature * y))) / math.gamma(dimension / 2)


class CoolingRate:
    r"""The granular cooling rate zeta(rho, T, E) of a Maxwellian, d T/dt = -zeta T / eps.

    From the weak form in the sigma-representation, one collision of relative velocity
    g = v - v_* changes the energy by |v'|^2 + |v'_*|^2 - |v|^2 - |v_*|^2
    = -(1 - e(|g|)^2)/4 |g|^2 (1 - g.sigma/|g|), so that for B = C |g|^lambda b E^gamma

    .. math:: \int Q(f,f)|v|^2 dv = -\frac{C\beta\,E^\gamma}{8}\iint f f_*
              |g|^{\lambda+2}\bigl(1 - e(|g|)^2\bigr)\,dv\,dv_*,\qquad
              \beta = \int_{S^{d-1}} b(\hat g\cdot\sigma)(1 - \hat g\cdot\sigma)\,d\sigma .

    For a Maxwellian of density rho and temperature T, the double integral is rho^2 times
    the average over its relative speeds (:func:`speed_average`), and with
    d/dt int |v|^2 f = rho d dT/dt,

    .. math:: \zeta = \frac{C\beta\,E^\gamma \rho}{8 d T}
              \bigl\langle s^{\lambda+2}(1 - e(s)^2)\bigr\rangle_{2T},

    which for a constant e is C beta E^gamma rho (1 - e^2) (4T)^{lambda/2}
    Gamma((d + lambda + 2)/2) / (2 d Gamma(d/2)): rho (1 - e^2)/4 for the review's 2D
    and 3D Maxwell molecules (the rate of
    :func:`granframe.model.exact.heated_maxwell_temperature`), and
    4 (1 - e^2) rho sqrt(T) / (3 sqrt(pi)) for the review's 3D hard spheres
    (C beta = 1: C = 1/(4 pi), beta = 4 pi). For a
    restitution law that depends on |g| the average is tabulated once in log T over the
    temperatures the grid holds and interpolated.
    """

    def __init__(self, kernel, restitution, grid):
        d = grid.dimension
        self.kernel, self.dimension = kernel, d
        self.elastic = is_elastic(restitution, grid)
        lam = kernel.speed_exponent
        self.exponent = lam / 2.0
        beta = kernel.prefactor(d) * kernel.angular_integral(d, lambda t: 1.0 - t)
        self._constant = beta / (8.0 * d)
        self.table = None
        if self.elastic:
            self.coefficient = 0.0
        elif restitution.is_constant:
            e = float(numpy.asarray(restitution(numpy.array([1.0]))).reshape(-1)[0])
            #: zeta = coefficient rho E^gamma T^(lambda/2) for a constant e
            self.coefficient = (self._constant * (1.0 - e * e) * 4.0 ** (lam / 2 + 1)
                                * math.exp(math.lgamma((d + lam + 2) / 2)
                                           - math.lgamma(d / 2)))
        else:
            self.coefficient = None
            top = float(grid.half_width) ** 2
            temperatures = top * numpy.logspace(-12.0, 0.0, 241)
            values = [self._constant * speed_average(
                lambda s: s ** (lam + 2) * (1.0 - numpy.asarray(restitution(s)) ** 2), d, t) / t
                for t in temperatures]
            self.table = (numpy.log(temperatures), numpy.log(numpy.maximum(values, 1e-300)))

    def __call__(self, density, temperature, energy, xp=numpy):
        """zeta of every cell (arrays in ``xp``)."""
        factor = self.kernel.energy_factors(energy) if self.kernel.energy_exponent else 1.0
        if self.coefficient is not None:
            if self.coefficient == 0.0:
                return 0.0 * density
            return self.coefficient * density * factor * temperature ** self.exponent
        log_t, log_z = (xp.asarray(a) for a in self.table)
        return density * factor * xp.exp(xp.interp(xp.log(temperature), log_t, log_z))

    def cooled(self, density, temperature, energy, dt: float, knudsen: float,
               heat_bath: float, xp=numpy):
        r"""T after dt of dT/dt = -zeta(T) T / eps + 2 tau at fixed rho and E^gamma.

        A constant e without a heat bath has the closed form
        T (1 + (lambda/2) zeta dt/eps)^(-2/lambda) (T e^{-zeta dt/eps} for lambda = 0);
        otherwise classical RK4 on ln T with enough substeps that each takes at most a
        twentieth of the fastest rate's time (relative error below 1e-7)."""
        if self.elastic and not heat_bath:
            return temperature
        zeta = self(density, temperature, energy, xp)
        if self.coefficient is not None and not heat_bath:
            x = zeta * (dt / knudsen)
            if self.exponent == 0.0:
                return temperature * xp.exp(-x)
            return temperature * (1.0 + self.exponent * x) ** (-1.0 / self.exponent)
        rate = float(to_host(xp.max(zeta / knudsen + 2.0 * heat_bath / temperature)))
        steps = int(min(max(1, math.ceil(20.0 * rate * dt)), 100000))
        h = dt / steps

        def slope(log_t):
            t = xp.exp(log_t)
            return -self(density, t, energy, xp) / knudsen + 2.0 * heat_bath / t

        log_t = xp.log(temperature)
        for _ in range(steps):
            k1 = slope(log_t)
            k2 = slope(log_t + 0.5 * h * k1)
            k3 = slope(log_t + 0.5 * h * k2)
            k4 = slope(log_t + h * k3)
            log_t = log_t + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return xp.exp(log_t)


def relaxation_rate(operator, mode: str, temperature: float, density: float = 1.0,
                    amplitude: float = 1e-3) -> float:
    r"""The rate at which the run's collision operator relaxes a small shear stress
    (``mode`` "shear") or heat flux ("heat") of a Maxwellian of ``density`` and
    ``temperature`` (eps = 1): the collision frequencies of the shear viscosity and the heat
    conductivity in the first Sonine approximation, mu = p eps / nu_s and
    kappa = (d + 2)/2 p eps / nu_q (granframe's q = int c |c|^2 f / 2).

    With h = a M phi / T^k, phi = v_1 v_2 (k = 1) or v_1 (|v|^2 - (d + 2) T) (k = 3/2),

    .. math:: \nu = -\frac{\int \phi\,[Q(M + h) - Q(M - h)]\,dv}{2\int \phi\,h\,dv},

    the linearised operator's eigenvalue on the mode when it is one (Maxwell molecules:
    -rho a_1 of :func:`granframe.model.exact.maxwell_pressure_rate` for the shear,
    exactly), its Rayleigh quotient in the Sonine basis otherwise. One call of the operator
    on a stack of two distributions on the run's backend."""
    grid, backend = operator.grid, operator.backend
    d = grid.dimension
    maxwellian = numpy.asarray(grid.maxwellian(density, None, temperature))
    mesh = [numpy.broadcast_to(m, grid.shape) for m in grid.mesh()]
    if mode == "shear":
        weight = mesh[0] * mesh[1] / temperature
    else:
        weight = mesh[0] * (sum(m * m for m in mesh) - (d + 2) * temperature) / temperature ** 1.5
    perturbation = amplitude * maxwellian * weight
    stack = backend.asarray(numpy.stack([maxwellian + perturbation, maxwellian - perturbation]))
    q = backend.to_numpy(operator(stack))
    change = float(numpy.sum((q[0] - q[1]) * weight))
    return -change / (2.0 * float(numpy.sum(perturbation * weight)))


def scaled_rates(coefficient: float, kernel, density, temperature, energy, xp=numpy):
    """nu = c rho T^(lambda/2) E^gamma of every cell (arrays in ``xp``; T where it is not
    positive taken as 1): how a relaxation rate measured at one state
    (:func:`relaxation_rate`) scales with the cell's state for the kernel
    C |g|^lambda b E^gamma."""
    factor = kernel.energy_factors(energy) if kernel.energy_exponent else 1.0
    return (coefficient * density * factor
            * xp.where(temperature > 0, temperature, 1.0) ** (kernel.speed_exponent / 2))


class FluidParts:
    """What the fluid levels share: the moments of a batch of cells, their discrete
    Maxwellians and the cooled temperature, all on the backend."""

    def __init__(self, equation):
        operator = equation.operator
        self.grid, self.xp = operator.grid, operator.backend.xp
        self.moments = FieldMoments(self.grid, 1.0, self.xp)
        self.cooling = CoolingRate(operator.kernel, operator.restitution, self.grid)
        self.knudsen, self.heat_bath = equation.knudsen, equation.heat.tau

    def equilibria(self, f, dt: float, heat: bool = True):
        r"""(M, M', ok) for f (cells, *grid.shape): the discrete Maxwellian of every cell's
        mass, momentum (node -L at -L, as Q conserves it) and second moment, the one of its
        mass, momentum and second moment after dt of cooling (and of the heat bath's
        heating with ``heat``), S' = S + rho d (T' - T), and where both exist; with ``dt``
        None, M twice (no cooling is integrated)."""
        xp, d = self.xp, self.grid.dimension
        rho, velocity, temperature, energy = self.moments.primitives(f, node="periodic")
        valid = xp.isfinite(rho) & (rho > 0) & xp.isfinite(temperature) & (temperature > 0)
        safe_rho = xp.where(valid, rho, 1.0)
        safe_t = xp.where(valid, temperature, 1.0)
        momentum = safe_rho[:, None] * xp.where(valid[:, None], velocity, 0.0)
        second = xp.where(valid, 2.0 * energy, d * safe_t)
        now, ok_now = discrete_maxwellians(self.grid, safe_rho, momentum, second, xp,
                                           self.moments.points)
        if dt is None:
            return now, now, ok_now & valid
        later = self.cooling.cooled(safe_rho, safe_t, xp.where(valid & (energy > 0), energy,
                                                                 1.0),
                                    dt, self.knudsen, self.heat_bath if heat else 0.0, xp)
        cooled = second + safe_rho * d * (later - safe_t)
        after, ok_after = discrete_maxwellians(self.grid, safe_rho, momentum, cooled, xp,
                                               self.moments.points)
        return now, after, ok_now & ok_after & valid


class EulerLevel(CollisionModel):
    r"""The granular Euler level: every cell set to its local equilibrium after cooling,

    .. math:: f \leftarrow \mathcal M[\rho, \rho u, S'],\qquad
              S' = S + \rho d\,(T(t+\Delta t) - T),

    the discrete Maxwellian with exactly the cell's grid mass and momentum and the second
    moment of dT/dt = -zeta T/eps + 2 tau over the step (:class:`CoolingRate`). Between
    two transport half steps this is the kinetic flux-vector splitting scheme of the
    granular Euler equations of the velocity grid (B. Perthame, SIAM J. Numer. Anal. 29
    (1992) 1-19). Cells without an equilibrium are left as they are and reported."""

    name = "euler"
    full = False

    def __init__(self, context):
        self.parts = FluidParts(context.equation)

    def advance(self, f, t, dt):
        xp = self.parts.xp
        _, after, ok = self.parts.equilibria(f, dt)
        self.converged = ok
        return xp.where(ok.reshape((-1,) + (1,) * self.parts.grid.dimension), after, f)


class RelaxationEquation(CellCollisions):
    r"""The BGK equation of every cell, d_t f = nu_s (M[f] - f)/eps + tau Delta_v f, for the
    run's time integrator: M[f] the discrete Maxwellian of the cell's grid mass, momentum and
    energy, nu_s = c rho T^(lambda/2) E^gamma (``coefficient`` c from
    :func:`relaxation_rate`). The heat bath and the penalisation of the penalised
    schemes are those of the full equation (:class:`CellCollisions`)."""

    def __init__(self, equation, coefficient: float):
        super().__init__(equation.operator, equation.heat.tau, equation.knudsen,
                         equation.penalty)
        self.invariants = ("mass",) if self.heat.tau else ("mass", "momentum", "energy")
        self.coefficient = float(coefficient)

    def rates(self, rho, temperature, energy):
        """nu_s of every cell (arrays on the backend, :func:`scaled_rates`)."""
        return scaled_rates(self.coefficient, self.operator.kernel, rho, temperature, energy,
                            self.operator.backend.xp)

    def nonlinear(self, t, f):
        grid, xp = self.operator.grid, self.operator.backend.xp
        flat = f.reshape((-1,) + tuple(grid.shape))
        rho, velocity, temperature, energy = self.moments.primitives(flat, node="periodic")
        valid = xp.isfinite(rho) & (rho > 0) & xp.isfinite(temperature) & (temperature > 0)
        safe_rho = xp.where(valid, rho, 1.0)
        target, ok = discrete_maxwellians(
            grid, safe_rho, safe_rho[:, None] * xp.where(valid[:, None], velocity, 0.0),
            xp.where(valid, 2.0 * energy, grid.dimension * 1.0), xp, self.moments.points)
        rate = xp.where(valid & ok, self.rates(safe_rho, temperature,
                                                xp.where(energy > 0, energy, 1.0)), 0.0)
        shape = (-1,) + (1,) * grid.dimension
        return ((rate / self.knudsen).reshape(shape) * (target - flat)).reshape(f.shape)


class RelaxationLevel(CollisionModel):
    r"""The granular BGK level: d_t f = nu_s (M[f] - f)/eps (+ tau Delta_v f) stepped by the
    run's own time integrator (:class:`RelaxationEquation`), so that it shares the full
    level's time discretisation and differs from it only by the model, then cooled:

    .. math:: f \leftarrow f + \mathcal M[\rho, \rho u, S'] - \mathcal M[\rho, \rho u, S],

    with S' the second moment after dt of dT/dt = -zeta T/eps (:class:`CoolingRate`): mass
    and momentum are kept to round-off, the energy to the cooling. nu_s = c rho T^(lambda/2)
    E^gamma with c from :func:`relaxation_rate` of the run's operator at the run's
    mean initial temperature: the level has the full operator's shear viscosity in the
    first Sonine approximation (its Prandtl number is 1, the full operator's about 2/3)."""

    name = "bgk"
    full = False

    def __init__(self, context):
        self.parts = FluidParts(context.equation)
        self.equation = RelaxationEquation(context.equation, context.shear_coefficient)
        self.integrator = context.integrator

    def advance(self, f, t, dt):
        equation = self.equation
        before = equation.conserved(f)
        out = equation.restore(self.integrator.step(equation, t, f, dt), before)
        if self.parts.cooling.elastic:
            return out
        xp, d = self.parts.xp, self.parts.grid.dimension
        now, after, ok = self.parts.equilibria(out, dt, heat=False)
        self.converged = ok
        return out + xp.where(ok.reshape((-1,) + (1,) * d), after - now, 0.0)


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
    (:func:`relaxation_rate`), so that the level has its viscosity and its conductivity in
    the first Sonine approximation. Pr is kept at (d - 1)/d or more (2/3 in 3D, 1/2 in 2D),
    where Lambda is positive definite for every positive f (Andries et al.: its eigenvalues
    are T/Pr + (1 - 1/Pr) theta_k with 0 < theta_k < d T)."""

    def __init__(self, equation, shear: float, heat: float):
        super().__init__(equation, heat)
        d = self.operator.grid.dimension
        self.prandtl = max(heat / shear, (d - 1) / d)
        grid = self.operator.grid
        mesh = [numpy.broadcast_to(m, grid.shape).reshape(-1) for m in grid.mesh()]
        self.nodes = self.operator.backend.xp.asarray(numpy.stack(mesh))

    def nonlinear(self, t, f):
        grid, xp = self.operator.grid, self.operator.backend.xp
        d = grid.dimension
        flat = f.reshape((-1,) + tuple(grid.shape))
        raw = self.moments.raw(flat)
        rho, velocity, temperature, energy = self.moments.primitives(flat, node="periodic")
        valid = xp.isfinite(rho) & (rho > 0) & xp.isfinite(temperature) & (temperature > 0)
        safe_rho = xp.where(valid, rho, 1.0)
        safe_t = xp.where(valid, temperature, 1.0)
        u = xp.where(valid[:, None], velocity, 0.0)
        second = xp.zeros((flat.shape[0], d, d))
        for k, (i, j) in enumerate(self.moments.pairs):
            column = raw[:, 1 + d + k]
            second[:, i, j] = column
            second[:, j, i] = column
        theta = second / safe_rho[:, None, None] - u[:, :, None] * u[:, None, :]
        identity = xp.eye(d)[None]
        inverse = 1.0 / self.prandtl
        tensor = inverse * safe_t[:, None, None] * identity + (1.0 - inverse) * theta
        tensor = xp.where(valid[:, None, None], tensor, identity)
        target, ok = discrete_gaussians(grid, safe_rho, safe_rho[:, None] * u,
                                        xp.where(valid, 2.0 * energy, d * 1.0), tensor, xp,
                                        self.moments.points, self.nodes)
        rate = xp.where(valid & ok, self.rates(safe_rho, temperature,
                                                xp.where(energy > 0, energy, 1.0)), 0.0)
        shape = (-1,) + (1,) * d
        return ((rate / self.knudsen).reshape(shape) * (target - flat)).reshape(f.shape)


class EllipsoidalLevel(RelaxationLevel):
    """The granular ES-BGK level: :class:`EllipsoidalEquation` stepped by the run's own
    time integrator, then cooled as the BGK level (:class:`RelaxationLevel`): the full
    operator's viscosity and conductivity in the first Sonine approximation."""

    name = "esbgk"

    def __init__(self, context):
        self.parts = FluidParts(context.equation)
        self.equation = EllipsoidalEquation(context.equation, context.shear_coefficient,
                                            context.heat_coefficient)
        self.integrator = context.integrator


class BoltzmannLevel(CollisionModel):
    """The full level: the run's time integrator on the run's collision operator (with the
    conservative correction and the round-off restoration of
    :meth:`~granframe.space.collisions.CellCollisions.restore`)."""

    name = "boltzmann"
    full = True

    def __init__(self, context):
        self.equation, self.integrator = context.equation, context.integrator

    def advance(self, f, t, dt):
        equation = self.equation
        before = equation.conserved(f) if equation.invariants else None
        return equation.restore(self.integrator.step(equation, t, f, dt), before)


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
        """c of nu_s = c rho T^(lambda/2) E^gamma, from :func:`relaxation_rate` of the
        run's operator at :attr:`temperature` (computed once per run)."""
        return self._coefficient("shear")

    @functools.cached_property
    def heat_coefficient(self) -> float:
        """c of nu_q = c rho T^(lambda/2) E^gamma (:func:`relaxation_rate`, "heat")."""
        return self._coefficient("heat")


def realizability(density, velocity, temperature, dx: float, periodic: bool, knudsen: float,
                  rate):
    r"""The Navier-Stokes realizability indicator of every cell (see the module notes),

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


def choose_levels(previous, kappa, delta, realizable, thresholds, distances,
                  hysteresis: float, reach, periodic: bool):
    """The level of every cell from its level ``previous`` and its indicators (see the
    module notes): for each level k >= 1, the cell is at least at k when kappa exceeds
    ``thresholds[k-1]`` or delta exceeds ``distances[k-1]``, each threshold scaled by
    ``hysteresis`` for a cell already at k or above; cells without an equilibrium
    (``realizable`` false) take the top level; then every cell lifts the cells within its
    ``reach`` (cells each side: an integer, or one per cell; across the ends of a
    periodic interval) to at least its own level."""
    top = len(thresholds)
    level = numpy.zeros(len(previous), dtype=numpy.int64)
    for k in range(1, top + 1):
        scale = numpy.where(previous >= k, hysteresis, 1.0)
        need = (kappa > thresholds[k - 1] * scale) | (delta > distances[k - 1] * scale)
        level = numpy.where(need, k, level)
    level = numpy.where(realizable, level, top)
    cells = len(level)
    reach = numpy.broadcast_to(numpy.asarray(reach, dtype=numpy.int64), (cells,))
    widened = level.copy()
    for j in numpy.flatnonzero((level > 0) & (reach > 0)):
        r = int(min(reach[j], cells))
        if periodic:
            near = numpy.arange(j - r, j + r + 1) % cells
        else:
            near = numpy.arange(max(j - r, 0), min(j + r, cells - 1) + 1)
        widened[near] = numpy.maximum(widened[near], level[j])
    return widened


def equilibrium_distance(context, time_step: float, steps: int = 12) -> float:
    r"""delta_inf: the relative L1 distance from its Maxwellian of the uniform state the
    full level tends to, for an inelastic gas (the homogeneous cooling state) or under a
    heat bath (the heated state); the Maxwellian closure of the fluid levels leaves it out.

    One cell, the Maxwellian of the run's mean initial temperature, advanced by the full
    level (the run's integrator and operator) for ``steps`` steps of
    min(dt, eps / nu) (nu the mean loss frequency): about ``steps`` collision times, in
    which the shape relaxes to its self-similar one while the temperature falls by
    exp(-steps zeta/nu) only. Returns the distance after the last step. Measured once
    per run, on the run's backend."""
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
        before = equation.conserved(cell) if equation.invariants else None
        cell = equation.restore(integrator.step(equation, k * step, cell, step), before)
    now, _, ok = parts.equilibria(cell, None)
    rho = parts.moments.primitives(cell, node="halves")[0]
    distance = xp.abs(cell - now).sum(axis=tuple(range(1, grid.dimension + 1)))
    value = float(to_host(distance * grid.cell_volume / rho).reshape(-1)[0])
    return value if bool(to_host(ok).reshape(-1)[0]) else 2.0


class HybridCollisions:
    """The collision step of a space run with a hierarchy (see the module notes).

    Every ``interval`` steps the levels of all cells are chosen (:func:`choose_levels`)
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
        #: tends to (:func:`equilibrium_distance`): 0 for an elastic gas without heat bath
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
        (:func:`choose_levels`)."""
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
