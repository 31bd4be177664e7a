"""Free cooling: concentration on a fixed grid, the rescaled formulation, the cooling state.

    python studies/free_cooling.py --out docs/figures/cooling   # 18 min 40 s on 2 cores

(``--only hcs`` or ``--only maxwell`` measures one part again; the 3D cooling states take
most of the time.) Without a heat bath the gas cools for ever (Haff's law T ~ t^-2 for hard
spheres) and f concentrates at its mean velocity. Three parts (``--only``):

- ``concentration``: 2D hard spheres, e = 0.5, T0 = 1, S = 4, N = 32 and 64 (h = 0.55, 0.28),
  RK4. The unscaled equation (dt = 0.05) is run to t = 100 next to the rescaled one
  (:mod:`granframe.equations.rescaled`, ds = 0.1) to the same t. Reference: the rescaled N = 64 run,
  checked against the unscaled N = 64 run while both are resolved. Reported: when the unscaled
  temperature leaves the reference by 1e-3 and when its negative-mass share passes the
  runner's 1 % limit, with T/T0 and the thermal speed sqrt(T) in grid spacings there.
- ``hcs``: the homogeneous cooling state of hard spheres for e = 0.2 ... 0.9, rescaled, RK4
  ds = 0.1, at two resolutions (:data:`HCS_RESOLUTIONS`): the main one from a Maxwellian to
  s = 10 (3D: N = 32, S = 4.5, N_rho = 30, Lebedev 17; 2D: N = 64, S = 4.5, N_rho = 32, M = 32)
  and a refined one from the Maxwellian to s = 6 (3D: N = 40, S = 5.5, N_rho = 36, Lebedev 23,
  at e = 0.2, 0.5, 0.9; 2D: N = 80, S = 5.5, N_rho = 40, M = 64), compared at s = 6. Its
  kurtosis and Sonine coefficient a2 against the first Sonine approximation of van Noije &
  Ernst (Granular Matter 1, 1998) for 3D hard spheres,
  a2 = 16 (1-e)(1-2e^2) / (9 + 24d - e(41 - 8d) + 30 e^2 (1-e)),
  and the second one (F truncated after S_3, moment equations linear in a2 and a3), computed
  from the collisional moments by quadrature (:func:`sonine_approximations`).
  (The 2D kernel with isotropic b is not the hard-disk one, so it has no such reference.)
- ``maxwell``: 2D Maxwell molecules, e = 0.5, rescaled to s = t = 40 (:data:`MAXWELL_CASES`:
  S = 3.5 ... 10, N = 64 and 128, and quadrature and time-step changes): the exact law
  T = T0 exp(-(1-e^2) t/4) and the kurtosis against its exact evolution from the closed
  moment equations (:func:`maxwell_kurtosis`). Their cooling state has a power-law tail
  (at e = 0.5 its scaled 6th moment is finite and its 8th is not, :func:`maxwell_moment_growth`),
  which a bounded box truncates.
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402

import granframe as gf  # noqa: E402
from granframe.abc import Part  # noqa: E402
from granframe.backends import preferred_backend  # noqa: E402
from granframe.equations.homogeneous import HomogeneousBoltzmann  # noqa: E402
from granframe.equations.rescaled import RescaledBoltzmann  # noqa: E402
from granframe.errors import NonFiniteError  # noqa: E402
from granframe.run.runner import moments  # noqa: E402
from granframe.theory.cooling import maxwellian_cooling_rate  # noqa: E402
from granframe.velocity.grid import ANTI_ALIASING_FACTOR  # noqa: E402
from granframe.tools.studykit import (command, finish, read_summary, save_figure, write_csv,  # noqa: E402
                                write_summary)

PARTS = ("concentration", "hcs", "maxwell")
E_CONCENTRATION, FINAL_T = 0.5, 100.0


def sonine_a2(e: float, d: int) -> float:
    """First Sonine approximation of the HCS of hard spheres (van Noije & Ernst 1998)."""
    return 16 * (1 - e) * (1 - 2 * e * e) / (9 + 24 * d - e * (41 - 8 * d) + 30 * e * e * (1 - e))


def _sonine_polynomial(order, x, d):
    """The Sonine polynomial S_order(x) of index d/2 - 1 (order 0, 2, 3), x = c^2."""
    if order == 0:
        return numpy.ones_like(x)
    if order == 2:
        return x * x / 2 - (d + 2) * x / 2 + d * (d + 2) / 8
    return (-x ** 3 / 6 + (d + 4) * x * x / 4 - (d + 2) * (d + 4) * x / 8
            + d * (d + 2) * (d + 4) / 48)


def sonine_collision_moments(e: float, d: int = 3, hermite: int = 10, radial: int = 48,
                             polar: int = 10) -> dict:
    r"""Collisional moments of inelastic hard spheres between Sonine terms, by quadrature.

    With F = phi (1 + a_2 S_2(c^2) + a_3 S_3(c^2)), phi = pi^{-d/2} e^{-c^2}, the moment
    mu_p = -\int c^p J[F, F] dc is, to first order in a_2 and a_3,
    mu_p = I(p, 0) + a_2 I(p, 2) + a_3 I(p, 3), with (up to a factor common to all p)

    .. math::

        I(p, k) = \frac{1}{2}\int dG \int dg \int_{g\cdot\hat\sigma > 0} d\hat\sigma\,
        \phi_1\phi_2 [S_k(c_1^2) + S_k(c_2^2)]\, (g\cdot\hat\sigma)
        (c_1^p + c_2^p - c_1'^p - c_2'^p)

    (S_0 = 1 counted once), c_{1,2} = G ± g/2, c_1' = c_1 - (1+e)/2 (g.sigma) sigma,
    c_2' = c_2 + (1+e)/2 (g.sigma) sigma. The integrand is rotation invariant, so g is put
    on the last axis and sigma in the plane of the first and last: Gauss-Hermite in each
    component of G (weight e^{-2G^2}, exact for these polynomials), Gauss-Legendre in
    |g| on [0, 12] (weight |g|^{d-1} e^{-|g|^2/2}) and in cos(theta) = g.sigma/|g| on [0, 1].
    Returns {(p, k): I(p, k)} for p = 2, 4, 6 and k = 0, 2, 3.
    """
    nodes, weights = numpy.polynomial.hermite.hermgauss(hermite)
    axis_points, axis_weights = nodes / numpy.sqrt(2), weights / numpy.sqrt(2)
    G = numpy.stack([a.ravel() for a in numpy.meshgrid(*[axis_points] * d, indexing="ij")], -1)
    G_weight = numpy.prod(numpy.stack([a.ravel() for a in numpy.meshgrid(
        *[axis_weights] * d, indexing="ij")], -1), axis=-1)
    x, w = numpy.polynomial.legendre.leggauss(radial)
    speed, speed_weight = 6 * (x + 1), 6 * w
    speed_weight = speed_weight * numpy.exp(-speed ** 2 / 2) * speed ** (d - 1)
    x, w = numpy.polynomial.legendre.leggauss(polar)
    cos, cos_weight = (x + 1) / 2, w / 2
    speed, cos = [a.ravel() for a in numpy.meshgrid(speed, cos, indexing="ij")]
    pair_weight = numpy.outer(speed_weight, cos_weight).ravel() * speed * cos   # (g.sigma)
    g = numpy.zeros((speed.size, d))
    g[:, -1] = speed
    sigma = numpy.zeros((speed.size, d))
    sigma[:, 0], sigma[:, -1] = numpy.sqrt(1 - cos ** 2), cos
    c1 = G[:, None, :] + g[None] / 2
    c2 = G[:, None, :] - g[None] / 2
    jump = ((1 + e) / 2 * (speed * cos))[None, :, None] * sigma[None]
    squares = [(c * c).sum(-1) for c in (c1, c2, c1 - jump, c2 + jump)]
    weight = G_weight[:, None] * pair_weight[None]
    moments = {}
    for p in (2, 4, 6):
        change = (squares[0] ** (p // 2) + squares[1] ** (p // 2) - squares[2] ** (p // 2)
                  - squares[3] ** (p // 2)) / 2
        for k in (0, 2, 3):
            factor = (1.0 if k == 0 else _sonine_polynomial(k, squares[0], d)
                      + _sonine_polynomial(k, squares[1], d))
            moments[(p, k)] = float(numpy.sum(weight * change * factor))
    return moments


def sonine_approximations(e: float, d: int = 3) -> tuple[float, float, float]:
    """(a_2 of the first Sonine approximation, a_2 and a_3 of the second) of the HCS of hard
    spheres, from the moment equations of :func:`sonine_collision_moments`.

    The scaled cooling state satisfies mu_p = (p/d) mu_2 <c^p> with <c^4> = d(d+2)/4 (1 + a_2)
    and <c^6> = d(d+2)(d+4)/8 (1 + 3a_2 - a_3). First approximation: p = 4 with a_3 = 0,
    linear in a_2 (this is van Noije & Ernst's, :func:`sonine_a2`). Second: p = 4 and p = 6,
    linear in (a_2, a_3): F truncated after S_3, products of a_2, a_3 dropped. Published
    closed forms of second approximations (Brilliantov & Poeschel, Europhys. Lett. 74, 2006;
    Santos & Montanero, Granular Matter 11, 2009) were not at hand to compare with.
    """
    I = sonine_collision_moments(e, d)
    k4, k6 = d + 2, 0.75 * (d + 2) * (d + 4)
    first = (k4 * I[(2, 0)] - I[(4, 0)]) / (I[(4, 2)] - k4 * (I[(2, 0)] + I[(2, 2)]))
    matrix = [[I[(4, 2)] - k4 * (I[(2, 0)] + I[(2, 2)]), I[(4, 3)] - k4 * I[(2, 3)]],
              [I[(6, 2)] - k6 * (3 * I[(2, 0)] + I[(2, 2)]),
               I[(6, 3)] - k6 * (I[(2, 3)] - I[(2, 0)])]]
    a2, a3 = numpy.linalg.solve(matrix, [k4 * I[(2, 0)] - I[(4, 0)], k6 * I[(2, 0)] - I[(6, 0)]])
    return float(first), float(a2), float(a3)


def _operator(kernel, d, n_modes, support, e, radial_points, sphere):
    """``fast_spectral`` on the grid (d, N, S) with explicit quadratures (N_rho, sphere)."""
    grid = gf.VelocityGrid(d, n_modes, support)
    return gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel(kernel),
        gf.restitution_law("constant", value=e), backend=gf.array_backend(preferred_backend()),
        radial_points=radial_points, sphere=sphere)


def _march(equation, f, dt, steps, every=1):
    """RK4 steps; the runner's moments after every ``every`` steps (until f is not finite)."""
    grid, rk4 = equation.operator.grid, gf.time_integrator("rk4")
    rows = [dict(moments(grid, f, numpy), step=0)]
    for i in range(1, steps + 1):
        with numpy.errstate(over="ignore", invalid="ignore"):   # the unscaled runs blow up
            try:
                f = rk4.step(equation, (i - 1) * dt, f, dt)
            except NonFiniteError:   # a stage overflowed: the operator refuses that stage
                rows.append(dict(moments(grid, numpy.full_like(f, numpy.nan), numpy), step=i))
                break
        if i % every == 0 or i == steps:
            state = moments(grid, f, numpy)
            rows.append(dict(state, step=i))
            if not numpy.isfinite(state["kinetic_energy"]):
                break
    return f, rows


def _plane_rules(n_modes):
    """The 2D quadratures of the concentration and Maxwell parts: N_rho = N/2, circle M = 32."""
    return n_modes // 2, gf.CircleTrapezoid(32)


def rescaled_run(kernel, d, n_modes, support, e, ds, rules, final_s=None, final_t=None,
                 every=1):
    """A rescaled run from the Maxwellian T0 = 1 to s = ``final_s`` or to the s of the
    physical time ``final_t``, with the quadratures ``rules`` = (N_rho, sphere rule); rows
    carry s, t, T_g and the physical T."""
    operator = _operator(kernel, d, n_modes, support, e, *rules)
    f0 = operator.grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    law = equation.rescaling
    if final_s is None:
        final_s = float(law.rescaled_time(final_t))
    g, rows = _march(equation, f0, ds, int(numpy.ceil(final_s / ds - 1e-9)), every)
    for row in rows:
        s = row["step"] * ds
        row.update(s=s, t=float(law.physical_time(s)), rescaled_temperature=row["temperature"],
                   temperature=float(law.temperature(s, row["temperature"])))
    return operator.grid, g, law, rows


def concentration(quick: bool) -> dict:
    sizes = (32,) if quick else (32, 64)
    final_t = 10.0 if quick else FINAL_T
    runs, rows = {}, []
    for n in sizes:
        grid, _, law, rescaled = rescaled_run("hard_spheres", 2, n, 4.0, E_CONCENTRATION, 0.1,
                                              _plane_rules(n), final_t=final_t)
        operator = _operator("hard_spheres", 2, n, 4.0, E_CONCENTRATION, *_plane_rules(n))
        dt = 0.05
        _, direct = _march(HomogeneousBoltzmann(operator), grid.maxwellian(temperature=1.0), dt,
                           round(final_t / dt))
        for row in direct:
            row["t"] = row["step"] * dt
        runs[n] = {"grid": grid, "rescaled": rescaled, "direct": direct, "law": law}
    finest = runs[sizes[-1]]
    spline = CubicSpline([r["s"] for r in finest["rescaled"]],
                         numpy.log([r["rescaled_temperature"] for r in finest["rescaled"]]))

    def exact(t):   # T(t) = T_g(s(t)) / omega(s(t))^2, T_g (nearly constant) interpolated in s
        s = finest["law"].rescaled_time(t)
        return finest["law"].temperature(s, numpy.exp(spline(s)))

    for n, run in runs.items():
        h = run["grid"].spacing
        for kind in ("direct", "rescaled"):
            series = run[kind]
            t = numpy.array([r["t"] for r in series])
            T = numpy.array([r["temperature"] for r in series])
            negative = numpy.array([r["negative_mass_fraction"] for r in series])
            error = numpy.abs(T / exact(t) - 1)
            run[kind + "_error"] = error
            bad_T = numpy.flatnonzero(~(error <= 1e-3))
            bad_share = numpy.flatnonzero(~(negative <= 1e-2))
            row = {"N": n, "h": h, "formulation": kind, "final_t": float(t[-1]),
                   "final_T": float(T[-1]), "final_negative_share": float(negative[-1])}
            for label, bad in (("T_error_1e-3", bad_T), ("negative_share_1e-2", bad_share)):
                i = int(bad[0]) if bad.size else None
                row[f"t_{label}"] = None if i is None else float(t[i])
                row[f"T_over_T0_{label}"] = None if i is None else float(T[i])
                row[f"thermal_speed_over_h_{label}"] = (None if i is None
                                                         else float(numpy.sqrt(T[i]) / h))
            early = t <= 1.0
            row["max_error_t_le_1"] = float(error[early].max())
            rows.append(row)
    return {"rows": rows, "runs": runs, "exact": exact, "final_t": final_t}


#: Restitution coefficients of the cooling-state table.
HCS_RESTITUTIONS = (0.2, 0.4, 0.5, 0.6, 0.8, 0.9)
#: Resolutions of the cooling state, per dimension: (N, S, N_rho, sphere rule), and the
#: rescaled time run, both from the Maxwellian T0 = 1. ``main`` gives the table; ``refined``
#: raises S (so L and the truncation R = 2S), N and both quadratures at about the same
#: spacing h. It is compared with the main run at its own final s, where the two have had
#: the same time. ``smoke`` is the quick variant's.
HCS_RESOLUTIONS = {
    "main": ({3: (32, 4.5, 30, gf.Lebedev(17)), 2: (64, 4.5, 32, gf.CircleTrapezoid(32))}, 10.0),
    "refined": ({3: (40, 5.5, 36, gf.Lebedev(23)), 2: (80, 5.5, 40, gf.CircleTrapezoid(64))},
                6.0),
    "smoke": ({2: (32, 3.5, 16, gf.CircleTrapezoid(32))}, 3.0),
}
#: Restitution coefficients of the refined runs (in 3D one costs about 4 main runs per unit s).
HCS_REFINED = {3: (0.2, 0.5, 0.9), 2: HCS_RESTITUTIONS}
#: Largest ds times the drift's radius bound (RescaledBoltzmann.stiffness) of these runs. The
#: bound is loose: RK4 ran stably at 4.3 (2D, N = 64, S = 4.5, e = 0.2, ds = 0.1) and blew up
#: at 5.4 (N = 80, S = 5.5). ds = min(0.1, 4/radius); the cooling state, a zero of the
#: right-hand side, does not depend on ds.
HCS_DRIFT_STEP = 4.0


def settling_time(series, tolerance: float = 1e-4) -> float:
    """The rescaled time from which the kurtosis stays within ``tolerance`` of its last value."""
    last = series[-1]["kurtosis"]
    away = [r["s"] for r in series if abs(r["kurtosis"] - last) > tolerance]
    return max(away, default=series[0]["s"])


def hcs_case(level: str, d: int, e: float) -> tuple[dict, list]:
    """One cooling state: the rescaled hard-sphere run from the Maxwellian T0 = 1 at the
    resolution ``level`` of :data:`HCS_RESOLUTIONS`; its table row and its history. The row
    carries a2 at the refined runs' final s too, for the comparison with them."""
    resolutions, final_s = HCS_RESOLUTIONS[level]
    n, support, radial_points, sphere = resolutions[d]
    operator = _operator("hard_spheres", d, n, support, e, radial_points, sphere)
    grid = operator.grid
    f0 = grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    ds = min(0.1, HCS_DRIFT_STEP / equation.stiffness(f0)[Part.DRIFT])
    steps = int(numpy.ceil(final_s / ds - 1e-9))
    ds = final_s / steps
    _, series = _march(equation, f0, ds, steps)
    for row in series:
        row["s"] = row["step"] * ds
    last = series[-1]
    tail = [r["kurtosis"] for r in series if r["s"] >= final_s - 2.0 - 1e-9]
    compare = HCS_RESOLUTIONS["refined"][1]
    row = {"level": level, "d": d, "N": n, "S": support, "h": grid.spacing,
           "N_rho": radial_points, "sphere": _rule_label(sphere), "ds": ds, "final_s": final_s,
           "e": e, "a0": equation.rescaling.rate, "kurtosis": last["kurtosis"],
           "a2": last["sonine_a2"],
           f"a2_at_s{compare:g}": min(series, key=lambda r: abs(r["s"] - compare))["sonine_a2"],
           "kurtosis_change_last_2": max(tail) - min(tail),
           "s_settled_1e-4": settling_time(series),
           "rescaled_temperature": last["temperature"],
           "negative_share": last["negative_mass_fraction"],
           "mass_error": abs(last["mass"] / series[0]["mass"] - 1)}
    return row, series


def hcs(quick: bool) -> dict:
    """The cooling states at the main resolution (the table) and at the refined one (its
    convergence column); the Sonine approximations of 3D hard spheres."""
    restitutions = (0.5,) if quick else HCS_RESTITUTIONS
    rows, histories = [], {}
    for d in (3, 2):
        for e in restitutions:
            for level in ("smoke",) if quick else ("main", "refined"):
                if d in HCS_RESOLUTIONS[level][0] and (level != "refined"
                                                      or e in HCS_REFINED[d]):
                    row, histories[(level, d, e)] = hcs_case(level, d, e)
                    rows.append(row)
    return {"rows": rows, "histories": histories,
            "sonine": [dict(e=e, **dict(zip(("a2_first", "a2_second", "a3_second"),
                                sonine_approximations(e, 3))))
                       for e in restitutions]}


def maxwell_moment_rates(e: float, d: int = 2) -> tuple[float, float, float]:
    r"""Exact moment equations of inelastic Maxwell molecules with constant e and
    \int B d\sigma = 1 (B = 1/(2 pi) in 2D), for isotropic f with zero mean velocity.

    In the sigma-representation v' = V + (1-e)/4 g + (1+e)/4 |g| sigma (V the centre of mass,
    g = v - v_*), the weak form d/dt <psi> = <<E_sigma psi(v') - psi(v)>> over pairs of f
    closes on the moments m_n = \int |v|^n f:

        dm_2/dt = -lambda m_2,   dm_4/dt = A m_4 + B m_2^2.

    With W = p v + q v_* (p, q = 1/2 ± (1-e)/4) and b = (1+e)/4,
    E_sigma|v'|^4 = |W|^4 + (2 + 4/d) b^2 |W|^2 |g|^2 + b^4 |g|^4, averaged over independent
    isotropic v, v_* with <|v|^2 (v.v_*)> = 0 and <(v.v_*)^2> = m_2^2/d. Returns (lambda, A, B);
    lambda = (1 - e^2)/4 in every d.
    """
    p, q, b = 0.5 + (1 - e) / 4, 0.5 - (1 - e) / 4, (1 + e) / 4

    def pair(al, be, ga, de):   # <|al v + be v*|^2 |ga v + de v*|^2> = (m_4, m_2^2) coefficients
        return numpy.array([al * al * ga * ga + be * be * de * de,
                            al * al * de * de + be * be * ga * ga + 4 * al * be * ga * de / d])

    quartic = (pair(p, q, p, q) + (2 + 4 / d) * b * b * pair(p, q, 1, -1)
               + b ** 4 * pair(1, -1, 1, -1))
    return 1 - (p * p + q * q + 2 * b * b), quartic[0] - 1, quartic[1]


def maxwell_moment_growth(order: int, e: float) -> float:
    """Growth rate of the scaled moment m_n / m_2^{n/2} (n = ``order``, even) of cooling 2D
    Maxwell molecules: A_n + n lambda/2, where A_n = E_sigma|p x + b sigma|^n +
    E_sigma|q x + b sigma|^n - 1 (x a unit vector; :func:`maxwell_moment_rates` for p, q, b)
    is the coefficient of m_n in dm_n/dt (the terms with all n powers on one partner); the
    rest of the equation holds lower moments only. The cooling state has a finite scaled
    m_n where this is negative, and none where it is positive: a power-law tail. The circle
    average is a trapezoid rule, exact for these trigonometric polynomials."""
    p, q, b = 0.5 + (1 - e) / 4, 0.5 - (1 - e) / 4, (1 + e) / 4
    angle = numpy.linspace(0.0, 2 * numpy.pi, 4 * order + 4, endpoint=False)
    rate = sum(numpy.mean(((c + b * numpy.cos(angle)) ** 2 + (b * numpy.sin(angle)) ** 2)
                          ** (order // 2)) for c in (p, q)) - 1
    return float(rate + order / 2 * maxwell_moment_rates(e, 2)[0])


def maxwell_kurtosis(t, e: float, d: int = 2, initial: float | None = None):
    """Exact kurtosis m_4/m_2^2 of cooling Maxwell molecules at time t (from the Maxwellian,
    (d+2)/d, unless ``initial``): K = K_inf + (K_0 - K_inf) e^{(A + 2 lambda) t} with
    K_inf = -B/(A + 2 lambda) (:func:`maxwell_moment_rates`); scale-free, so the same in the
    rescaled variables."""
    rate, a, b = maxwell_moment_rates(e, d)
    start = (d + 2) / d if initial is None else initial
    limit = -b / (a + 2 * rate)
    return limit + (start - limit) * numpy.exp((a + 2 * rate) * numpy.asarray(t))


#: The Maxwell-molecule runs: (N, S, N_rho, circle M, ds); N_rho = N/2, M = 32, ds = 0.1 for
#: S = 3.5, 5, 7 at N = 64 and S = 7, 10 at N = 128 (S doubled at h = 0.24 and 0.34, h halved
#: at S = 7), then one quadrature or time-step change at a time at (64, 5).
MAXWELL_CASES = ((64, 3.5, 32, 32, 0.1), (64, 5.0, 32, 32, 0.1), (64, 7.0, 32, 32, 0.1),
                 (128, 7.0, 64, 32, 0.1), (128, 10.0, 64, 32, 0.1), (64, 5.0, 64, 32, 0.1),
                 (64, 5.0, 32, 64, 0.1), (64, 5.0, 32, 32, 0.05))
#: Times at which the kurtosis is compared with the exact one.
MAXWELL_TIMES = (10.0, 20.0, 40.0)


def maxwell(quick: bool) -> dict:
    cases = MAXWELL_CASES[:1] if quick else MAXWELL_CASES
    final_s = 5.0 if quick else 40.0
    times = [t for t in MAXWELL_TIMES if t <= final_s] or [final_s]
    rows, histories = [], {}
    e = 0.5
    for n, support, radial_points, circle, ds in cases:
        grid, g, law, series = rescaled_run("maxwell", 2, n, support, e, ds,
                                            (radial_points, gf.CircleTrapezoid(circle)),
                                            final_s, every=round(1 / ds))
        T0 = series[0]["temperature"]
        for r in series:
            r["T_error"] = abs(r["temperature"] / (T0 * numpy.exp(-maxwellian_cooling_rate(e) * r["t"])) - 1)
            r["kurtosis_error"] = r["kurtosis"] - float(maxwell_kurtosis(r["t"], e))
        histories[(n, support, radial_points, circle, ds)] = series
        row = {"N": n, "S": support, "h": grid.spacing, "N_rho": radial_points, "M": circle,
               "ds": ds, "final_t": series[-1]["t"], "T_over_T0": series[-1]["temperature"] / T0,
               "max_T_error": max(r["T_error"] for r in series), "a0": law.rate}
        for t in times:
            at = min(series, key=lambda r: abs(r["t"] - t))
            row[f"kurtosis_t{t:g}"] = at["kurtosis"]
            row[f"kurtosis_exact_t{t:g}"] = float(maxwell_kurtosis(at["t"], e))
        rows.append(row)
    return {"rows": rows, "histories": histories}


_TIME = "time t (dimensionless)"


def _rule_label(sphere) -> str:
    """'Lebedev <order>' or 'circle M = <points>'."""
    return (f"Lebedev {sphere.order}" if isinstance(sphere, gf.Lebedev)
            else f"circle M = {sphere.n_points}")


def _numerics(level, d) -> str:
    """N, S, N_rho and the sphere rule of the cooling-state runs of ``level`` in ``d`` D."""
    n, support, radial_points, sphere = HCS_RESOLUTIONS[level][0][d]
    return f"N = {n}, S = {support}, N_ρ = {radial_points}, {_rule_label(sphere)}"


def _positive(values):
    """``values`` with zeros and negative entries left out (for a logarithmic axis)."""
    values = numpy.asarray(values, dtype=float)
    return numpy.where(values > 0, values, numpy.nan)


def _figure_concentration(result, out):
    fig, axes = plt.subplots(1, 3, figsize=(16, 5), constrained_layout=True)
    styles = {"direct": "-", "rescaled": "--"}
    reference = max(result["runs"])
    for n, run in result["runs"].items():
        for kind in ("direct", "rescaled"):
            series = run[kind]
            t = numpy.array([r["t"] for r in series])
            label = f"{'unscaled' if kind == 'direct' else 'rescaled'}, N = {n}"
            keep = t > 0
            axes[0].loglog(t[keep], _positive([r["temperature"] for r, k in zip(series, keep)
                                               if k]), styles[kind], label=label)
            error_label = label + (" (the reference itself: round-off)"
                                   if kind == "rescaled" and n == reference else "")
            axes[1].loglog(t[keep], _positive(run[kind + "_error"][keep]), styles[kind],
                           label=error_label)
            axes[2].loglog(t[keep], _positive([r["negative_mass_fraction"]
                                               for r, k in zip(series, keep) if k]),
                           styles[kind], label=label)
    axes[1].axhline(1e-3, color="k", ls=":", lw=1, label="1e-3 (the report's threshold)")
    axes[2].axhline(1e-2, color="k", ls=":", lw=1, label="runner's positivity limit (1 %)")
    axes[0].set(xlabel=_TIME, ylabel="temperature T (dimensionless)",
                title="temperature (T ≤ 0 and non-finite values left out)", ylim=(1e-4, 2.0))
    axes[1].set(xlabel=_TIME, ylabel=r"temperature error $|T/T_{ref} - 1|$ (dimensionless)",
                ylim=(1e-17, 10.0),
                title=f"error against the reference (rescaled, N = {reference}; zeros left out)")
    axes[2].set(xlabel=_TIME,
                ylabel=r"negative mass share $\int f^- / \int |f|$ (dimensionless)",
                title="positivity (zeros left out)", ylim=(1e-18, 1.0))
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    sizes = ", ".join(str(n) for n in result["runs"])
    fig.suptitle(f"free cooling of 2D hard spheres (kernel exponent λ = 1), constant e = "
                 f"{E_CONCENTRATION}, Maxwellian T0 = 1, S = 4, N = {sizes}, N_ρ = N/2, circle "
                 f"M = 32\nRK4: unscaled Δt = 0.05, rescaled Δs = 0.1, to t = "
                 f"{result['final_t']:g}; all quantities dimensionless", fontsize=10)
    save_figure(fig, out / "concentration.png")


def _figure_hcs(result, out):
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5), constrained_layout=True)
    rows = result["rows"]
    first = rows[0]["level"]                      # "main" (or "smoke" in the quick variant)
    shown = max(r["d"] for r in rows)
    for (level, d, e), series in result["histories"].items():
        if level == first and d == shown:
            axes[0].plot([r["s"] for r in series], [r["kurtosis"] for r in series],
                         label=f"e = {e}")
    axes[0].axhline((shown + 2) / shown, color="k", ls=":", lw=1,
                    label=f"Maxwellian, (d + 2)/d = {(shown + 2) / shown:.4g}")
    axes[0].set(xlabel="rescaled time s (dimensionless)",
                ylabel=r"kurtosis $\kappa$ (dimensionless)",
                title=f"{shown}D hard spheres, {first} resolution, from a Maxwellian")
    styles = {("main", 3): "o", ("refined", 3): "x", ("main", 2): "s", ("refined", 2): "+",
              ("smoke", 2): "s"}
    for (level, d), marker in styles.items():
        chosen = [r for r in rows if r["d"] == d and r["level"] == level]
        if chosen:
            axes[1].plot([r["e"] for r in chosen], [r["a2"] for r in chosen], marker,
                         ms=8 if marker in "x+" else 6, mfc="none" if marker in "os" else None,
                         label=f"granframe {d}D, {level}: {_numerics(level, d)}")
    grid_e = numpy.linspace(0.0, 1.0, 101)
    axes[1].plot(grid_e, [sonine_a2(e, 3) for e in grid_e], "k-", lw=1,
                 label="first Sonine approximation, 3D hard spheres (van Noije & Ernst 1998);"
                       "\nnone for the 2D kernel")
    sonine = result["sonine"]
    axes[1].plot([r["e"] for r in sonine], [r["a2_second"] for r in sonine], "k--", lw=1,
                 marker=".", label="second Sonine approximation, 3D, linear in (a2, a3)")
    axes[1].set(xlabel="restitution coefficient e (dimensionless)",
                ylabel=r"Sonine coefficient $a_2$ of the cooling state (dimensionless)",
                title="cooling state: a2 at the last step")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    final_s = {r["level"]: r["final_s"] for r in rows}
    fig.suptitle("homogeneous cooling state of hard spheres (kernel exponent λ = 1), constant "
                 "e, no heat bath, rescaled formulation, RK4 with Δs = min(0.1, 4/drift radius)\n"
                 + "; ".join(f"{level}: to s = {s:g}" for level, s in final_s.items())
                 + ", from a Maxwellian T0 = 1; all quantities dimensionless", fontsize=10)
    save_figure(fig, out / "hcs.png")


def _figure_maxwell(result, out):
    fig, axes = plt.subplots(1, 2, figsize=(14, 5.5), constrained_layout=True)
    for (n, support, radial_points, circle, ds), series in result["histories"].items():
        check = (radial_points, circle, ds) != (n // 2, 32, 0.1)
        label = (f"N = {n}, S = {support} (h = {2 * ANTI_ALIASING_FACTOR * support / n:.2f})"
                 + (f", N_ρ = {radial_points}, M = {circle}, Δs = {ds}" if check else ""))
        t = [r["t"] for r in series]
        style = dict(ls=":" if check else "-", marker="o", ms=2.5, lw=1, label=label)
        axes[0].semilogy(t, _positive([r["T_error"] for r in series]), **style)
        axes[1].plot(t, [r["kurtosis_error"] for r in series], **style)
    final_s = max(r["s"] for series in result["histories"].values() for r in series)
    axes[0].set(xlabel=_TIME, ylabel=r"temperature error $|T/T_{exact} - 1|$ (dimensionless)",
                title="against T0 exp(-(1 - e²) t/4) (zeros at t = 0 left out)")
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[1].set(xlabel=_TIME,
                ylabel=r"kurtosis error $\kappa - \kappa_{exact}$ (dimensionless)",
                title="against the exact moment equations (maxwell_kurtosis)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("free cooling of 2D Maxwell molecules (kernel exponent λ = 0), e = 0.5, "
                 "Maxwellian T0 = 1, rescaled, RK4 to s = t = "
                 f"{final_s:g}\nN_ρ = N/2, circle M = 32, Δs = 0.1 unless stated; a marker "
                 "per unit of time; all quantities dimensionless", fontsize=10)
    save_figure(fig, out / "maxwell_tails.png")


def run(out: pathlib.Path, quick: bool = False, only=None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = read_summary(out, only)
    parts = {"concentration": (concentration, _figure_concentration),
             "hcs": (hcs, _figure_hcs), "maxwell": (maxwell, _figure_maxwell)}
    for name in PARTS if only is None else [p for p in PARTS if p in only]:
        measure, draw = parts[name]
        result = measure(quick)
        write_csv(out / f"{name}.csv", result["rows"])
        draw(result, out)
        summary[name] = result["rows"]
        if "sonine" in result:            # hcs: the Sonine approximations of its table
            write_csv(out / "sonine.csv", result["sonine"])
            summary["sonine"] = result["sonine"]
    write_summary(out, summary)
    return summary


def _show(summary):
    for name, rows in summary.items():
        print(name)
        for row in rows:
            print("  " + ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                                   for k, v in row.items()))


main = command(run, __doc__, "short runs at small N (smoke test)", parts="part", show=_show)


if __name__ == "__main__":
    raise SystemExit(finish(main))
