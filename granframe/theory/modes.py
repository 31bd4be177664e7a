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

With ``burnett`` the matrix also carries the linear second-order (Burnett) terms that
survive at the heat mode's threshold (where w = 0): the Burnett part of the cooling rate,
zeta^(2) = nu_0 l^2 (zeta_T* lap T/T + zeta_n* lap n/n) with l = sqrt(T)/nu_0
(:func:`cooling_rate_burnett`, ``"cooling"``; Brey, Dufty, Kim & Santos 1998 state that
these terms enter the energy balance at the order of the heat flux; the coefficients are
derived in docs/granular.md, first Sonine approximation), and the linear Burnett normal
stress of the elastic hard-sphere gas, which makes the heat mode's balance of pressure
p + P_xx^(2) instead of p (:func:`burnett_stress`, ``"stress"``).
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


def cooling_rate_burnett(restitution: float) -> dict:
    r"""The linear second-order (Burnett) part of the cooling rate of dilute 3D inelastic
    hard spheres, in the leading Sonine approximation (derived in docs/granular.md; not taken
    from a publication):

        zeta^(2) = nu_0 l^2 (zeta_T* lap T / T + zeta_n* lap n / n),   l = sqrt(T)/nu_0,

    the only linear scalars of second order (lap u is a vector; for a longitudinal mode of
    wavenumber k*, zeta^(2)/nu_0 = -k*^2 (zeta_T* theta + zeta_n* rho')). zeta depends on
    f through int int |g|^3 f f, so zeta^(2) = (3/16) zeta_M c_2, with zeta_M* =
    (5/12)(1 - e^2) the Maxwellian rate and c_2 = int v^4 f^(2) / (15 n T^2) the amplitude of
    the second Sonine polynomial S_2 in the scalar part of the second-order Chapman-Enskog
    distribution, c_2 = l^2 (xi_T lap T/T + xi_n lap n/n). Projecting the second-order
    equation (d_t^(0) + L) f^(2) = -(d_t^(1) + V.grad) f^(1) - d_t^(2) f^(0) on v^4, with
    f^(1) in its first Sonine form and d_t^(0) acting on the cooling T and on lap T
    (d_t^(0) lap T = -zeta ((3/2) lap T + (T/n) lap n)):

        (lambda* - (5/2) zeta* - (3/8) zeta_M*) xi_T = 2 kappa*,
        (lambda* - 2 zeta* - (3/8) zeta_M*) xi_n = 2 mu* + zeta* xi_T,
        zeta_T* = (3/16) zeta_M* xi_T,   zeta_n* = (3/16) zeta_M* xi_n,

    with lambda* = (1 + e)(271 - 207 e + 30 e^2 - 30 e^3)/192 the linearised collision
    operator's v^4 element on f_M S_2 (per nu_0; 2/3 when elastic), the element that with the
    Maxwellian one, -(5/4)(1 - e^2)(9 + 2 e^2) nu_0 n T^2, gives van Noije & Ernst's a_2
    (Granular Matter 1 (1998) 57) from the fourth-moment balance of the cooling state;
    zeta*, kappa*, mu* the first-Sonine ones (:func:`~granframe.theory.sonine.transport_coefficients`),
    the second-order collision integrals taken at a_2 = 0. Both coefficients vanish as
    1 - e^2 in the elastic limit (where xi_T -> 3, xi_n -> 0).

    Returns
    -------
    dict
        ``lambda*``, ``xi_T``, ``xi_n``, ``zeta_T*``, ``zeta_n*``.
    """
    e = restitution
    c = transport_coefficients(e)
    zeta, kappa, mu = c["zeta*"], c["kappa*"], c["mu*"]
    zeta_maxwell = 5 / 12 * (1 - e * e)
    relaxation = (1 + e) * (271 - 207 * e + 30 * e ** 2 - 30 * e ** 3) / 192
    xi_t = 2 * kappa / (relaxation - 2.5 * zeta - 3 / 8 * zeta_maxwell)
    xi_n = (2 * mu + zeta * xi_t) / (relaxation - 2 * zeta - 3 / 8 * zeta_maxwell)
    return {"lambda*": relaxation, "xi_T": xi_t, "xi_n": xi_n,
            "zeta_T*": 3 / 16 * zeta_maxwell * xi_t, "zeta_n*": 3 / 16 * zeta_maxwell * xi_n}


#: the linear Burnett terms :func:`longitudinal_matrix` can add (``burnett``)
BURNETT = ("cooling", "stress")

#: Burnett's stress coefficients omega_2, omega_3 of elastic rigid spheres (S. Chapman &
#: T. G. Cowling, *The Mathematical Theory of Non-uniform Gases*, 3rd ed., section 15.41;
#: Maxwell molecules: 2 and 3)
HARD_SPHERE_OMEGA = (2.028, 2.418)


