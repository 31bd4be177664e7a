r"""The Euler equations of a gas, ordinary and granular: the exact Riemann solver, the
piston problem's Rankine-Hugoniot state, a finite-volume solver of the Euler equations on
a line or a rectangle, and its granular piston problem.

In granframe's variables gamma = (d+2)/d, p = rho T with T the temperature per velocity
dimension, and E = rho u^2/2 + p/(gamma - 1) = int |v|^2/2 f dv, since 1/(gamma-1) = d/2:
the Euler equations are the hydrodynamic limit eps -> 0 of the Boltzmann equation
(docs/space.md). The granular Euler equations add the collisional cooling to the energy
(docs/granular.md, studies/granular_shock.py).
"""

from __future__ import annotations

import math

import numpy

from granframe import validators as check
from granframe.theory.cells import gauss_cell_averages
from granframe.theory.cooling import maxwellian_cooling_rate


# -- The Riemann problem of the Euler equations ---------------------------------------------


def _euler_state(owner, name, state):
    try:
        rho, u, p = (float(s) for s in state)
    except (TypeError, ValueError):
        check.reject(owner, name, state, "must be a (rho, u, p) triple of real numbers")
    if not (0.0 < rho < math.inf and math.isfinite(u) and 0.0 < p < math.inf):
        check.reject(owner, name, state, "must be (rho, u, p) with rho > 0, p > 0 finite "
                     "and u finite")
    return rho, u, p


def _gamma_argument(owner, gamma):
    if not check.is_real(gamma) or not (1.0 < float(gamma) < math.inf):
        check.reject(owner, "gamma", gamma, "must be a finite real number > 1 "
                     "((d+2)/d: 2 in 2D, 5/3 in 3D)")
    return float(gamma)


def _pressure_function(p, rho, pk, gamma):
    """Toro's f_K(p) and f_K'(p) (section 4.3): shock branch for p > p_K, rarefaction
    branch for p <= p_K."""
    a = math.sqrt(gamma * pk / rho)
    if p > pk:
        A, B = 2.0 / ((gamma + 1.0) * rho), (gamma - 1.0) / (gamma + 1.0) * pk
        root = math.sqrt(A / (p + B))
        return (p - pk) * root, root * (1.0 - 0.5 * (p - pk) / (p + B))
    ratio = p / pk
    exponent = (gamma - 1.0) / (2.0 * gamma)
    return (2.0 * a / (gamma - 1.0) * (ratio ** exponent - 1.0),
            ratio ** (-(gamma + 1.0) / (2.0 * gamma)) / (rho * a))


def euler_riemann_star(left, right, gamma: float) -> dict:
    r"""Star state and wave speeds of the Euler Riemann problem (Toro, ch. 4).

    The pressure p* in the star region is the root of

        f(p) = f_L(p) + f_R(p) + u_R - u_L = 0,
        f_K(p) = (p - p_K) sqrt(A_K / (p + B_K))                  p > p_K (shock),
        f_K(p) = 2 a_K / (gamma-1) ((p/p_K)^{(gamma-1)/(2 gamma)} - 1)   p <= p_K (fan),

    A_K = 2 / ((gamma+1) rho_K), B_K = (gamma-1)/(gamma+1) p_K, a_K = sqrt(gamma p_K/rho_K),
    found by Newton's method from the two-rarefaction guess (f is increasing and concave,
    so the iterates converge) until the relative change is below 1e-15;
    u* = (u_L + u_R)/2 + (f_R(p*) - f_L(p*))/2. Toro, Riemann Solvers and Numerical
    Methods for Fluid Dynamics, 3rd ed., 2009, sections 4.2-4.3.

    Parameters
    ----------
    left, right : tuple
        (rho, u, p) on each side; rho > 0, p > 0 (in granframe's variables p = rho T).
    gamma : float
        Ratio of specific heats, > 1 ((d+2)/d for the Boltzmann equation's Euler limit).

    Returns
    -------
    dict
        ``p``, ``u`` (p*, u*), ``rho_left``, ``rho_right`` (the densities either side of
        the contact), ``left_wave``, ``right_wave`` (``"shock"`` or ``"rarefaction"``)
        and ``speeds``: the sorted speeds of every discontinuity and fan edge (a shock
        speed, or the head and tail of a fan, on each side, and the contact u*).

    Raises
    ------
    ValueError
        For data that generate vacuum, 2 (a_L + a_R)/(gamma - 1) <= u_R - u_L.
    """
    return _riemann_star("euler_riemann_star", left, right, gamma)


