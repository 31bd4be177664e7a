"""Exact solutions and laws used to validate the operators (review, sections 1 and 3)."""

from __future__ import annotations

import math

import numpy

from granframe import validators as check
from granframe.theory.cooling import maxwellian_cooling_rate


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
    d_t f = Q(f,f) + tau Delta f with the review's B (1/(2 pi) in 2D, 1/(4 pi) in 3D):
    rho0 (1-e^2)/4 is the cooling rate of Maxwell molecules
    (:func:`granframe.theory.cooling.maxwellian_cooling_rate`).
    For e = 1 it is T0 + 2 tau t.
    """
    e, tau = restitution, heat_bath
    t = numpy.asarray(time, dtype=float)
    if e == 1.0:
        return initial_temperature + 2.0 * tau * t
    limit = 8.0 * tau / ((1.0 - e * e) * density)
    # T0 e^-rate + limit (1 - e^-rate), no cancellation
    rate = maxwellian_cooling_rate(e, density) * t
    return initial_temperature * numpy.exp(-rate) - limit * numpy.expm1(-rate)


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


def _maxwell_pressure_coefficients(kernel, restitution: float, dimension: int):
    """(a1, a2) with int Q(f,f) v_i v_j dv = rho (a1 P_ij + a2 tr(P) delta_ij) for Maxwell
    molecules B = C b(cos theta) and a constant restitution e (see
    :func:`maxwell_pressure_rate`)."""
    if not kernel.is_maxwellian or getattr(kernel, "energy_exponent", 0.0) != 0.0:
        check.reject("maxwell_pressure_rate", "kernel", kernel,
                     "must be a Maxwell-molecule kernel (constant speed part, no energy factor)")
    if not check.is_real(restitution) or not 0.0 <= restitution <= 1.0:
        check.reject("maxwell_pressure_rate", "restitution", restitution,
                     "must be a constant restitution coefficient in [0, 1]")
    d, e = dimension, float(restitution)
    b0 = kernel.angular_integral(d)
    b1 = kernel.angular_integral(d, lambda t: t)
    b2 = kernel.angular_integral(d, lambda t: t * t)
    alpha1, alpha2 = (b0 - b2) / (d - 1), (d * b2 - b0) / (d - 1)
    a, b = (1.0 - e) / 4.0, (1.0 + e) / 4.0
    C = kernel.prefactor(d)
    return (C * (2 * a * a * b0 + 4 * a * b * b1 + 2 * b * b * alpha2 - b0 / 2),
            C * 2 * b * b * alpha1)


def _pressure_argument(owner, pressure):
    try:
        P = numpy.asarray(pressure, dtype=float)
    except (TypeError, ValueError):
        P = numpy.empty(0)
    if (P.ndim != 2 or P.shape[0] != P.shape[1] or P.shape[0] not in (2, 3)
            or not numpy.isfinite(P).all()):
        shown = P.tolist() if P.size else pressure
        check.reject(owner, "pressure", shown, "must be a 2 x 2 or 3 x 3 matrix of finite "
                     "real numbers")
    return P


def maxwell_pressure_rate(pressure, density: float, restitution: float, kernel,
                          heat_bath: float = 0.0, knudsen: float = 1.0):
    """Exact dP/dt of the pressure tensor for Maxwell molecules and a constant e.

    For d_t f = Q(f,f)/eps + tau Delta f, P_ij = int (v-u)_i (v-u)_j f dv obeys the closed
    linear ODE

        dP/dt = (rho/eps) (a1 P + a2 tr(P) I) + 2 tau rho I,

    which for the review's kernel (B = 1/(2 pi) in 2D, 1/(4 pi) in 3D, b = 1) reads

        dP/dt = (rho/eps) (-(1+e)(3-e)/8 P + (1+e)^2/(8d) tr(P) I) + 2 tau rho I.

    Derivation (weak form, sigma-representation). With g = v - v_*, V = (v + v_*)/2 and
    w = (1-e)/4 g + (1+e)/4 |g| sigma, v' = V + w and v'_* = V - w, so

        v'_i v'_j + v'_*i v'_*j - v_i v_j - v_*i v_*j = 2 w_i w_j - g_i g_j / 2.

    Over the sphere, with t = ghat.sigma, int b sigma dsigma = beta1 ghat and
    int b sigma_i sigma_j dsigma = alpha1 delta_ij + alpha2 ghat_i ghat_j, where
    beta0 = int b, beta1 = int b t, beta2 = int b t^2, alpha1 = (beta0 - beta2)/(d-1),
    alpha2 = (d beta2 - beta0)/(d-1) (alpha1 = |S^{d-1}|/d, alpha2 = beta1 = 0 for b = 1).
    Writing a = (1-e)/4, b = (1+e)/4 and using int int f f_* g_i g_j = 2 rho P_ij
    (momentum is conserved),

        int Q v_i v_j = (C/2) int int f f_* int_S b (2 w_i w_j - g_i g_j/2) dsigma
                      = rho (a1 P_ij + a2 tr(P) delta_ij),
        a1 = C (2 a^2 beta0 + 4 a b beta1 + 2 b^2 alpha2 - beta0/2),  a2 = 2 C b^2 alpha1,

    and int Delta f v_i v_j = 2 rho delta_ij; mass and momentum are conserved, so
    dP/dt = d/dt int v_i v_j f. The trace, a1 + d a2 = -(1-e^2) C (beta0 - beta1)/4, is
    :func:`maxwell_energy_dissipation` (C |S^{d-1}| = 1 for the review's kernel).

    Parameters
    ----------
    pressure : array_like
        P, d x d.
    density : float
        rho (constant in time).
    restitution : float
        The constant e in [0, 1].
    kernel : granframe.model.kernels.VariableHardSpheres
        A Maxwell-molecule kernel (its C and b enter through a1 and a2).
    heat_bath, knudsen : float
        tau and eps.

    Returns
    -------
    numpy.ndarray
        dP/dt, d x d.
    """
    P = _pressure_argument("maxwell_pressure_rate", pressure)
    d = len(P)
    a1, a2 = _maxwell_pressure_coefficients(kernel, restitution, d)
    return (density / knudsen * (a1 * P + a2 * numpy.trace(P) * numpy.eye(d))
            + 2.0 * heat_bath * density * numpy.eye(d))


def maxwell_pressure_tensor(time, initial_pressure, density: float, restitution: float,
                            kernel, heat_bath: float = 0.0, knudsen: float = 1.0):
    """The pressure tensor P(t) of Maxwell molecules with a constant e, in closed form.

    Solves the ODE of :func:`maxwell_pressure_rate`, dP/dt = (rho/eps)(a1 P + a2 tr(P) I)
    + 2 tau rho I, from P(0) = P0. Its isotropic part tr(P)/d I = rho T I and its
    traceless part D = P - tr(P)/d I decouple:

        T(t) = T0 exp(-k_T t) + 2 tau (1 - exp(-k_T t)) / k_T,   k_T = -(rho/eps)(a1 + d a2),
        D(t) = D0 exp(-k_D t),                                     k_D = -(rho/eps) a1,

    (T = T0 + 2 tau t when k_T = 0, e = 1). For the review's kernel k_T = rho (1-e^2)/(4 eps),
    the law of :func:`heated_maxwell_temperature`, and

        k_D = rho (1+e)(3-e) / (8 eps)

    in 2D and 3D alike (rho/(2 eps) when elastic): the anisotropy relaxes faster than the
    temperature cools, so an anisotropic state tends to the isotropic homogeneous cooling
    (or heated) state.

    Parameters
    ----------
    time : float or array_like
        Times t >= 0.
    initial_pressure : array_like
        P0, d x d.
    density, restitution, kernel, heat_bath, knudsen
        As for :func:`maxwell_pressure_rate`.

    Returns
    -------
    numpy.ndarray
        P(t), of shape ``numpy.shape(time) + (d, d)``.
    """
    P0 = _pressure_argument("maxwell_pressure_tensor", initial_pressure)
    d = len(P0)
    a1, a2 = _maxwell_pressure_coefficients(kernel, restitution, d)
    t = numpy.asarray(time, dtype=float)[..., None, None]
    k_T, k_D = -density / knudsen * (a1 + d * a2), -density / knudsen * a1
    T0 = numpy.trace(P0) / (d * density)
    growth = t if k_T == 0.0 else -numpy.expm1(-k_T * t) / k_T      # int_0^t exp(-k_T s) ds
    T = T0 * numpy.exp(-k_T * t) + 2.0 * heat_bath * growth
    identity = numpy.eye(d)
    return density * T * identity + (P0 - T0 * density * identity) * numpy.exp(-k_D * t)


def maxwell_pressure_law(kernel, restitution, heat_bath: float, knudsen: float = 1.0):
    """The exact pressure-tensor law P(t, P0, rho0) of a run, or ``None`` where none is known.

    It exists for Maxwell molecules (any constant C and angular part b, no energy factor)
    and a constant restitution coefficient: :func:`maxwell_pressure_tensor`.
    """
    from granframe.model.kernels import VariableHardSpheres
    from granframe.model.restitution import Constant

    if (not isinstance(kernel, VariableHardSpheres) or not kernel.is_maxwellian
            or kernel.energy_exponent != 0.0 or not isinstance(restitution, Constant)):
        return None

    def law(time, initial_pressure, density):
        return maxwell_pressure_tensor(time, initial_pressure, density, restitution.value,
                                       kernel, heat_bath, knudsen)

    return law