def burnett_stress(restitution: float) -> dict:
    r"""The linear Burnett normal stress of a gas at rest, in the units of
    :func:`longitudinal_matrix`. Burnett's P_ij^(2) (Chapman & Cowling, section 15.3) has
    two linear terms in a gas at rest: omega_2 (mu^2/p) d_t e_ij, with d_t e_ij =
    -(1/rho) (d_i d_j p)° by the Euler equations, and omega_3 (mu^2/(rho T)) (d_i d_j T)°
    (° the traceless part: (2/3) d_x^2 along x). For a longitudinal mode, with
    mu^2 k^2/(rho p) = eta*^2 k*^2 (eta_0 = p/nu_0),

        P_xx^(2) / p = (gamma* (rho' + theta) - beta* theta) k*^2,
        gamma* = (2/3) omega_2 eta*^2,   beta* = (2/3) omega_3 eta*^2,

    eta* the first-Sonine granular viscosity ratio and omega_2, omega_3 those of elastic
    rigid spheres (:data:`HARD_SPHERE_OMEGA`): their change with e is of order 1 - e and is
    not included.

    Returns
    -------
    dict
        ``gamma*``, ``beta*``.
    """
    eta = transport_coefficients(restitution)["eta*"]
    omega_2, omega_3 = HARD_SPHERE_OMEGA
    return {"gamma*": 2 / 3 * omega_2 * eta * eta, "beta*": 2 / 3 * omega_3 * eta * eta}


def _burnett_parts(owner: str, burnett) -> tuple:
    """``burnett`` as a tuple of :data:`BURNETT` names (False: none, True: all)."""
    if burnett is False or burnett is None:
        return ()
    if burnett is True:
        return BURNETT
    parts = (burnett,) if isinstance(burnett, str) else tuple(burnett)
    if not all(part in BURNETT for part in parts):
        check.reject(owner, "burnett", burnett, "must be False, True or names from "
                     f"{', '.join(BURNETT)}")
    return parts