def _riemann_star(owner, left, right, gamma):
    """:func:`euler_riemann_star`, its errors naming ``owner``."""
    gamma = _gamma_argument(owner, gamma)
    rl, ul, pl = _euler_state(owner, "left", left)
    rr, ur, pr = _euler_state(owner, "right", right)
    al, ar = math.sqrt(gamma * pl / rl), math.sqrt(gamma * pr / rr)
    if 2.0 * (al + ar) / (gamma - 1.0) <= ur - ul:
        check.reject(owner, "left, right", (tuple(left), tuple(right)),
                     f"must not generate vacuum: 2 (a_L + a_R)/(gamma - 1) = "
                     f"{2.0 * (al + ar) / (gamma - 1.0):.6g} <= u_R - u_L = {ur - ul:.6g}; "
                     "the exact solver needs states without vacuum")
    z = (gamma - 1.0) / (2.0 * gamma)
    p = ((al + ar - 0.5 * (gamma - 1.0) * (ur - ul))
         / (al / pl ** z + ar / pr ** z)) ** (1.0 / z)          # two-rarefaction guess
    for _ in range(100):
        fl, dl = _pressure_function(p, rl, pl, gamma)
        fr, dr = _pressure_function(p, rr, pr, gamma)
        step = (fl + fr + ur - ul) / (dl + dr)
        new = max(p - step, 1e-3 * p)
        if abs(new - p) <= 1e-15 * new:
            p = new
            break
        p = new
    fl, _ = _pressure_function(p, rl, pl, gamma)
    fr, _ = _pressure_function(p, rr, pr, gamma)
    u = 0.5 * (ul + ur) + 0.5 * (fr - fl)
    g6 = (gamma - 1.0) / (gamma + 1.0)
    speeds = []
    if p > pl:
        rho_left = rl * (p / pl + g6) / (g6 * p / pl + 1.0)
        speeds.append(ul - al * math.sqrt((gamma + 1.0) / (2 * gamma) * p / pl + z))
    else:
        rho_left = rl * (p / pl) ** (1.0 / gamma)
        speeds += [ul - al, u - al * (p / pl) ** z]
    speeds.append(u)
    if p > pr:
        rho_right = rr * (p / pr + g6) / (g6 * p / pr + 1.0)
        speeds.append(ur + ar * math.sqrt((gamma + 1.0) / (2 * gamma) * p / pr + z))
    else:
        rho_right = rr * (p / pr) ** (1.0 / gamma)
        speeds += [u + ar * (p / pr) ** z, ur + ar]
    return {"p": p, "u": u, "rho_left": rho_left, "rho_right": rho_right,
            "left_wave": "shock" if p > pl else "rarefaction",
            "right_wave": "shock" if p > pr else "rarefaction", "speeds": speeds}


def euler_riemann(left, right, gamma: float, x, t: float, x0: float = 0.5) -> dict:
    r"""Exact solution of the Riemann problem of the 1D compressible Euler equations.

    d_t (rho, rho u, E) + d_x (rho u, rho u^2 + p, u (E + p)) = 0 with
    E = rho u^2/2 + p/(gamma - 1), from (rho, u, p) = ``left`` for x < x0 and ``right``
    for x > x0. The solution is self-similar in S = (x - x0)/t and sampled as in Toro,
    section 4.5 (the star state from :func:`euler_riemann_star`); inside a left fan

        a = 2/(gamma+1) (a_L + (gamma-1)/2 (u_L - S)),
        u = 2/(gamma+1) (a_L + (gamma-1)/2 u_L + S),
        rho = rho_L (a/a_L)^{2/(gamma-1)},   p = p_L (a/a_L)^{2 gamma/(gamma-1)},

    and symmetrically on the right. In granframe's variables gamma = (d+2)/d, p = rho T with
    T the temperature per velocity dimension, and E = int |v|^2/2 f dv, since
    1/(gamma-1) = d/2. Toro, Riemann Solvers and Numerical Methods for Fluid Dynamics,
    3rd ed., 2009, ch. 4.

    Parameters
    ----------
    left, right : tuple
        (rho, u, p) with rho > 0, p > 0.
    gamma : float
        > 1.
    x : array_like
        Positions (any shape).
    t : float
        Time >= 0 (t = 0: the initial data, the left state for x < x0).
    x0 : float
        Position of the initial discontinuity.

    Returns
    -------
    dict
        ``rho``, ``u``, ``p``, ``T`` (= p / rho), arrays of the shape of x.
    """
    owner = "euler_riemann"
    gamma = _gamma_argument(owner, gamma)
    t = check.time_point(owner, t)
    rl, ul, pl = _euler_state(owner, "left", left)
    rr, ur, pr = _euler_state(owner, "right", right)
    star = _riemann_star(owner, left, right, gamma)
    x = numpy.asarray(x, dtype=float)
    if t == 0.0:
        is_left = x < x0
        rho, u, p = (numpy.where(is_left, a, b) for a, b in ((rl, rr), (ul, ur), (pl, pr)))
        return {"rho": rho, "u": u, "p": p, "T": p / rho}
    s = (x - x0) / t
    with numpy.errstate(invalid="ignore"):
        rho_l, u_l, p_l = _left_of_contact(s, (rl, ul, pl), star, gamma)
        rho_r, u_r, p_r = _right_of_contact(s, (rr, ur, pr), star, gamma)
    is_left = s < star["u"]
    rho = numpy.where(is_left, rho_l, rho_r)
    u = numpy.where(is_left, u_l, u_r)
    p = numpy.where(is_left, p_l, p_r)
    return {"rho": rho, "u": u, "p": p, "T": p / rho}


