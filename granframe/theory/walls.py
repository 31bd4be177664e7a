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

from granframe import validators as check
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
        ``rho_b``, ``Lambda``, ``T_min/T_b``, ``rho_max/rho_b``, ``T/T_b`` at the 101
        ``distance`` values from the centre (0 to 1/2), and ``wall slope``, dW/dx at
        x = 0 (into the gas: negative, the gas is colder inside).
    """
    coefficients = transport_coefficients(restitution)
    eps = math.sqrt(2.0) * knudsen
    conduction = coefficients["kappa*"] - coefficients["mu*"]
    c = 6.144 * coefficients["zeta*"] / (math.pi * eps * eps * conduction)
    x = numpy.linspace(0.0, 0.5, 101)
    if c == 0.0:                                   # elastic: no sink, a uniform gas
        return {"rho_b": 1.0, "Lambda": 0.0, "T_min/T_b": 1.0, "rho_max/rho_b": 1.0,
                "distance": x, "T/T_b": numpy.ones_like(x), "wall slope": 0.0}

    def shoot(beta):
        """From the centre: V = W/W_c with V(0) = 1, V'(0) = 0, V'' = beta V^(-1/3)
        (beta = Lambda W_c^(-4/3)), on 0 <= y <= 1/2 (y the distance from the centre)."""
        solution = scipy.integrate.solve_ivp(
            lambda _, y: [y[1], beta * y[0] ** (-1.0 / 3.0)], (0.0, 0.5), [1.0, 0.0],
            t_eval=x, rtol=1e-12, atol=1e-14, method="DOP853")
        v = solution.y[0]
        w = v / v[-1]                              # W = V / V(1/2): W = 1 at the wall
        rho_b = 1.0 / (2.0 * scipy.integrate.simpson(w ** (-2.0 / 3.0), x=x))
        slope = -solution.y[1][-1] / v[-1]         # dW/dx at x = 0, into the gas
        return w, rho_b, beta * v[-1] ** (-4.0 / 3.0), slope  # Lambda = beta W_c^(4/3)

    def mismatch(log_beta):
        _, rho_b, lam, _ = shoot(math.exp(log_beta))
        return math.log(lam / (c * rho_b * rho_b))

    log_beta = scipy.optimize.brentq(mismatch, math.log(1e-8), math.log(1e8), xtol=1e-13)
    w, rho_b, lam, slope = shoot(math.exp(log_beta))
    temperature = w ** (2.0 / 3.0)
    return {"rho_b": rho_b, "Lambda": lam, "T_min/T_b": float(temperature[0]),
            "rho_max/rho_b": float(1.0 / temperature[0]), "distance": x,
            "T/T_b": temperature, "wall slope": float(slope)}


#: The temperature-jump coefficient of hard spheres under diffuse reflection,
#: T - T_w = c lambda dT/dn at the wall (n into the gas, lambda = 1/(sqrt 2 n pi sigma^2)
#: the hard-sphere mean free path): Sone's d_1 = 2.4001 in his unit k = (sqrt(pi)/2)
#: lambda/L (Y. Sone, T. Ohwada & K. Aoki, Phys. Fluids A 1 (1989) 363; Y. Sone,
#: *Molecular Gas Dynamics*, Birkhauser 2007, table 3.1), so c = 2.4001 sqrt(pi)/2.
HARD_SPHERE_JUMP = 2.4001 * math.sqrt(math.pi) / 2.0


def heated_walls_jump(restitution: float, knudsen: float,
                      jump: float = HARD_SPHERE_JUMP) -> dict:
    r"""The steady Navier-Stokes profile between the walls with a temperature jump at them:
    the gas next to a wall at T_w = 1 is at

        T_b = 1 + c lambda_b dT/dx|_{x=0},   lambda_b = eps/(sqrt 2 rho_b) = Kn/rho_b,

    c = ``jump`` (:data:`HARD_SPHERE_JUMP`, Sone's first-order jump of the elastic
    hard-sphere gas; its change with e is of order 1 - e and is not included). The shape
    W = (T/T_b)^{3/2} and rho_b do not depend on T_b (:func:`heated_walls_profile`), and
    T = T_b W^{2/3} gives dT/dx|_0 = (2/3) T_b W'(0), so the jump fixes T_b in closed form,

        T_b = 1 / (1 - (2/3) c (Kn/rho_b) W'(0)),

    and with it the absolute profiles T(x) = T_b W^{2/3}, rho(x) = rho_b T_b / T(x)
    (p = rho_b T_b uniform). Valid outside the walls' Knudsen layers (a few lambda_b),
    where Sone's asymptotic theory adds a layer correction that decays exponentially.

    Returns
    -------
    dict
        The entries of :func:`heated_walls_profile` and ``T_b``, ``pressure``, ``lambda_b``,
        and ``temperature``, ``density`` at the ``distance`` values from the centre.
    """
    if not (math.isfinite(jump) and jump >= 0.0):
        check.reject("heated_walls_jump", "jump", jump, "a finite number >= 0")
    profile = heated_walls_profile(restitution, knudsen)
    lambda_b = knudsen / profile["rho_b"]
    t_b = 1.0 / (1.0 - (2.0 / 3.0) * jump * lambda_b * profile["wall slope"])
    temperature = t_b * profile["T/T_b"]
    return {**profile, "T_b": t_b, "pressure": profile["rho_b"] * t_b,
            "lambda_b": lambda_b, "temperature": temperature,
            "density": profile["rho_b"] * t_b / temperature}


def heated_walls_maxwellian(x, v1, v2, v3, restitution: float, knudsen: float):
    r"""The local Maxwellian at rest of :func:`heated_walls_jump`'s profile on [0, 1],

        f = rho(x) (2 pi T(x))^{-3/2} exp(-|v|^2 / (2 T(x))),

    the initial data of a run that starts at the Navier-Stokes state (``initial = {name =
    "space_function", function = "granframe.theory.walls:heated_walls_maxwellian",
    params = {restitution = E, knudsen = KN}}``): it relaxes to the kinetic steady state
    in a few mean free times instead of the heat-conduction time from a uniform gas."""
    result = heated_walls_jump(restitution, knudsen)
    distance = numpy.abs(numpy.asarray(x, dtype=float) - 0.5)
    temperature = numpy.interp(distance, result["distance"], result["temperature"])
    density = result["pressure"] / temperature
    return (density / (2.0 * math.pi * temperature) ** 1.5
            * numpy.exp(-(v1 ** 2 + v2 ** 2 + v3 ** 2) / (2.0 * temperature)))