def longitudinal_matrix(restitution: float, k_star: float, zeta: float | None = None,
                        conduction: float = 1.0, burnett=False):
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
    Landau & Lifshitz, Fluid Mechanics, section 79). With ``burnett`` containing
    ``"cooling"`` the theta row also carries the linear Burnett part of the cooling rate
    (:func:`cooling_rate_burnett`), -zeta^(2)/nu_0 = k*^2 (zeta_n* rho' + zeta_T* theta):

        d theta/d tau = -(zeta* + ((5/2) mu* - zeta_n*) k*^2) rho' + (2/3) k* w
                        - (zeta*/2 + ((5/2) kappa* - zeta_T*) k*^2) theta,

    and with ``"stress"`` the w row the linear Burnett normal stress (:func:`burnett_stress`),
    -d_x P_xx^(2) / (rho sqrt T) in these units:

        d w/d tau = -k* ((1 + gamma* k*^2) rho' + (1 + (gamma* - beta*) k*^2) theta)
                    + (zeta*/2 - (4/3) eta* k*^2) w.

    These are the linear second-order terms that act at the heat mode's threshold, where
    w = 0 (the Burnett heat flux's linear terms are in u); the super-Burnett k*^4 heat
    conduction, of the same order in 1 - e there, is not known in closed form and is not
    included.

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
    burnett : bool, str or tuple of str
        The linear Burnett terms to add, names from :data:`BURNETT` (True: all; the cooling
        terms are the first-Sonine zeta_T*, zeta_n* whatever ``zeta`` and ``conduction``
        are). False, M is the Navier-Stokes matrix above, unchanged.

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
    matrix = numpy.array([
        [0.0, k_star, 0.0],
        [-k_star, c["zeta*"] / 2 - 4 / 3 * c["eta*"] * k_star ** 2, -k_star],
        [-(c["zeta*"] + 2.5 * c["mu*"] * k_star ** 2), 2 / 3 * k_star,
         -(c["zeta*"] / 2 + 2.5 * c["kappa*"] * k_star ** 2)]])
    parts = _burnett_parts("longitudinal_matrix", burnett)
    if "cooling" in parts:
        b = cooling_rate_burnett(restitution)
        matrix[2, 0] += b["zeta_n*"] * k_star ** 2
        matrix[2, 2] += b["zeta_T*"] * k_star ** 2
    if "stress" in parts:
        b = burnett_stress(restitution)
        matrix[1, 0] -= b["gamma*"] * k_star ** 3
        matrix[1, 2] -= (b["gamma*"] - b["beta*"]) * k_star ** 3
    return matrix


def heat_critical_wavenumber(restitution: float, burnett=False) -> float:
    r"""k*_h, where the heat mode stops growing: det M(k*) = k*^2 (zeta*/2 - (5/2)(kappa* -
    mu*) k*^2) (expanding :func:`longitudinal_matrix` along its first row) vanishes at

        k*_h = sqrt(zeta* / (5 (kappa* - mu*))),

    and a longitudinal perturbation of k* < k*_h has a growing mode (the clustering
    instability; Brey, Dufty, Kim & Santos 1998, in the units k* = k sqrt(T)/nu_0).
    Below e = 0.1878 the first-Sonine kappa* - mu* is not positive and there is no such
    threshold: refused by name.

    With ``burnett`` (names from :data:`BURNETT`, True for all, as for
    :func:`longitudinal_matrix`), det M = -k* (M_10 M_22 - M_12 M_20) =
    k*^2 (zeta*/2 - b x - a x^2) in x = k*^2, with A = (5/2) kappa* - zeta_T*,
    B = (5/2) mu* - zeta_n* (zeta_T* = zeta_n* = 0 without ``"cooling"``) and gamma*, beta*
    of :func:`burnett_stress` (0 without ``"stress"``):

        b = A - B - gamma* zeta*/2 + beta* zeta*,   a = gamma* A - (gamma* - beta*) B,
        k*_h^2 = zeta* / (b + sqrt(b^2 + 2 a zeta*)),

    the root that is zeta*/(2b) when a = 0 (the cooling terms alone:
    k*_h = sqrt(zeta*/(5 (kappa* - mu*) + 2 (zeta_n* - zeta_T*)))). Refused below
    e = 0.1878 as without them (they correct a Navier-Stokes threshold that does not exist
    there) and where that root is not real and positive."""
    owner = "heat_critical_wavenumber"
    c = transport_coefficients(restitution)
    conduction = c["kappa*"] - c["mu*"]
    if not conduction > 0.0:
        check.reject(owner, "restitution", restitution,
                     f"must be above 0.1878: kappa* - mu* = {conduction:.4g} <= 0 there in "
                     "first-Sonine theory, which then has no heat-mode threshold")
    parts = _burnett_parts(owner, burnett)
    if not parts:
        return math.sqrt(c["zeta*"] / (5.0 * conduction))
    cooling = (cooling_rate_burnett(restitution) if "cooling" in parts
               else {"zeta_T*": 0.0, "zeta_n*": 0.0})
    stress = (burnett_stress(restitution) if "stress" in parts
              else {"gamma*": 0.0, "beta*": 0.0})
    zeta, gamma, beta = c["zeta*"], stress["gamma*"], stress["beta*"]
    big_a = 2.5 * c["kappa*"] - cooling["zeta_T*"]
    big_b = 2.5 * c["mu*"] - cooling["zeta_n*"]
    b = big_a - big_b - gamma * zeta / 2 + beta * zeta
    a = gamma * big_a - (gamma - beta) * big_b
    discriminant = b * b + 2.0 * a * zeta
    denominator = b + math.sqrt(discriminant) if discriminant >= 0.0 else math.nan
    if not denominator > 0.0:
        check.reject(owner, "restitution", restitution,
                     f"has no heat-mode threshold with the Burnett terms {', '.join(parts)} "
                     f"(b = {b:.4g}, a = {a:.4g})")
    return math.sqrt(zeta / denominator)


def heat_mode_index(values, k_star: float) -> int:
    """Which of the eigenvalues ``values`` of :func:`longitudinal_matrix` at k* is the heat
    mode's: the real one with the largest real part (the other two are the sound pair,
    complex at k* > 0, and at k* = 0 the eigenvalues 0 and -zeta*/2)."""
    real = numpy.flatnonzero(numpy.abs(values.imag) <= 1e-12 * max(1.0, abs(k_star)))
    return int(real[numpy.argmax(values.real[real])])


def heat_mode(restitution: float, k_star: float, zeta: float | None = None,
              conduction: float = 1.0, burnett=False):
    r"""The heat mode of :func:`longitudinal_matrix` at k*: M v = lambda v with lambda the
    real eigenvalue with the largest real part (:func:`heat_mode_index`), per unit tau, and
    v = (rho', w, theta) scaled to rho' = 1; at k*_h (:func:`heat_critical_wavenumber`)
    lambda = 0 and v = (1, 0, -1), an isobaric mode (with the Burnett stress, p + P_xx^(2)
    is uniform instead). ``zeta``, ``conduction``, ``burnett`` as
    for :func:`longitudinal_matrix` (and :func:`heat_critical_wavenumber`).

    Returns
    -------
    tuple
        (lambda, v).
    """
    values, vectors = numpy.linalg.eig(longitudinal_matrix(restitution, k_star, zeta,
                                                           conduction, burnett))
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


#: the fields a plane mode of :func:`plane_modes_maxwellian` perturbs
PLANE_MODE_FIELDS = ("density", "temperature", "longitudinal", "transverse")


def _plane_modes(modes, lengths) -> list:
    """``modes`` checked: (field, K_x, K_y, amplitude, phase) of each, K in radians per
    unit length."""
    owner = "plane_modes_maxwellian"
    try:
        lx, ly = (float(value) for value in lengths)
    except (TypeError, ValueError):
        lx = ly = math.nan
    if not (0.0 < lx < math.inf and 0.0 < ly < math.inf):
        check.reject(owner, "lengths", lengths, "must be [L_x, L_y], two finite lengths > 0")
    if isinstance(modes, dict) or not isinstance(modes, (list, tuple)) or not modes:
        check.reject(owner, "modes", modes, "must be a list of one or more modes, each a "
                     "table {field, wave = [k_x, k_y], amplitude[, phase]}")
    checked = []
    for index, mode in enumerate(modes):
        name = f"modes[{index}]"
        if not isinstance(mode, dict) or set(mode) - {"field", "wave", "amplitude", "phase"}:
            check.reject(owner, name, mode, "must be a table {field, wave = [k_x, k_y], "
                         "amplitude[, phase]}")
        if mode.get("field") not in PLANE_MODE_FIELDS:
            check.reject(owner, f"{name}.field", mode.get("field"),
                         f"must be one of {list(PLANE_MODE_FIELDS)}")
        wave = mode.get("wave")
        if (not isinstance(wave, (list, tuple)) or len(wave) != 2
                or not all(isinstance(k, int) and not isinstance(k, bool) for k in wave)
                or wave[0] == wave[1] == 0):
            check.reject(owner, f"{name}.wave", wave, "must be [k_x, k_y], integers (periods "
                         "on L_x and L_y), not both 0")
        values = []
        for key, default in (("amplitude", None), ("phase", 0.0)):
            value = mode.get(key, default)
            if not check.is_real(value) or not math.isfinite(float(value)):
                check.reject(owner, f"{name}.{key}", value, "must be a finite real number")
            values.append(float(value))
        checked.append((mode["field"], 2 * math.pi * wave[0] / lx, 2 * math.pi * wave[1] / ly,
                        *values))
    return checked


def plane_modes_maxwellian(x, y, v1, v2, v3=None, *, lengths, modes):
    r"""The local Maxwellian of plane modes about rho = T = 1, u = 0, on a rectangle
    [0, L_x] x [0, L_y] (2D velocities, or 3D with ``v3``):

        rho = 1 + sum_density A sin(phi),   T = 1 + sum_temperature A sin(phi),
        u = sum_longitudinal A sin(phi) K/|K| + sum_transverse A sin(phi) K_perp/|K|,
        phi = K . x + phase,   K = 2 pi (k_x / L_x, k_y / L_y),   K_perp = (-K_y, K_x),
        f = rho (2 pi T)^{-d/2} exp(-|v - u|^2 / (2 T)),

    the sums over the ``modes`` of each field. One transverse mode is a shear (vortex)
    mode of the cooling state on a wave vector in any direction; transverse modes along
    x and along y together make a lattice of vortices; the heat mode of
    :func:`heat_mode`, (r, w, theta), is a density mode A r, a longitudinal mode A w of
    phase pi/2 (u = A w cos(K . x) K/|K|, as :func:`longitudinal_maxwellian`) and a
    temperature mode A theta.

    Parameters
    ----------
    x, y, v1, v2, v3 : array_like
        Positions and velocity components, broadcast against each other (the call of a
        ``space_function`` initial condition on a rectangle).
    lengths : sequence of float
        [L_x, L_y].
    modes : list of dict
        Each {``field``: one of :data:`PLANE_MODE_FIELDS`, ``wave``: [k_x, k_y] (integers:
        periods on L_x and L_y), ``amplitude``: A, ``phase``: optional, radians}.
    """
    rho, temperature = 1.0, 1.0
    u = [0.0, 0.0]
    for field, kx, ky, amplitude, phase in _plane_modes(modes, lengths):
        wave = amplitude * numpy.sin(kx * numpy.asarray(x) + ky * numpy.asarray(y) + phase)
        norm = math.hypot(kx, ky)
        if field == "density":
            rho = rho + wave
        elif field == "temperature":
            temperature = temperature + wave
        else:
            direction = (kx / norm, ky / norm) if field == "longitudinal" else (-ky / norm,
                                                                                 kx / norm)
            u = [u[0] + wave * direction[0], u[1] + wave * direction[1]]
    squared = (v1 - u[0]) ** 2 + (v2 - u[1]) ** 2 + (0.0 if v3 is None else v3 ** 2)
    d = 2 if v3 is None else 3
    return rho / (2.0 * math.pi * temperature) ** (d / 2) * numpy.exp(-squared
                                                                         / (2.0 * temperature))