def _left_of_contact(s, left, star, gamma):
    """rho, u, p of :func:`euler_riemann` at S = (x - x0)/t as if left of the contact: the
    left state, the left fan (if the left wave is one) or the star state."""
    rl, ul, pl = left
    g4, g5, g7 = 2.0 / (gamma - 1.0), 2.0 / (gamma + 1.0), 0.5 * (gamma - 1.0)
    g3 = 2.0 * gamma / (gamma - 1.0)
    al = math.sqrt(gamma * pl / rl)
    speeds = star["speeds"]
    if star["left_wave"] == "shock":
        outside_l, fan_l = s < speeds[0], numpy.zeros(s.shape, dtype=bool)
    else:
        outside_l, fan_l = s < speeds[0], (s >= speeds[0]) & (s < speeds[1])
    cl = numpy.clip(g5 * (al + g7 * (ul - s)), 0.0, None) / al
    rho_l = numpy.where(outside_l, rl, numpy.where(fan_l, rl * cl ** g4, star["rho_left"]))
    u_l = numpy.where(outside_l, ul, numpy.where(fan_l, g5 * (al + g7 * ul + s), star["u"]))
    p_l = numpy.where(outside_l, pl, numpy.where(fan_l, pl * cl ** g3, star["p"]))
    return rho_l, u_l, p_l


def _right_of_contact(s, right, star, gamma):
    """rho, u, p of :func:`euler_riemann` at S = (x - x0)/t as if right of the contact: the
    mirror image (x -> -x, u -> -u) of :func:`_left_of_contact` for the mirrored problem,
    whose left state is the right one with u reversed."""
    rr, ur, pr = right
    mirror = {"rho_left": star["rho_right"], "u": -star["u"], "p": star["p"],
              "left_wave": star["right_wave"],
              "speeds": [-speed for speed in reversed(star["speeds"])]}
    rho_r, u_r, p_r = _left_of_contact(-s, (rr, -ur, pr), mirror, gamma)
    return rho_r, -u_r, p_r


def euler_riemann_cell_averages(left, right, gamma: float, edges, t: float, x0: float = 0.5,
                                points: int = 8) -> dict:
    r"""Cell averages of the exact Euler Riemann solution (:func:`euler_riemann`).

    Each cell [e_i, e_{i+1}] is split at the positions x0 + s t of the shocks, the contact
    and the fan edges (the ``speeds`` of :func:`euler_riemann_star`), and every piece gets
    the ``points``-point Gauss-Legendre rule. Between the breaks the solution is constant
    or a fan, where rho, rho u and E are powers of a linear function of x: polynomials of
    degree <= 2 + 2 gamma/(gamma-1) (7 for gamma = 2, 9 for 5/3, 13 for 1.4), integrated
    exactly by 7 or more points. For other gamma the fan is smooth: on the Sod data with
    gamma = 1.3 at t = 0.2, the default 8 points and 60 points agree to 3e-15 on 10 and on
    100 cells of [0, 1].

    Returns
    -------
    dict
        The averages of the conserved variables ``rho``, ``momentum`` (rho u) and
        ``energy`` (E = rho u^2/2 + p/(gamma-1)), and from them, as a finite-volume scheme
        computes them, ``u`` = momentum/rho, ``p`` = (gamma-1)(E - momentum^2/(2 rho)),
        ``T`` = p/rho; arrays of length ``len(edges) - 1``.
    """
    owner = "euler_riemann_cell_averages"
    edges = check.cell_edges(owner, edges)
    points = check.rule_points(owner, points)
    gamma = _gamma_argument(owner, gamma)
    t = check.time_point(owner, t)
    star = _riemann_star(owner, left, right, gamma)

    def conserved(x):
        w = euler_riemann(left, right, gamma, x, t, x0)
        momentum = w["rho"] * w["u"]
        return numpy.stack([w["rho"], momentum,
                            0.5 * momentum * w["u"] + w["p"] / (gamma - 1.0)], axis=-1)

    breaks = x0 + t * numpy.asarray(star["speeds"]) if t > 0 else numpy.array([x0])
    rho, momentum, energy = gauss_cell_averages(edges, conserved, breaks, points).T
    u = momentum / rho
    p = (gamma - 1.0) * (energy - 0.5 * momentum * u)
    return {"rho": rho, "momentum": momentum, "energy": energy, "u": u, "p": p, "T": p / rho}


# -- The piston problem: Rankine-Hugoniot ----------------------------------------------------


