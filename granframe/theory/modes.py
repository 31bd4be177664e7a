r"""Linear granular hydrodynamics about the homogeneous cooling state of 3D inelastic hard
spheres: the shear mode, the longitudinal (sound and heat) modes and their critical
wavenumbers.

Linearising the granular Navier-Stokes equations with the first-Sonine coefficients
(:mod:`granframe.theory.sonine`) about the cooling state (rho_H, T_H(t), u = 0), in the
time tau = int nu_0 dt and the wavenumber k* = k sqrt(T_H)/nu_0 (Brey, Dufty, Kim &
Santos, Phys. Rev. E 58 (1998) 4638; Garzo, Phys. Rev. E 72 (2005) 021106; the derivation
in granframe's units is in docs/granular.md):

- the transverse velocity u_2 / sqrt(T) = A sin(k x) has the rate
  Gamma(k) = zeta/2 - (eta/rho) k^2 and grows for k < k_c = sqrt(rho zeta / (2 eta))
  (the shear instability, Goldhirsch & Zanetti, Phys. Rev. Lett. 70 (1993) 1619);
- the longitudinal amplitudes (rho', w, theta) of rho/rho_H - 1, i u_1/sqrt(T_H) and
  T/T_H - 1 obey d/d tau (rho', w, theta) = M(k*) (rho', w, theta)
  (:func:`longitudinal_matrix`), whose heat mode grows for k* < k*_h (the clustering
  instability).
"""

from __future__ import annotations

import math

import numpy

from granframe import validators as check
from granframe.theory.sonine import (elastic_viscosity, hard_sphere_cooling_rate,
                                     reference_frequency, transport_coefficients)


def shear_mode(restitution: float, knudsen: float, density: float, temperature: float,
               k: float) -> dict:
    r"""The shear mode of the cooling state in granframe's units (module notes):

        Gamma(k) = zeta/2 - eta k^2 / rho,   k_c = sqrt(rho zeta / (2 eta)),

    zeta the first-Sonine cooling rate (:func:`~granframe.theory.sonine.hard_sphere_cooling_rate`)
    and eta = eta_0 eta* the shear viscosity (Brey et al. 1998; Garzo & Dufty 1999).

    Returns
    -------
    dict
        ``zeta``, ``eta``, ``rate`` (Gamma(k)) and ``k_c``.
    """
    eta = elastic_viscosity(knudsen, temperature) * transport_coefficients(restitution)["eta*"]
    zeta = hard_sphere_cooling_rate(restitution, knudsen, density, temperature)
    return {"zeta": zeta, "eta": eta, "rate": zeta / 2 - eta * k * k / density,
            "k_c": math.sqrt(density * zeta / (2 * eta))}


def longitudinal_matrix(restitution: float, k_star: float, zeta: float | None = None,
                        conduction: float = 1.0):
    r"""The linearised Navier-Stokes matrix M of the longitudinal modes about the cooling
    state, d/d tau (rho', w, theta) = M (rho', w, theta), for the Fourier amplitudes of
    rho/rho_H - 1, i u_1/sqrt(T_H) and T/T_H - 1 at wavenumber k* = k sqrt(T_H)/nu_0, in
    tau = int nu_0 dt (Brey, Dufty, Kim & Santos 1998; docs/granular.md):

        d rho'/d tau  = k* w
        d w/d tau     = -k* (rho' + theta) + (zeta*/2 - (4/3) eta* k*^2) w
        d theta/d tau = -(zeta* + (5/2) mu* k*^2) rho' + (2/3) k* w
                        - (zeta*/2 + (5/2) kappa* k*^2) theta

    (w = i u_1/sqrt(T) makes the matrix real; the compression -div u enters rho' and theta
    with the same sign, as in n and (3/2) n T, so that in the elastic limit the pair of
    complex eigenvalues is sound, -(k*^2/2)((4/3) eta* + kappa*) +- i sqrt(5/3) k*:
    Landau & Lifshitz, Fluid Mechanics, section 79).

    Parameters
    ----------
    restitution : float
        e.
    k_star : float
        k*.
    zeta : float or None
        A zeta* to use instead of the first-Sonine one (eta*, kappa*, mu* stay).
    conduction : float
        A factor on kappa* and mu* (on the heat flux).

    Returns
    -------
    numpy.ndarray
        M, 3 x 3.
    """
    c = transport_coefficients(restitution)
    if zeta is not None:
        c["zeta*"] = zeta
    c["kappa*"] *= conduction
    c["mu*"] *= conduction
    return numpy.array([
        [0.0, k_star, 0.0],
        [-k_star, c["zeta*"] / 2 - 4 / 3 * c["eta*"] * k_star ** 2, -k_star],
        [-(c["zeta*"] + 2.5 * c["mu*"] * k_star ** 2), 2 / 3 * k_star,
         -(c["zeta*"] / 2 + 2.5 * c["kappa*"] * k_star ** 2)]])


