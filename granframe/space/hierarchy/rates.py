r"""The rates of the fluid levels of the hierarchy (:mod:`granframe.space.hierarchy`): the
granular cooling rate of a Maxwellian (:class:`CoolingRate`), the rates at which the run's
own collision operator relaxes a shear stress and a heat flux (:func:`relaxation_rate`),
and how such a rate scales with the state of a cell (:func:`scaled_rates`).
"""

from __future__ import annotations

import functools
import math

import numpy

from granframe.backends import to_host
from granframe.model.restitution import is_elastic
from granframe.theory.cooling import maxwellian_cooling_rate

class CoolingRate:
    r"""The granular cooling rate zeta(rho, T, E) of a Maxwellian, d T/dt = -zeta T / eps.

    From the weak form in the sigma-representation, one collision of relative velocity
    g = v - v_* changes the energy by |v'|^2 + |v'_*|^2 - |v|^2 - |v_*|^2
    = -(1 - e(|g|)^2)/4 |g|^2 (1 - g.sigma/|g|), so that for B = C |g|^lambda b E^gamma

    .. math:: \int Q(f,f)|v|^2 dv = -\frac{C\beta\,E^\gamma}{8}\iint f f_*
              |g|^{\lambda+2}\bigl(1 - e(|g|)^2\bigr)\,dv\,dv_*,\qquad
              \beta = \int_{S^{d-1}} b(\hat g\cdot\sigma)(1 - \hat g\cdot\sigma)\,d\sigma .

    For a Maxwellian of density rho and temperature T, the double integral is rho^2 times
    the average over its relative speeds
    (:func:`~granframe.theory.cooling.relative_speed_average`), and with
    d/dt int |v|^2 f = rho d dT/dt (:func:`~granframe.theory.cooling.maxwellian_cooling_rate`
    with C beta, which gives the coefficient and the table below),

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
        rate = functools.partial(
            maxwellian_cooling_rate, dimension=d, speed_exponent=lam,
            scattering=kernel.prefactor(d) * kernel.angular_integral(d, lambda t: 1.0 - t))
        self.table = None
        self._tables = {}
        if self.elastic:
            self.coefficient = 0.0
        elif restitution.is_constant:
            e = float(numpy.asarray(restitution(numpy.array([1.0]))).reshape(-1)[0])
            #: zeta = coefficient rho E^gamma T^(lambda/2) for a constant e: the rate at
            #: rho = T = 1 (without E^gamma)
            self.coefficient = float(rate(e))
        else:
            self.coefficient = None
            top = float(grid.half_width) ** 2
            temperatures = top * numpy.logspace(-12.0, 0.0, 241)
            values = [rate(restitution, 1.0, t) for t in temperatures]
            self.table = (numpy.log(temperatures), numpy.log(numpy.maximum(values, 1e-300)))

    def __call__(self, density, temperature, energy, xp=numpy):
        """zeta of every cell (arrays in ``xp``)."""
        factor = self.kernel.energy_factors(energy) if self.kernel.energy_exponent else 1.0
        if self.coefficient is not None:
            if self.coefficient == 0.0:
                return 0.0 * density
            return self.coefficient * density * factor * temperature ** self.exponent
        log_t, log_z = self._table_in(xp)
        return density * factor * xp.exp(xp.interp(xp.log(temperature), log_t, log_z))

    def _table_in(self, xp):
        """:attr:`table` in ``xp``, copied there once per namespace."""
        if xp not in self._tables:
            self._tables[xp] = tuple(xp.asarray(a) for a in self.table)
        return self._tables[xp]

    def rates(self, density, temperature, energy, knudsen: float, heat_bath: float,
              xp=numpy):
        """|d ln T/dt| of the temperature law at T of every cell, zeta/eps + 2 tau/T
        (arrays in ``xp``): the rate that sets the substeps of :meth:`cooled`."""
        return self(density, temperature, energy, xp) / knudsen + 2.0 * heat_bath / temperature

    @staticmethod
    def substeps(rate: float, dt: float) -> int:
        """The RK4 substeps of :meth:`cooled` over dt for cells whose fastest rate is
        ``rate``: each at most a twentieth of 1/rate (between 1 and 100000)."""
        return int(min(max(1, math.ceil(20.0 * rate * dt)), 100000))

    def cooled(self, density, temperature, energy, dt: float, knudsen: float,
               heat_bath: float, xp=numpy, rate: float | None = None):
        r"""T after dt of dT/dt = -zeta(T) T / eps + 2 tau at fixed rho and E^gamma.

        A constant e without a heat bath has the closed form
        T (1 + (lambda/2) zeta dt/eps)^(-2/lambda) (T e^{-zeta dt/eps} for lambda = 0);
        otherwise classical RK4 on ln T with :meth:`substeps` for the fastest ``rate``
        (:meth:`rates`; relative error below 1e-7 where every cell's rate is at most
        ``rate``). The number of substeps is a host decision: a hierarchy passes the fastest
        rate of the cells at the start of the step, already on the host
        (:class:`StepRates`); without it the fastest rate of this batch is taken to the
        host, one device->host copy of one number."""
        if self.elastic and not heat_bath:
            return temperature
        zeta = self(density, temperature, energy, xp)
        if self.coefficient is not None and not heat_bath:
            x = zeta * (dt / knudsen)
            if self.exponent == 0.0:
                return temperature * xp.exp(-x)
            return temperature * (1.0 + self.exponent * x) ** (-1.0 / self.exponent)
        if rate is None:
            rate = float(to_host(xp.max(zeta / knudsen + 2.0 * heat_bath / temperature)))
        steps = self.substeps(rate, dt)
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


class StepRates:
    r"""The fastest rates of the temperature law over the cells at the start of a step, on
    the host, from which the fluid levels choose the substeps of
    :meth:`CoolingRate.cooled`: max over the cells of zeta/eps (cooling alone, as the
    relaxation levels cool) and of zeta/eps + 2 tau/T (with the heat bath, as the Euler
    level heats), from the density, velocity and temperature of every cell that the record
    of the previous step has already brought to the host (:meth:`follow`), so that no
    level reads its substeps from the device.

    The state a level advances differs from the recorded one by the step's transport, so
    the substeps hold the RK4 rule for the cells at the start of the step; every cell of
    every process counts (the maximum over the processes), so that the levels take the
    same substeps whatever cells a process holds and at whatever level they are. Before
    the first record (no rates yet) a level reads the rate of its own batch
    (:meth:`CoolingRate.cooled` without ``rate``).

    Parameters
    ----------
    cooling : CoolingRate
    knudsen, heat_bath : float
        eps and tau of the run.
    """

    def __init__(self, cooling: CoolingRate, knudsen: float, heat_bath: float):
        self.cooling, self.knudsen, self.heat_bath = cooling, knudsen, heat_bath
        #: {tau: the fastest rate} for tau = 0 and the run's tau, or None before the first
        #: :meth:`follow`
        self.values = None

    def fastest(self, heat_bath: float) -> float | None:
        """The fastest rate with the heat bath ``heat_bath`` (0 or the run's), or None."""
        return None if self.values is None else self.values[heat_bath]

    def follow(self, density, velocity, temperature, communicator) -> None:
        """The rates of the cells of this process (host arrays: density and temperature
        (cells,), velocity (cells, d)), combined over the processes of ``communicator``
        (one :meth:`~granframe.abc.Communicator.allgather` of two numbers); cells without
        a positive density and temperature do not count."""
        density, temperature = numpy.asarray(density), numpy.asarray(temperature)
        valid = (density > 0) & (temperature > 0) & numpy.isfinite(temperature)
        rho, t = density[valid], temperature[valid]
        d = numpy.asarray(velocity).shape[-1]
        energy = 0.5 * rho * ((numpy.asarray(velocity)[valid] ** 2).sum(axis=-1) + d * t)
        local = numpy.zeros(2)
        if rho.size:
            cooling = self.cooling.rates(rho, t, energy, self.knudsen, 0.0)
            heated = cooling + 2.0 * self.heat_bath / t
            local[:] = numpy.max(cooling), numpy.max(heated)
        fastest = communicator.allgather(local).max(axis=0)
        self.values = {0.0: float(fastest[0]), self.heat_bath: float(fastest[1])}


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
