r"""A granular gas heated by two walls (no gravity): the steady granular Navier-Stokes
profile of 3D inelastic hard spheres with the first-Sonine coefficients.

Walls at x = 0 and x = 1, mean density 1, eps = sqrt(2) Kn (lambda_mfp = eps / (sqrt 2 rho),
docs/granular.md). The steady state has u = 0 and, to Navier-Stokes order, a uniform
pressure p = rho T; the energy balance is

    d q / dx = -(3/2) zeta rho T,
    q = -kappa dT/dx - mu d rho/dx = -kappa_0 (kappa* - mu*) dT/dx

(with rho = p/T: mu d rho/dx = -mu (p/T^2) dT/dx = -kappa_0 mu* dT/dx, since mu =
kappa_0 T mu*/n), kappa_0 = (75/64) eps sqrt(pi T), zeta = nu_0 zeta*, nu_0 = 16 n sqrt(T) /
(5 eps sqrt(pi)), with the first-Sonine coefficients of Garzo & Dufty, Phys. Rev. E 59
(1999) 5895 (:mod:`granframe.theory.sonine`; the derivation: docs/granular.md, section 1).
With
w = T^{3/2} it is w'' = C p^2 w^{-1/3}, C = 6.144 zeta* / (pi eps^2 (kappa* - mu*)); in
units of the gas at the wall (T_b, rho_b = p/T_b), W = (T/T_b)^{3/2} solves

    W'' = Lambda W^{-1/3},  W(0) = W(1) = 1,   Lambda = C rho_b^2,

and the mass fixes rho_b: rho_b int_0^1 W^{-2/3} dx = 1. So T_min/T_b and rho_max/rho_b
follow from e and eps alone, whatever the temperature jump T_w - T_b at the walls.
"""

from __future__ import annotations

import math

import numpy
import scipy.integrate
import scipy.optimize

from granframe.theory.sonine import transport_coefficients


def heated_walls_profile(restitution: float, knudsen: float) -> dict:
    r"""The steady Navier-Stokes profile between the walls (module notes).

    Shot from the centre, where the profile is flat: V'' = beta V^(-1/3), V(0) = 1,
    V'(0) = 0 (DOP853, rtol 1e-12) gives W = V/V(1/2) for Lambda = beta V(1/2)^(4/3), and
    beta is found (Brent's method) so that Lambda = C rho_b^2 with rho_b from the mass
    (Simpson's rule). An elastic gas (e = 1) has no sink: a uniform profile.

    Parameters
    ----------
    restitution : float
        e.
    knudsen : float
        Kn (eps = sqrt(2) Kn).

    Returns
    -------
    dict
        ``rho_b``, ``Lambda``, ``T_min/T_b``, ``rho_max/rho_b``, and ``T/T_b`` at the 101
        ``distance`` values from the centre (0 to 1/2).
    """
    coefficients = transport_coefficients(restitution)
    eps = math.sqrt(2.0) * knudsen
    conduction = coefficients["kappa*"] - coefficients["mu*"]
    c = 6.144 * coefficients["zeta*"] / (math.pi * eps * eps * conduction)
    x = numpy.linspace(0.0, 0.5, 101)
    if c == 0.0:                                   # elastic: no sink, a uniform gas
        return {"rho_b": 1.0, "Lambda": 0.0, "T_min/T_b": 1.0, "rho_max/rho_b": 1.0,
                "distance": x, "T/T_b": numpy.ones_like(x)}

    def shoot(beta):
        """From the centre: V = W/W_c with V(0) = 1, V'(0) = 0, V'' = beta V^(-1/3)
        (beta = Lambda W_c^(-4/3)), on 0 <= y <= 1/2 (y the distance from the centre)."""
        solution = scipy.integrate.solve_ivp(
            lambda _, y: [y[1], beta * y[0] ** (-1.0 / 3.0)], (0.0, 0.5), [1.0, 0.0],
            t_eval=x, rtol=1e-12, atol=1e-14, method="DOP853")
        v = solution.y[0]
        w = v / v[-1]                              # W = V / V(1/2): W = 1 at the wall
        rho_b = 1.0 / (2.0 * scipy.integrate.simpson(w ** (-2.0 / 3.0), x=x))
        return w, rho_b, beta * v[-1] ** (-4.0 / 3.0)    # Lambda = beta W_c^(4/3)

    def mismatch(log_beta):
        _, rho_b, lam = shoot(math.exp(log_beta))
        return math.log(lam / (c * rho_b * rho_b))

    log_beta = scipy.optimize.brentq(mismatch, math.log(1e-8), math.log(1e8), xtol=1e-13)
    w, rho_b, lam = shoot(math.exp(log_beta))
    temperature = w ** (2.0 / 3.0)
    return {"rho_b": rho_b, "Lambda": lam, "T_min/T_b": float(temperature[0]),
            "rho_max/rho_b": float(1.0 / temperature[0]), "distance": x,
            "T/T_b": temperature}
