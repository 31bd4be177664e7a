r"""The Navier-Stokes profile of a steady normal shock in a gas of elastic hard spheres
(Gilbarg & Paolucci, J. Rational Mech. Anal. 2 (1953) 617), for context next to the
kinetic (DSMC, spectral) profiles.

Units (granframe's): unit particle mass, Boltzmann constant 1, p = rho T, three velocity
dimensions (gamma = 5/3); the upstream state rho_1 = 1, T_1 = 1, u_1 = M sqrt(gamma) in the
shock's frame; lengths in units of the upstream hard-sphere mean free path
lambda_1 = 1 / (sqrt(2) n_1 pi sigma_d^2).

Transport coefficients: the first Chapman-Enskog (first Sonine) approximations for hard
spheres of diameter sigma_d (Chapman & Cowling, *The Mathematical Theory of Non-Uniform
Gases*, 3rd ed., sections 10.21 and 12.1),

    mu = 5 / (16 sigma_d^2) sqrt(m k T / pi),   kappa = (15/4) (k/m) mu   (Prandtl 2/3).

With 1/sigma_d^2 = sqrt(2) pi n_1 lambda_1 this is, at unit mass and k,

    mu(T) = (5/16) sqrt(2 pi) rho_1 lambda_1 sqrt(T_1) (T/T_1)^{1/2} = 0.78332... sqrt(T)

in these units; equivalently lambda_1 = 16 mu_1 / (5 rho_1 sqrt(2 pi T_1)), the
"viscosity-based" mean free path, which for hard spheres with the first Chapman-Enskog mu
is exactly the kinetic one. (The converged Sonine series gives mu 1.016 and kappa 1.025
times these; not used here.)

The equations: the steady 1D Navier-Stokes equations integrate once to the fluxes of
mass, momentum and energy being uniform, m = rho u = rho_1 u_1,

    (4/3) mu u' = m (u + T/u) - P,                       P = m (u_1 + T_1/u_1),
    kappa T'    = m ((3/2) T - u^2/2) + u P - E,        E = m ((5/2) T_1 + u_1^2/2),

an autonomous system in (u, T) whose two rest points are the Rankine-Hugoniot states.
The upstream one is an unstable node, the downstream one a saddle; the shock is the
trajectory entering the saddle along its stable eigenvector, found here by integrating
backwards in x from a point 1e-9 (u_1 - u_2) from the saddle along that eigenvector
(Gilbarg & Paolucci 1953; Landau & Lifshitz, *Fluid Mechanics*, section 93).

The inverse maximum-slope density thickness lambda_1 / delta, delta = (rho_2 - rho_1) /
max |d rho/dx|, is evaluated from the exact slope d rho/dx = -m u'/u^2 of the ODE, not
by differencing. As M -> 1 it tends to Taylor's weak shock, delta = 8 b / ((gamma + 1)
(u_1 - u_2)) with b = (4/3) mu + kappa (1/c_v - 1/c_p) = (7/3) mu (0.5 % apart at
M = 1.01, 1 % at 1.02). Values: lambda_1/delta = 0.1752 (M = 1.5), 0.3325 (2), 0.5533 (3).
"""

from __future__ import annotations

import functools
import math

import numpy
import scipy.integrate
import scipy.optimize

#: ratio of specific heats of a monatomic gas
GAMMA = 5.0 / 3.0

#: mu_1 / (rho_1 lambda_1 sqrt(T_1)) for hard spheres, first Chapman-Enskog approximation
VISCOSITY = 5.0 / 16.0 * math.sqrt(2.0 * math.pi)


