"""Exact solutions and laws used to validate the operators (review, sections 1 and 3)."""

from __future__ import annotations

import math

import numpy

from granframe import validators as check


def _bkw_profile(grid, shape_parameter, xp=numpy):
    """f(K, v) of the BKW solution, evaluated for a real or complex K."""
    v2 = grid.speed_squared(xp)
    K = shape_parameter
    if grid.dimension == 2:
        return xp.exp(-v2 / (2 * K)) * (2 * K - 1 + (1 - K) / (2 * K) * v2) / (2 * math.pi * K * K)
    return (xp.exp(-v2 / (2 * K)) * ((5 * K - 3) / K + (1 - K) / (K * K) * v2)
            / (2 * (2 * math.pi * K) ** 1.5))


def bkw(grid, time: float, xp=numpy):
    """BKW solution of the elastic Boltzmann equation for Maxwell molecules, and its time derivative.

    With B = 1/(2 pi) in 2D and B = 1/(4 pi) in 3D (the review's constants),
    mass 1, zero momentum and temperature 1:

    - 2D: f = exp(-v^2/(2K)) (2K - 1 + (1-K) v^2/(2K)) / (2 pi K^2), K = 1 - exp(-t/8)/2;
    - 3D: f = exp(-v^2/(2K)) ((5K-3)/K + (1-K) v^2/K^2) / (2 (2 pi K)^{3/2}), K = 1 - exp(-t/6).

    f >= 0 requires K >= 1/2 (2D, all t >= 0) and K >= 3/5 (3D, t >= 6 ln(5/2)).
    Returns ``(f, df/dt)`` on the grid; df/dt = (df/dK) K'(t) with df/dK by a
    complex-step derivative, exact to round-off.

    References: A. V. Bobylev (1975); M. Krook, T. T. Wu, Phys. Fluids 20 (1977).
    """
    if not check.is_real(time) or not math.isfinite(time) or time < 0:
        check.reject("bkw", "time", time, "must be a finite real number >= 0")
    if grid.dimension == 2:
        K, dK = 1 - math.exp(-time / 8) / 2, math.exp(-time / 8) / 16
    else:
        K, dK = 1 - math.exp(-time / 6), math.exp(-time / 6) / 6
        if K < 0.6:
            check.reject("bkw", "time", time, "must be >= 6 ln(5/2) = 5.4977 in 3D (f >= 0)")
    step = 1e-30
    derivative = _bkw_profile(grid, complex(K, step), xp).imag / step
    return _bkw_profile(grid, K, xp), derivative * dK


def maxwell_energy_dissipation(grid, f, restitution: float, kernel) -> float:
    """Exact d/dt int |v|^2 f dv = int Q(f,f) |v|^2 dv for Maxwell molecules, constant e.

    From the weak form in the sigma-representation, |v'|^2 + |v'_*|^2 - |v|^2 - |v_*|^2
    = -(1-e^2)/4 |u|^2 (1 - uhat.sigma), u = v - v_*, so for B = C b(cos theta)

        int Q |v|^2 = -(1-e^2)/8 C int_S b(t)(1-t) dsigma int int f f_* |v-v_*|^2
                    = -(1-e^2)/4 C beta (rho int |v|^2 f - |int v f|^2),

    where beta = int_{S^{d-1}} b(uhat.sigma)(1 - uhat.sigma) dsigma (|S^{d-1}| for b = 1).
    With the review's C this is -(1-e^2) d rho^2 T / 4, the rate behind Haff's and the
    heated temperature laws.
    """
    d = grid.dimension
    if not kernel.is_maxwellian:
        check.reject("maxwell_energy_dissipation", "kernel", kernel,
                     "must be a Maxwell-molecule kernel (constant speed part)")
    beta = kernel.angular_integral(d, lambda t: 1 - t)
    rho = grid.mass(f)
    second = 2.0 * grid.kinetic_energy(f)
    momentum = grid.momentum(f)
    return (-(1 - restitution ** 2) / 4 * kernel.prefactor(d) * beta
            * (rho * second - momentum @ momentum))


def heated_maxwell_temperature(time, initial_temperature, restitution, heat_bath, density=1.0):
    """Temperature of the heated Maxwell-molecule problem (review, eq. (ext_temp)).

    T(t) = (T0 - 8 tau/(1-e^2)) exp(-rho0 (1-e^2) t / 4) + 8 tau/(1-e^2), for
    d_t f = Q(f,f) + tau Delta f with the review's B (1/(2 pi) in 2D, 1/(4 pi) in 3D).
    For e = 1 it is T0 + 2 tau t.
    """
    e, tau = restitution, heat_bath
    t = numpy.asarray(time, dtype=float)
    if e == 1.0:
        return initial_temperature + 2.0 * tau * t
    limit = 8.0 * tau / ((1.0 - e * e) * density)
    return (initial_temperature - limit) * numpy.exp(-density * (1 - e * e) / 4 * t) + limit


def heated_maxwell_law(kernel, restitution, heat_bath: float, knudsen: float = 1.0):
    """The exact temperature law T(t, T0, rho0) of a run, or ``None`` where none is known.

    It exists for Maxwell molecules with the review's constant (isotropic b,
    no energy factor) and a constant restitution coefficient, in 2D and 3D:
    d_t f = Q/eps + tau Delta f gives dT/dt = -rho (1-e^2) T / (4 eps) + 2 tau, i.e.
    :func:`heated_maxwell_temperature` with density rho/eps (Haff's exponential
    law when tau = 0).
    """
    from granframe.model.kernels import VariableHardSpheres
    from granframe.model.restitution import Constant

    if (not isinstance(kernel, VariableHardSpheres) or not kernel.is_maxwellian
            or not kernel.is_isotropic or kernel.energy_exponent != 0.0
            or kernel.constant is not None or not isinstance(restitution, Constant)):
        return None

    def law(time, initial_temperature, density):
        return heated_maxwell_temperature(time, initial_temperature, restitution.value,
                                          heat_bath, density / knudsen)

    return law