def rankine_hugoniot(speed: float, gamma: float, density: float = 1.0,
                     temperature: float = 1.0) -> dict:
    r"""The state behind the shock of the piston problem: gas (rho_1, T_1) moving at -U
    into a wall at rest.

    The reflected problem is the Riemann problem (rho_1, +U, p_1) | (rho_1, -U, p_1),
    whose star state (:func:`euler_riemann_star`; Toro, Riemann Solvers and Numerical
    Methods for Fluid Dynamics, 3rd ed., 2009, ch. 4) is the gas at rest behind the shock:
    rho_2, p_2, T_2 = p_2 / rho_2. Mass conservation across the shock gives its speed in
    the wall's frame,

        s = rho_1 U / (rho_2 - rho_1),

    and its Mach number against the incoming gas, M = (s + U) / c_1, c_1 = sqrt(gamma T_1).
    The result satisfies the Rankine-Hugoniot relations of Landau & Lifshitz, Fluid
    Mechanics, section 89: rho_2/rho_1 = (gamma+1) M^2 / ((gamma-1) M^2 + 2),
    p_2/p_1 = 1 + 2 gamma (M^2 - 1)/(gamma + 1).

    Parameters
    ----------
    speed : float
        U > 0, the speed of the gas towards the wall.
    gamma : float
        The ratio of specific heats, (d+2)/d.
    density, temperature : float
        rho_1 and T_1 of the incoming gas.

    Returns
    -------
    dict
        ``rho_2``, ``T_2``, ``p_2``, ``shock_speed`` (s, in the wall's frame) and ``mach``.
    """
    pressure = density * temperature
    star = euler_riemann_star((density, speed, pressure), (density, -speed, pressure), gamma)
    rho2 = star["rho_left"]
    shock = density * speed / (rho2 - density)
    return {"rho_2": rho2, "T_2": star["p"] / rho2, "p_2": star["p"], "shock_speed": shock,
            "mach": (shock + speed) / math.sqrt(gamma * temperature)}


def piston_speed(mach: float, gamma: float, temperature: float = 1.0) -> float:
    r"""The speed U of the gas against a wall that drives a shock of Mach number M:

        U = 2 c_1 (M - 1/M) / (gamma + 1),   c_1 = sqrt(gamma T_1)

    (Landau & Lifshitz, Fluid Mechanics, section 89: the velocity jump across a shock of
    Mach number M; :func:`rankine_hugoniot` inverts it)."""
    return 2.0 * math.sqrt(gamma * temperature) * (mach - 1.0 / mach) / (gamma + 1.0)


# -- The granular Euler equations --------------------------------------------------------------


def _primitive(q, dimension):
    """rho, the velocity components (one row per momentum row of q) and T of conserved
    q = (rho, rho u_1, ..., E) with E = rho |u|^2/2 + d rho T/2."""
    rho = q[0]
    u = q[1:-1] / rho
    temperature = (q[-1] - 0.5 * rho * (u * u).sum(axis=0)) / (0.5 * dimension * rho)
    return rho, u, temperature


def _conserved(rho, u, temperature, dimension):
    return numpy.concatenate([rho[None], rho * u, (0.5 * rho * (u * u).sum(axis=0)
                                                   + 0.5 * dimension * rho * temperature)[None]])


def _minmod(a, b):
    return numpy.where(a * b > 0.0, numpy.sign(a) * numpy.minimum(abs(a), abs(b)), 0.0)


def _hll(left, right, normal, dimension):
    """HLL flux (Harten, Lax & van Leer 1983) with Davis's wave speeds through faces of
    normal e_normal, from primitive (rho, u, T) states either side of each face."""
    gamma = (dimension + 2) / dimension
    fluxes, states, speeds = [], [], []
    for rho, u, temperature in (left, right):
        state = _conserved(rho, u, temperature, dimension)
        un, p = u[normal], rho * temperature
        flux = state * un
        flux[1 + normal] += p
        flux[-1] += p * un
        states.append(state)
        fluxes.append(flux)
        speeds.append((un, numpy.sqrt(gamma * temperature)))
    (ul, cl), (ur, cr) = speeds
    slow = numpy.minimum(ul - cl, ur - cr)
    fast = numpy.maximum(ul + cl, ur + cr)
    lo, hi = numpy.minimum(slow, 0.0), numpy.maximum(fast, 0.0)
    return (hi * fluxes[0] - lo * fluxes[1] + hi * lo * (states[1] - states[0])) / (hi - lo)


def _ghosts(prim, axis, sides):
    """prim (rows rho, u_1..u_k, T; then the space axes) with two ghost cells at each end
    of space axis ``axis``: 'periodic', 'reflecting' (the mirror images of the first two
    cells in mirror order, the normal velocity reversed) or 'transmissive' (the end cell
    repeated)."""
    ax = axis + 1
    n = prim.shape[ax]
    #: the cells each kind copies into the ghosts, in array order: (before the first
    #: cell, after the last)
    taken = {"periodic": ([n - 2, n - 1], [0, 1]), "transmissive": ([0, 0], [n - 1, n - 1]),
             "reflecting": ([1, 0], [n - 1, n - 2])}
    ends = []
    for end, side in enumerate(sides):
        block = numpy.take(prim, taken[side][end], axis=ax)
        if side == "reflecting":
            block[1 + axis] *= -1.0
        ends.append(block)
    return numpy.concatenate([ends[0], prim, ends[1]], axis=ax)