def rankine_hugoniot(mach: float, gamma: float = GAMMA) -> dict:
    r"""The downstream state of the normal shock, upstream rho_1 = T_1 = 1, u_1 = M
    sqrt(gamma) (Landau & Lifshitz, *Fluid Mechanics*, section 89).

    rho_2 = (gamma + 1) M^2 / ((gamma - 1) M^2 + 2), p_2 = (2 gamma M^2 - (gamma - 1)) /
    (gamma + 1), T_2 = p_2 / rho_2, u_2 = u_1 / rho_2.

    Returns
    -------
    dict
        ``rho1``, ``T1``, ``u1``, ``rho2``, ``T2``, ``u2``, ``p2``.
    """
    mach = float(mach)
    if not (mach > 1.0 and math.isfinite(mach)):
        raise ValueError(f"rankine_hugoniot: parameter 'mach' = {mach!r} is invalid; must be "
                         "a finite number > 1")
    rho2 = (gamma + 1.0) * mach ** 2 / ((gamma - 1.0) * mach ** 2 + 2.0)
    p2 = (2.0 * gamma * mach ** 2 - (gamma - 1.0)) / (gamma + 1.0)
    u1 = mach * math.sqrt(gamma)
    return {"rho1": 1.0, "T1": 1.0, "u1": u1, "rho2": rho2, "T2": p2 / rho2,
            "u2": u1 / rho2, "p2": p2}


def hard_sphere_viscosity(temperature):
    """mu(T) = (5/16) sqrt(2 pi) sqrt(T) (first Chapman-Enskog, lambda_1 = rho_1 = 1)."""
    return VISCOSITY * numpy.sqrt(temperature)


def navier_stokes_shock(mach: float, points: int = 2001, span: float | None = None) -> dict:
    r"""The Navier-Stokes profile of the hard-sphere shock at Mach ``mach``.

    Parameters
    ----------
    mach : float
        The upstream Mach number M > 1.
    points : int
        Points of the returned profile.
    span : float, optional
        The profile is returned on [-span, span] lambda_1 around the density midpoint
        (default: 6 / (lambda_1/delta), three thicknesses each side).

    Returns
    -------
    dict
        ``x`` (from the density midpoint rho = (rho_1 + rho_2)/2), ``density``,
        ``velocity``, ``temperature``, ``inverse_thickness`` (lambda_1/delta), ``state``
        (:func:`rankine_hugoniot`) and ``x_max_slope`` (where the slope is largest).
    """
    state = rankine_hugoniot(mach)
    u1, t1, u2, t2 = state["u1"], state["T1"], state["u2"], state["T2"]
    rho1, rho2 = state["rho1"], state["rho2"]
    m = rho1 * u1
    P = m * (u1 + t1 / u1)
    E = m * (2.5 * t1 + 0.5 * u1 ** 2)
    cv = 1.5

    def rates(y):
        u, t = y
        mu = hard_sphere_viscosity(t)
        kappa = 2.5 * cv * mu                                  # (15/4) mu
        return numpy.array([(m * (u + t / u) - P) / (4.0 / 3.0 * mu),
                            (m * (cv * t - 0.5 * u * u) + u * P - E) / kappa])

    mu2 = hard_sphere_viscosity(t2)
    jacobian = numpy.array([[m * (1.0 - t2 / u2 ** 2), m / u2],
                            [P - m * u2, m * cv]])
    jacobian /= numpy.array([[4.0 / 3.0 * mu2], [2.5 * cv * mu2]])
    values, vectors = numpy.linalg.eig(jacobian)
    if not (values.real.min() < 0.0 < values.real.max()):
        raise ValueError(f"navier_stokes_shock: the downstream state at M = {mach!r} is not a "
                         "saddle")
    stable = vectors[:, int(numpy.argmin(values.real))].real
    stable = stable / stable[0]                                 # u grows upstream
    start = numpy.array([u2, t2]) + 1e-9 * (u1 - u2) * stable / numpy.linalg.norm(stable)

    def backwards(_, y):
        return -rates(y)

    def arrived(_, y):
        return (u1 - y[0]) - 1e-10 * (u1 - u2)
    arrived.terminal = True
    arrived.direction = -1
    reach = 400.0 / numpy.abs(values.real).min()
    solution = scipy.integrate.solve_ivp(backwards, (0.0, reach), start, method="DOP853",
                                         rtol=1e-11, atol=1e-13, dense_output=True,
                                         events=arrived)
    if not solution.success:
        raise RuntimeError(f"navier_stokes_shock: integration failed: {solution.message}")
    s_end = float(solution.t[-1])

    def density_slope(s):                                     # d rho/dx at tau = -x = s
        u, t = solution.sol(s)
        return -m * rates((u, t))[0] / u ** 2

    grid = numpy.linspace(0.0, s_end, 20001)
    slopes = density_slope(grid)
    k = int(numpy.argmax(slopes))
    low, high = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = scipy.optimize.minimize_scalar(lambda s: -density_slope(s), bounds=(low, high),
                                          method="bounded", options={"xatol": 1e-12})
    peak = max(-float(best.fun), float(slopes[k]))
    density = m / solution.sol(grid)[0]
    middle = 0.5 * (rho1 + rho2)
    # tau = -x: density falls with tau; the midpoint crossing by root finding
    j = int(numpy.nonzero(density <= middle)[0][0])
    s_mid = scipy.optimize.brentq(lambda s: m / solution.sol(s)[0] - middle,
                                  grid[j - 1], grid[j], xtol=1e-13)
    inverse = peak / (rho2 - rho1)
    if span is None:
        span = 3.0 / inverse
    x = numpy.linspace(-span, span, points)
    tau = numpy.clip(s_mid - x, 0.0, s_end)
    u, t = solution.sol(tau)
    beyond_up, beyond_down = s_mid - x > s_end, s_mid - x < 0.0
    u = numpy.where(beyond_up, u1, numpy.where(beyond_down, u2, u))
    t = numpy.where(beyond_up, t1, numpy.where(beyond_down, t2, t))
    return {"x": x, "density": m / u, "velocity": u, "temperature": t,
            "inverse_thickness": float(inverse), "x_max_slope": float(s_mid - best.x),
            "state": state}