def heat_critical_wavenumber(restitution: float) -> float:
    r"""k*_h, where the heat mode stops growing: det M(k*) = k*^2 (zeta*/2 - (5/2)(kappa* -
    mu*) k*^2) (expanding :func:`longitudinal_matrix` along its first row) vanishes at

        k*_h = sqrt(zeta* / (5 (kappa* - mu*))),

    and a longitudinal perturbation of k* < k*_h has a growing mode (the clustering
    instability; Brey, Dufty, Kim & Santos 1998, in the units k* = k sqrt(T)/nu_0).
    Below e = 0.1878 the first-Sonine kappa* - mu* is not positive and there is no such
    threshold: refused by name."""
    c = transport_coefficients(restitution)
    conduction = c["kappa*"] - c["mu*"]
    if not conduction > 0.0:
        check.reject("heat_critical_wavenumber", "restitution", restitution,
                     f"must be above 0.1878: kappa* - mu* = {conduction:.4g} <= 0 there in "
                     "first-Sonine theory, which then has no heat-mode threshold")
    return math.sqrt(c["zeta*"] / (5.0 * conduction))


def heat_mode_index(values, k_star: float) -> int:
    """Which of the eigenvalues ``values`` of :func:`longitudinal_matrix` at k* is the heat
    mode's: the real one with the largest real part (the other two are the sound pair,
    complex at k* > 0, and at k* = 0 the eigenvalues 0 and -zeta*/2)."""
    real = numpy.flatnonzero(numpy.abs(values.imag) <= 1e-12 * max(1.0, abs(k_star)))
    return int(real[numpy.argmax(values.real[real])])


def heat_mode(restitution: float, k_star: float, zeta: float | None = None,
              conduction: float = 1.0):
    r"""The heat mode of :func:`longitudinal_matrix` at k*: M v = lambda v with lambda the
    real eigenvalue with the largest real part (:func:`heat_mode_index`), per unit tau, and
    v = (rho', w, theta) scaled to rho' = 1; at k*_h (:func:`heat_critical_wavenumber`)
    lambda = 0 and v = (1, 0, -1), an isobaric mode. ``zeta``, ``conduction`` as for
    :func:`longitudinal_matrix`.

    Returns
    -------
    tuple
        (lambda, v).
    """
    values, vectors = numpy.linalg.eig(longitudinal_matrix(restitution, k_star, zeta,
                                                           conduction))
    index = heat_mode_index(values, k_star)
    vector = vectors[:, index].real
    return float(values[index].real), vector / vector[0]


def density_response(restitution: float, knudsen: float, temperature: float, k: float, s):
    r"""rho'(s)/rho'(0) of linear Navier-Stokes for a density mode with u = 0 and T uniform
    at s = 0, in the rescaled time s of a hard-sphere run at the temperature T_g
    (d tau = nu_0(T_g) ds, :func:`~granframe.theory.sonine.reference_frequency`):

        rho'(s) = e_1 . V exp(Lambda nu_0 s) V^{-1} e_1,

    with M(k*) = V Lambda V^{-1} (:func:`longitudinal_matrix`, k* = k sqrt(T_g)/nu_0).

    Returns
    -------
    numpy.ndarray
        rho'(s)/rho'(0) at each s.
    """
    nu0 = reference_frequency(knudsen, 1.0, temperature)
    matrix = longitudinal_matrix(restitution, k * math.sqrt(temperature) / nu0)
    values, vectors = numpy.linalg.eig(matrix)
    weights = numpy.linalg.solve(vectors, numpy.array([1.0, 0.0, 0.0]))
    tau = nu0 * numpy.asarray(s, dtype=float)
    return numpy.real((vectors[0][None, :] * weights[None, :]
                       * numpy.exp(values[None, :] * tau[:, None])).sum(axis=1))


def longitudinal_maxwellian(x, v1, v2, v3, k: float, amplitude: float, density: float,
                            velocity: float, temperature: float):
    r"""The local Maxwellian of a longitudinal mode about rho = T = 1, u = 0 (3D):

        rho = 1 + A r sin(k x),   u_1 = A w cos(k x),   T = 1 + A theta sin(k x),
        f = rho (2 pi T)^{-3/2} exp(-((v_1 - u_1)^2 + v_2^2 + v_3^2) / (2 T)),

    with (r, w, theta) = (``density``, ``velocity``, ``temperature``) in the variables of
    :func:`longitudinal_matrix` (for u_1 = A w cos(k x), the continuity equation
    d rho/dt = -d u_1/dx gives the eigen-relation lambda r = k* w of its first row): the
    Navier-Stokes mode (:func:`heat_mode`) as the initial data of a kinetic run
    (``initial = {name = "space_function", function =
    "granframe.theory.modes:longitudinal_maxwellian", params = {...}}``)."""
    phase = k * numpy.asarray(x)
    rho = 1.0 + amplitude * density * numpy.sin(phase)
    u1 = amplitude * velocity * numpy.cos(phase)
    t = 1.0 + amplitude * temperature * numpy.sin(phase)
    return (rho / (2.0 * math.pi * t) ** 1.5
            * numpy.exp(-((v1 - u1) ** 2 + v2 ** 2 + v3 ** 2) / (2.0 * t)))