def _axis_rate(prim, axis, dx, sides, dimension):
    """-d_axis of the Euler fluxes: MUSCL with the minmod limiter on (rho, u, T), the HLL
    flux at every face of that axis, two ghost cells at each end (:func:`_ghosts`)."""
    ax = axis + 1

    def part(array, start, stop):       # a view of array[start:stop] along the axis
        return array[(slice(None),) * ax + (slice(start, stop),)]

    padded = _ghosts(prim, axis, sides)
    slope = _minmod(part(padded, 1, -1) - part(padded, 0, -2),
                    part(padded, 2, None) - part(padded, 1, -1))
    centre = part(padded, 1, -1)
    left = part(centre + 0.5 * slope, None, -1)
    right = part(centre - 0.5 * slope, 1, None)
    flux = _hll((left[0], left[1:-1], left[-1]), (right[0], right[1:-1], right[-1]), axis,
                dimension)
    return -(part(flux, 1, None) - part(flux, None, -1)) / dx


def _euler_rate(q, spacings, boundaries, dimension):
    """-div of the Euler fluxes of q, the axes' parts added (unsplit, one stage)."""
    rho, u, temperature = _primitive(q, dimension)
    prim = numpy.concatenate([rho[None], u, temperature[None]])
    return sum(_axis_rate(prim, axis, dx, sides, dimension)
               for axis, (dx, sides) in enumerate(zip(spacings, boundaries)))


def _cool(q, dt, c, dimension):
    """The cooling over dt by its exact solution at fixed rho: T <- T exp(-c rho dt)."""
    rho, u, temperature = _primitive(q, dimension)
    return _conserved(rho, u, temperature * numpy.exp(-c * rho * dt), dimension)


def _integrate(q, times, spacings, sides, dimension, cfl, cooling=None) -> dict:
    """q advanced by SSP RK2 steps cfl / max(sum_a (|u_a| + sqrt(gamma T)) / dx_a), the last
    before each of ``times`` (sorted) shortened to land on it, with the cooling
    T <- T exp(-c rho dt) of rate c = ``cooling`` Strang-split around each step where
    given; the fields at each time and the number of steps."""
    gamma = (dimension + 2) / dimension
    out = {"time": [], "density": [], "velocity": [], "temperature": []}
    t, steps = 0.0, 0
    for target in times:
        while t < target - 1e-14 * max(1.0, target):
            rho, u, temperature = _primitive(q, dimension)
            sound = numpy.sqrt(gamma * temperature)
            rate = sum((abs(u[a]) + sound) / dx for a, dx in enumerate(spacings))
            dt = min(cfl / float(numpy.max(rate)), target - t)
            if cooling is not None:
                q = _cool(q, 0.5 * dt, cooling, dimension)
            stage = q + dt * _euler_rate(q, spacings, sides, dimension)
            q = 0.5 * (q + stage + dt * _euler_rate(stage, spacings, sides, dimension))
            if cooling is not None:
                q = _cool(q, 0.5 * dt, cooling, dimension)
            t += dt
            steps += 1
        rho, u, temperature = _primitive(q, dimension)
        for name, value in (("time", t), ("density", rho), ("velocity", u),
                            ("temperature", temperature)):
            out[name].append(value)
    return {**{k: numpy.asarray(v) for k, v in out.items()}, "steps": steps}