def inverse_thickness(mach: float) -> float:
    """lambda_1/delta of the Navier-Stokes hard-sphere shock (:func:`navier_stokes_shock`)."""
    return navier_stokes_shock(mach, points=3)["inverse_thickness"]


@functools.lru_cache(maxsize=8)
def _profile(mach: float) -> dict:
    return navier_stokes_shock(mach, points=8001, span=40.0)


def navier_stokes_maxwellian(x, v1, v2, v3, mach: float, position: float):
    r"""The local Maxwellian of the Navier-Stokes shock in the frame of the gas behind it,
    the initial data of granframe's shock run (studies/hard_sphere_shock.py):

        f = rho(s) (2 pi T(s))^{-3/2} exp(-((v_1 - u_2 + u(s))^2 + v_2^2 + v_3^2)
            / (2 T(s))),   s = position - x,

    with (rho, u, T)(s) of :func:`navier_stokes_shock` (s from the density midpoint,
    upstream at s < 0, lengths in lambda_1; beyond |s| = 40 the Rankine-Hugoniot
    states): the gas behind the shock (x < position) at rest, the gas ahead moving at
    u_2 - u_1 = -U towards it, and the shock moving at u_2 towards larger x. For
    ``initial = {name = "space_function", function =
    "granframe.theory.shock:navier_stokes_maxwellian", params = {mach = M, position = X}}``
    with x in lambda_1 (knudsen = sqrt 2)."""
    profile = _profile(float(mach))
    s = float(position) - numpy.asarray(x, dtype=float)
    density = numpy.interp(s, profile["x"], profile["density"])
    velocity = profile["state"]["u2"] - numpy.interp(s, profile["x"], profile["velocity"])
    temperature = numpy.interp(s, profile["x"], profile["temperature"])
    return (density / (2.0 * math.pi * temperature) ** 1.5
            * numpy.exp(-((v1 - velocity) ** 2 + v2 ** 2 + v3 ** 2) / (2.0 * temperature)))