def granular_euler_piston(speed: float, restitution: float, knudsen: float, length: float,
                          times, cells: int = 4000, cfl: float = 0.4,
                          dimension: int = 2) -> dict:
    r"""The granular Euler equations of Maxwell molecules for the piston problem, by finite
    volumes.

    The gas (rho = 1, T = 1, u = -U) fills [0, ell] between two reflecting walls; it solves

        d_t rho + d_x (rho u) = 0,   d_t (rho u) + d_x (rho u^2 + p) = 0,
        d_t E + d_x (u (E + p)) = -(1 - e^2) d rho^2 T / (8 eps),   p = rho T,
        E = rho u^2/2 + d rho T/2,

    the limit eps -> 0 at fixed (1 - e^2)/eps of the Boltzmann equation with the Maxwell
    kernel B = 1/|S^{d-1}|, whose energy sink is exact in rho and T for any f
    (:func:`~granframe.theory.cooling.maxwellian_cooling_rate`: dT/dt = -c rho T,
    c = (1 - e^2)/(4 eps)). The scheme (that of :func:`euler_finite_volumes` on one axis,
    with the cooling): MUSCL with the minmod limiter on (rho, u, T)
    (van Leer, J. Comput. Phys. 32 (1979) 101; Toro, Riemann Solvers and Numerical Methods
    for Fluid Dynamics, 3rd ed., 2009, ch. 13-14), the HLL flux with Davis's wave speeds
    S_L = min(u_L - c_L, u_R - c_R), S_R = max(u_L + c_L, u_R + c_R) (Harten, Lax & van
    Leer, SIAM Rev. 25 (1983) 35; Toro ch. 10), SSP RK2 (Shu & Osher, J. Comput. Phys. 77
    (1988) 439), mirrored ghost cells at both walls, and the cooling each step by its exact
    solution at fixed rho, T <- T exp(-c rho dt), Strang-split around the transport; the
    step is ``cfl`` dx / max(|u| + sqrt(gamma T)), shortened to land on each of ``times``.

    Parameters
    ----------
    speed : float
        U, the gas's speed towards the wall at x = 0.
    restitution, knudsen : float
        e and eps.
    length : float
        ell.
    times : sequence of float
        The times at which the fields are returned (sorted).
    cells : int
        Finite-volume cells on [0, ell].
    cfl : float
        Courant number of the time step.
    dimension : int
        d of the velocities: gamma = (d + 2)/d.

    Returns
    -------
    dict
        ``x`` (cell centres) and, one row per time, ``time``, ``density``, ``velocity``,
        ``temperature``.
    """
    dx = length / cells
    q = _conserved(numpy.ones(cells), numpy.full((1, cells), -speed), numpy.ones(cells),
                   dimension)
    run = _integrate(q, sorted(times), (dx,), (("reflecting", "reflecting"),), dimension, cfl,
                     cooling=maxwellian_cooling_rate(restitution) / knudsen)
    return {"x": (numpy.arange(cells) + 0.5) * dx, "time": run["time"],
            "density": run["density"], "velocity": run["velocity"][:, 0],
            "temperature": run["temperature"]}


# -- The Euler equations on a rectangle ------------------------------------------------------

#: the ends of a space axis that :func:`euler_finite_volumes` knows
ENDS = ("periodic", "reflecting", "transmissive")


def _euler_fields(owner, density, velocity, temperature):
    try:
        rho = numpy.asarray(density, dtype=float)
        u = numpy.asarray(velocity, dtype=float)
        temperature = numpy.asarray(temperature, dtype=float)
    except (TypeError, ValueError):
        check.reject(owner, "density", density, "density, velocity and temperature must be "
                     "arrays of real numbers")
    if rho.ndim < 1 or min(rho.shape) < 3:
        check.reject(owner, "density", f"an array of shape {rho.shape}",
                     "must have one axis per space axis, each of at least 3 cells")
    if u.shape != (rho.ndim,) + rho.shape:
        check.reject(owner, "velocity", f"an array of shape {u.shape}",
                     f"must have shape {(rho.ndim,) + rho.shape}: one component per space axis "
                     "on the cells of density")
    if temperature.shape != rho.shape:
        check.reject(owner, "temperature", f"an array of shape {temperature.shape}",
                     f"must have the shape of density, {rho.shape}")
    for name, value in (("density", rho), ("temperature", temperature)):
        if not numpy.all(numpy.isfinite(value) & (value > 0.0)):
            check.reject(owner, name, f"an array with minimum {numpy.min(value)!r}",
                         "must be finite and > 0 in every cell")
    if not numpy.all(numpy.isfinite(u)):
        check.reject(owner, "velocity", "an array with a non-finite value", "must be finite")
    return rho, u, temperature


def _euler_boundaries(owner, boundaries, axes):
    try:
        sides = tuple(tuple(str(end) for end in pair) for pair in boundaries)
    except TypeError:
        sides = ()
    if len(sides) != axes or any(len(pair) != 2 for pair in sides):
        check.reject(owner, "boundaries", boundaries,
                     f"must give ({', '.join(ENDS)}) pairs, (low end, high end), one per space "
                     f"axis ({axes})")
    for pair in sides:
        if any(end not in ENDS for end in pair) or (("periodic" in pair)
                                                    and pair != ("periodic", "periodic")):
            check.reject(owner, "boundaries", boundaries,
                         f"each end must be one of {', '.join(ENDS)}, and periodic at both "
                         "ends of an axis or at neither")
    return sides


def euler_finite_volumes(density, velocity, temperature, spacing, times, *,
                         boundaries=None, dimension: int = 2, cfl: float = 0.4) -> dict:
    r"""The Euler equations on a line or a rectangle of cells, by finite volumes: an
    independent reference for the hydrodynamic limit of granframe's kinetic runs.

    It solves, for the conserved q = (rho, rho u, E) on cells of sizes dx_a,

        d_t q + sum_a d_{x_a} F_a(q) = 0,   F_a = (rho u_a, rho u_a u + p e_a, u_a (E + p)),
        p = rho T,   E = rho |u|^2/2 + d rho T/2,   gamma = (d + 2)/d,

    with d the velocity dimension (granframe's variables: T per velocity dimension), the
    velocity having one component per space axis (a third velocity dimension enters only
    gamma and E: at rest across the plane, it stays so). The scheme is the unsplit one of
    the granular piston solver (:func:`granular_euler_piston`, its one-axis case): MUSCL
    with the minmod limiter on (rho, u, T) along each axis, the HLL flux with Davis's wave
    speeds at every face, the axes' flux differences added in each stage of SSP RK2 (van
    Leer 1979; Harten, Lax & van Leer 1983; Shu & Osher 1988; Toro, *Riemann Solvers and
    Numerical Methods for Fluid Dynamics*, 3rd ed., 2009, ch. 10, 13-14, 16), the step
    ``cfl`` / max(sum_a (|u_a| + sqrt(gamma T)) / dx_a), shortened to land on each of
    ``times``. Two ghost cells at each end: periodic, reflecting (mirror images, the normal
    velocity reversed: no mass or energy through) or transmissive (the end cell repeated:
    waves leave, to the scheme's accuracy).

    Parameters
    ----------
    density, temperature : array_like
        rho and T on the cells, shape (C_1[, C_2, ...]), each > 0.
    velocity : array_like
        u, shape (axes, C_1[, C_2, ...]).
    spacing : sequence of float
        dx_a, one per space axis.
    times : sequence of float
        The times at which the fields are returned (>= 0; sorted here).
    boundaries : sequence of (str, str), optional
        The (low, high) ends of each axis, from ``ENDS``; all transmissive by default.
    dimension : int
        d of the velocities (2 or 3): gamma = (d + 2)/d, 2 or 5/3.
    cfl : float
        Courant number, in (0, 0.5] (the positivity of MUSCL-HLL with SSP RK2 on two axes).

    Returns
    -------
    dict
        ``time`` (T,), ``density`` and ``temperature`` (T, C_1, ...), ``velocity``
        (T, axes, C_1, ...), and ``steps``, the number of steps taken.
    """
    owner = "euler_finite_volumes"
    rho, u, temperature = _euler_fields(owner, density, velocity, temperature)
    axes = rho.ndim
    try:
        spacings = tuple(float(dx) for dx in spacing)
    except (TypeError, ValueError):
        spacings = ()
    if len(spacings) != axes or not all(0.0 < dx < math.inf for dx in spacings):
        check.reject(owner, "spacing", spacing, f"must give {axes} finite cell sizes > 0, one "
                     "per space axis")
    sides = _euler_boundaries(owner, (("transmissive",) * 2,) * axes if boundaries is None
                              else boundaries, axes)
    if dimension not in (2, 3) or isinstance(dimension, bool):
        check.reject(owner, "dimension", dimension, "must be 2 or 3 (the velocity dimension)")
    if dimension < axes:
        check.reject(owner, "dimension", dimension, f"must be at least the number of space "
                     f"axes ({axes})")
    if not check.is_real(cfl) or not 0.0 < float(cfl) <= 0.5:
        check.reject(owner, "cfl", cfl, "must be a real number in (0, 0.5]")
    try:
        targets = sorted(float(t) for t in times)
    except (TypeError, ValueError):
        targets = [math.nan]
    if not targets or not all(0.0 <= t < math.inf for t in targets):
        check.reject(owner, "times", times, "must be one or more finite times >= 0")
    return _integrate(_conserved(rho, u, temperature, dimension), targets, spacings, sides,
                      dimension, float(cfl))


#: Liska & Wendroff's configuration 4 (SIAM J. Sci. Comput. 25 (2003) 995, Lax & Liu's
#: configuration 4: four shocks) on [0, 1]^2 about (1/2, 1/2): (rho, u_1, u_2, p) by quadrant
LISKA_WENDROFF_4 = {"upper_right": (1.1, 0.0, 0.0, 1.1),
                    "upper_left": (0.5065, 0.8939, 0.0, 0.35),
                    "lower_left": (1.1, 0.8939, 0.8939, 1.1),
                    "lower_right": (0.5065, 0.0, 0.8939, 0.35)}


def euler_quadrants(states, cells: int, time: float, *, dimension: int = 2,
                    boundaries=(("reflecting",) * 2,) * 2) -> dict:
    """A two-dimensional Riemann problem of the Euler equations on [0, 1]^2 at ``time``,
    solved by :func:`euler_finite_volumes` on ``cells`` x ``cells`` cells.

    Parameters
    ----------
    states : dict
        (rho, u_1, u_2, p) of each quadrant about (1/2, 1/2), keyed ``upper_right``,
        ``upper_left``, ``lower_left``, ``lower_right`` (as :data:`LISKA_WENDROFF_4`).
    cells : int
        Cells per axis, even (the quadrants meet at a face).
    time : float
        The time of the returned fields, >= 0.
    dimension : int
        d of the velocities: gamma = (d + 2)/d, and T = p / rho per velocity dimension.
    boundaries : sequence of (str, str)
        The ends of each axis, as in :func:`euler_finite_volumes` (reflecting walls by
        default).

    Returns
    -------
    dict
        ``rho``, ``u1``, ``u2``, ``T``, each (cells, cells) indexed (x, y).
    """
    owner = "euler_quadrants"
    if isinstance(cells, bool) or not isinstance(cells, int) or cells < 2 or cells % 2:
        check.reject(owner, "cells", cells, "must be an even integer >= 2")
    blocks = {"upper_right": (slice(cells // 2, None), slice(cells // 2, None)),
              "upper_left": (slice(None, cells // 2), slice(cells // 2, None)),
              "lower_left": (slice(None, cells // 2), slice(None, cells // 2)),
              "lower_right": (slice(cells // 2, None), slice(None, cells // 2))}
    if not isinstance(states, dict) or set(states) != set(blocks):
        check.reject(owner, "states", states, f"must map each of {sorted(blocks)} to "
                     "(rho, u_1, u_2, p)")
    rho = numpy.empty((cells, cells))
    u = numpy.empty((2, cells, cells))
    temperature = numpy.empty((cells, cells))
    for name, where in blocks.items():
        r, u1, u2, p = (float(value) for value in states[name])
        rho[where], u[0][where], u[1][where], temperature[where] = r, u1, u2, p / r
    solution = euler_finite_volumes(rho, u, temperature, (1.0 / cells, 1.0 / cells), [time],
                                    boundaries=boundaries, dimension=dimension)
    return {"rho": solution["density"][-1], "u1": solution["velocity"][-1][0],
            "u2": solution["velocity"][-1][1], "T": solution["temperature"][-1]}


def shock_states(mach: float, gamma: float, density: float = 1.0,
                 temperature: float = 1.0) -> dict:
    r"""The state behind a shock of Mach number M moving into gas (rho_1, T_1) at rest
    (Landau & Lifshitz, Fluid Mechanics, section 89):

        rho_2/rho_1 = (gamma+1) M^2 / ((gamma-1) M^2 + 2),
        p_2/p_1 = 1 + 2 gamma (M^2 - 1)/(gamma + 1),

    the gas behind moving at U = 2 c_1 (M - 1/M)/(gamma + 1) (:func:`piston_speed`) along
    the shock's motion, which is at the speed s = M c_1, c_1 = sqrt(gamma T_1).

    Returns
    -------
    dict
        ``rho_2``, ``T_2``, ``velocity`` (U) and ``shock_speed`` (s).
    """
    owner = "shock_states"
    if not check.is_real(mach) or not 1.0 <= float(mach) < math.inf:
        check.reject(owner, "mach", mach, "must be a finite real number >= 1")
    _gamma_argument(owner, gamma)
    m2 = float(mach) ** 2
    rho2 = density * (gamma + 1.0) * m2 / ((gamma - 1.0) * m2 + 2.0)
    p2 = density * temperature * (1.0 + 2.0 * gamma * (m2 - 1.0) / (gamma + 1.0))
    return {"rho_2": rho2, "T_2": p2 / rho2,
            "velocity": piston_speed(float(mach), gamma, temperature),
            "shock_speed": float(mach) * math.sqrt(gamma * temperature)}


def plane_states_maxwellian(x, y, v1, v2, v3=None, *, normal, offset, low, high):
    r"""Two Maxwellians on either side of the line n . x = ``offset`` of a rectangle (2D
    velocities, or 3D with ``v3``, the third component at rest):

        f = rho (2 pi T)^{-d/2} exp(-|v - u|^2 / (2 T)),
        (rho, u_1, u_2, T) = ``low`` where n . x < offset, ``high`` where n . x >= offset,

    n = ``normal`` / |``normal``|: the data of a plane shock or contact at any angle (a
    ``space_function`` initial condition on a rectangle, its cells averaged by the tensor
    Gauss-Legendre rule).
    """
    owner = "plane_states_maxwellian"
    try:
        n = numpy.array([float(a) for a in normal])
    except (TypeError, ValueError):
        n = numpy.array([math.nan])
    if n.shape != (2,) or not numpy.isfinite(n).all() or not numpy.hypot(*n) > 0:
        check.reject(owner, "normal", normal, "must be [n_x, n_y], finite and not zero")
    n = n / numpy.hypot(*n)
    states = []
    for name, state in (("low", low), ("high", high)):
        try:
            values = [float(a) for a in state]
        except (TypeError, ValueError):
            values = []
        if len(values) != 4 or not all(math.isfinite(a) for a in values) \
                or values[0] <= 0 or values[3] <= 0:
            check.reject(owner, name, state, "must be [rho, u_1, u_2, T], finite, rho > 0 "
                         "and T > 0")
        states.append(values)
    side = n[0] * numpy.asarray(x) + n[1] * numpy.asarray(y) >= float(offset)
    rho, u1, u2, t = (numpy.where(side, b, a) for a, b in zip(*states))
    squared = (v1 - u1) ** 2 + (v2 - u2) ** 2 + (0.0 if v3 is None else v3 ** 2)
    d = 2 if v3 is None else 3
    return rho / (2.0 * math.pi * t) ** (d / 2) * numpy.exp(-squared / (2.0 * t))
