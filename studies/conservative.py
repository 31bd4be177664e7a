"""The conservative correction of Q: its constraints, the penalised schemes' energy defect,
and spectral accuracy (docs/conservative.md).

    python studies/conservative.py --out docs/figures/conservative     # a few minutes, 2 cores
    python studies/conservative.py --out /tmp/conservative --quick     # seconds (smoke test)

Three parts (``--only constraints,penalised,bkw``), each a CSV table, all of them printed
as Markdown and written to ``tables.md``:

- ``constraints``: the moments of Q_c(f) - (0, 0, D(f)), and D(f) with R covering every
  pair of grid points against the closed-form Maxwell dissipation, for a smooth
  non-Maxwellian f (two Maxwellians) on 2D N = 32 and 3D N = 16 with the review's
  quadratures, Maxwell molecules and hard spheres, constant and speed-dependent (Toscani)
  e, each weight;
- ``penalised``: the largest temperature error over t in (0, 0.2] of the penalised schemes
  at eps = 1e-4, 2D N = 32, from two Maxwellians: elastic (T conserved) and e = 0.999
  (Haff's exponential law), dt = 0.01 (dt/eps = 100) refined to dt/8, with and without the
  correction, with the order observed between successive dt; the inelastic ARS(2,2,2)
  runs again at N = 48, and RK4 at dt/eps = 2.5 as an explicit reference;
- ``bkw``: max |Q - df/dt| / max |df/dt| of the fast operator, plain and corrected with
  each weight, on the BKW solution at t = 6.5 (elastic Maxwell molecules) over N, 2D and
  3D, with the quadratures refined so that N is the limit (N_rho = 48; M = 32 in 2D,
  Lebedev 17 in 3D, 21 at N = 40); the size of each correction, everywhere and outside
  B_S; the seconds of Q and of the correction alone.
"""

from __future__ import annotations

import math
import pathlib
import time

import numpy

import granframe as gf
from granframe.abc import CollisionOperator
from granframe.backends import preferred_backend
from granframe.equations.conservative import WEIGHTS, ConservativeCorrection
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.model.exact import bkw, heated_maxwell_temperature, maxwell_energy_dissipation
from granframe.tools.studykit import command, finish, read_summary, write_csv, write_summary

PARTS = ("constraints", "penalised", "bkw")

#: The review's quadratures (section 3): N_rho = 32 and 16 circle points in 2D, N_rho = 30
#: and the 32-point product rule in 3D
REVIEW_RULES = {2: {"radial_points": 32, "sphere": gf.CircleTrapezoid(16)},
                3: {"radial_points": 30, "sphere": gf.SphereProduct(4)}}


def _backend():
    return gf.array_backend(preferred_backend())


def _two_maxwellians(grid):
    """0.6 M(u = (0.8, 0, ..), T = 0.8) + 0.4 M(u = (-1.2, 0.3, ..), T = 0.5): far from
    equilibrium, with nonzero momentum."""
    d = grid.dimension
    return grid.project(grid.maxwellian(0.6, [0.8] + [0.0] * (d - 1), 0.8)
                        + grid.maxwellian(0.4, [-1.2, 0.3] + [0.0] * (d - 2), 0.5))


def _moments(grid, q):
    """h^d sum q (1, v, |v|^2)."""
    return ([grid.mass(q)] + list(grid.momentum(q))
            + [2.0 * grid.kinetic_energy(q)])


# -- constraints -----------------------------------------------------------------------------
def constraints(quick: bool) -> list[dict]:
    """Residuals of the d + 2 constraints of Q_c and the defects of Q, per setting."""
    rows = []
    cases = [(2, 32), (3, 16)] if not quick else [(2, 16)]
    laws = {"constant e = 0.5": gf.restitution_law("constant", value=0.5),
            "Toscani e = 1/(1 + 0.3|g|)": gf.restitution_law("toscani", strength=0.3,
                                                             exponent=1.0)}
    for d, n in cases:
        grid = gf.VelocityGrid(d, n, 4.0)
        f = _two_maxwellians(grid)
        # the same grid with R covering every pair of points, where the closed form holds
        covering = gf.VelocityGrid(d, n, 4.0, truncation_radius=2 * math.sqrt(d)
                                   * grid.half_width)
        for kernel_name in ("maxwell", "hard_spheres"):
            kernel = gf.collision_kernel(kernel_name)
            for law_name, law in laws.items():
                operator = gf.collision_operator("fast_spectral", grid, kernel, law,
                                                 backend=_backend(), **REVIEW_RULES[d])
                q = operator(f)
                plain = numpy.array(_moments(grid, q))
                for weight in WEIGHTS:
                    corrected = ConservativeCorrection(operator, weight)
                    dissipation = float(corrected.dissipation(f))
                    target = numpy.zeros(d + 2)
                    target[-1] = dissipation
                    moments = numpy.array(_moments(grid, corrected(f)))
                    if kernel.is_maxwellian and law.is_constant:
                        exact = maxwell_energy_dissipation(grid, f, law.value, kernel)
                        closed = abs(float(ConservativeCorrection(gf.collision_operator(
                            "fast_spectral", covering, kernel, law, backend=_backend()))
                            .dissipation(f)) / exact - 1.0)
                    else:
                        closed = math.nan
                    rows.append({
                        "d": d, "N": n, "kernel": kernel_name, "restitution": law_name,
                        "weight": weight, "D": dissipation,
                        "D_vs_exact_maxwell": closed,
                        "Q_momentum_defect": float(numpy.abs(plain[1:-1]).max()),
                        "Q_energy_defect": abs(plain[-1] - dissipation) / abs(dissipation),
                        "Qc_mass_residual": abs(moments[0]),
                        "Qc_momentum_residual": float(numpy.abs(moments[1:-1]).max()),
                        "Qc_energy_residual": abs(moments[-1] - target[-1]) / abs(dissipation)})
    return rows


# -- penalised schemes -----------------------------------------------------------------------
def penalised_error(scheme: str, restitution: float, steps: int, weight: str | None,
                    n_modes: int = 32, knudsen: float = 1e-4, final_time: float = 0.2) -> dict:
    """max over the steps of |T / T_exact - 1| (T_exact: T0 for e = 1, Haff's exponential
    law T0 exp(-rho (1 - e^2) t / (4 eps)) otherwise), the final mass and momentum drifts,
    and for e < 1 how far D(f) at the end is from the closed form of Maxwell molecules that
    the law assumes (it is not where f f_* reaches beyond R), for ``steps`` steps of
    ``scheme`` up to ``final_time``."""
    grid = gf.VelocityGrid(2, n_modes, 4.0)
    kernel = gf.collision_kernel("maxwell")
    plain = gf.collision_operator(
        "fast_spectral", grid, kernel, gf.restitution_law("constant", value=restitution),
        backend=_backend(), radial_points=32, sphere=gf.CircleTrapezoid(32))
    corrected = ConservativeCorrection(plain, weight or "maxwellian")
    operator = plain if weight is None else corrected
    equation = HomogeneousBoltzmann(operator, heat_bath=0.0, knudsen=knudsen)
    integrator = gf.time_integrator(scheme)
    f = _two_maxwellians(grid)
    rho, T0, p0 = grid.mass(f), grid.temperature(f), grid.momentum(f)
    dt, worst = final_time / steps, 0.0
    for i in range(steps):
        f = integrator.step(equation, i * dt, f, dt)
        exact = heated_maxwell_temperature((i + 1) * dt, T0, restitution, 0.0, rho / knudsen)
        worst = max(worst, abs(grid.temperature(f) / exact - 1.0))
    closed = maxwell_energy_dissipation(grid, f, restitution, kernel)
    return {"T_error": worst, "mass_drift": abs(grid.mass(f) / rho - 1.0),
            "momentum_drift": float(numpy.abs(grid.momentum(f) - p0).max()),
            "min_f_over_max_f": float(f.min() / f.max()),
            "D_vs_closed_form": (abs(float(corrected.dissipation(f)) / closed - 1.0)
                                 if restitution < 1.0 else math.nan)}


def penalised(quick: bool) -> list[dict]:
    """:func:`penalised_error` of both schemes, elastic and e = 0.999, without and with the
    correction, at 2D N = 32 over dt = 0.2/steps; the inelastic ARS(2,2,2) runs again at
    N = 48, where the grid no longer limits the error, and an explicit RK4 reference runs at
    dt/eps = 2.5 (N = 32, 800 steps)."""
    rows = []
    steps_list = (20,) if quick else (20, 40, 80, 160)
    weights = (None, "maxwellian") if quick else (None,) + WEIGHTS
    cases = [(scheme, e, 32, weight) for scheme in ("penalised_euler", "penalised_ars222")
             for e in (1.0, 0.999) for weight in weights]
    if not quick:
        cases += [("penalised_ars222", 0.999, 48, weight) for weight in (None, "maxwellian")]
        cases += [("rk4", 0.999, 32, "maxwellian")]      # explicit: dt/eps = 2.5
    for scheme, restitution, n_modes, weight in cases:
        previous = None
        for steps in (800,) if scheme == "rk4" else steps_list:
            result = penalised_error(scheme, restitution, steps, weight, n_modes)
            order = math.log2(previous / result["T_error"]) if previous else math.nan
            previous = result["T_error"]
            rows.append({"scheme": scheme, "e": restitution, "N": n_modes,
                         "weight": weight or "none", "steps": steps, "dt": 0.2 / steps,
                         "dt_over_eps": 0.2 / steps / 1e-4, **result,
                         "observed_order": order})
    return rows


# -- spectral accuracy -----------------------------------------------------------------------
class _Given(CollisionOperator):
    """An operator that returns a Q computed beforehand, with e = 0.5 (so that D(f) is
    computed): what the correction alone costs."""

    name = "given"

    def __init__(self, operator, q):
        super().__init__(operator.grid, operator.kernel,
                         gf.restitution_law("constant", value=0.5), operator.backend)
        self.q = q

    def __call__(self, f):
        return self.q


def bkw_errors(dimension: int, n_modes: int) -> dict:
    """Relative max errors of Q and of Q_c (each weight) on BKW at t = 6.5, S = 5; the size
    of the correction, everywhere and outside B_S; the seconds of Q and of the correction
    alone (best of 3, with D(f) computed)."""
    grid = gf.VelocityGrid(dimension, n_modes, 5.0)
    f, dfdt = bkw(grid, 6.5)
    sphere = gf.CircleTrapezoid(32) if dimension == 2 else gf.Lebedev(17 if n_modes < 40
                                                                          else 21)
    operator = gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel("maxwell"),
        gf.restitution_law("constant", value=1.0), backend=_backend(), radial_points=48,
        sphere=sphere)
    scale = numpy.abs(dfdt).max()
    outside = grid.speed_squared() > grid.support_radius ** 2
    started = time.perf_counter()
    q = operator(f)
    row = {"d": dimension, "N": n_modes, "h": grid.spacing,
           "Q": float(numpy.abs(q - dfdt).max() / scale),
           "Q_energy_defect": abs(2.0 * grid.kinetic_energy(q)),
           "seconds_Q": time.perf_counter() - started}
    for weight in WEIGHTS:
        qc = ConservativeCorrection(operator, weight)(f)
        row[f"Qc_{weight}"] = float(numpy.abs(qc - dfdt).max() / scale)
        row[f"size_{weight}"] = float(numpy.abs(qc - q).max() / scale)
        row[f"outside_{weight}"] = float(numpy.abs(qc - q)[outside].max() / scale)
        alone = ConservativeCorrection(_Given(operator, q), weight)
        seconds = []
        for _ in range(3):
            started = time.perf_counter()
            alone(f)
            seconds.append(time.perf_counter() - started)
        row[f"seconds_{weight}"] = min(seconds)
    return row


def bkw_table(quick: bool) -> list[dict]:
    sizes = {2: (16, 24), 3: (16,)} if quick else {2: (16, 24, 32, 48, 64),
                                                   3: (16, 24, 32, 40)}
    return [bkw_errors(d, n) for d, ns in sizes.items() for n in ns]


# -- report ----------------------------------------------------------------------------------
def _markdown(rows: list[dict], columns: list[str]) -> str:
    def cell(column, value):
        if isinstance(value, float):
            return ("—" if math.isnan(value) else f"{value:.4g}" if column in PLAIN
                    else f"{value:.2e}")
        return str(value)
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(c, row[c]) for c in columns) + " |" for row in rows]
    return "\n".join(lines)


#: columns shown as plain numbers rather than in exponent form
PLAIN = {"e", "h", "dt_over_eps", "observed_order"}

#: the Markdown tables: name -> (the part whose rows they show, their columns)
TABLES = {
    "constraints": ("constraints", [
        "d", "N", "kernel", "restitution", "weight", "D_vs_exact_maxwell", "Q_momentum_defect",
        "Q_energy_defect", "Qc_mass_residual", "Qc_momentum_residual", "Qc_energy_residual"]),
    "penalised": ("penalised", ["scheme", "e", "N", "weight", "steps", "dt_over_eps",
                                "T_error", "observed_order", "mass_drift", "momentum_drift",
                                "min_f_over_max_f", "D_vs_closed_form"]),
    "bkw": ("bkw", ["d", "N", "h", "Q_energy_defect", "Q"] + [f"Qc_{w}" for w in WEIGHTS]),
    "bkw_correction": ("bkw", ["d", "N"] + [f"{k}_{w}" for w in WEIGHTS
                                             for k in ("size", "outside")]),
    "bkw_cost": ("bkw", ["d", "N", "seconds_Q"] + [f"seconds_{w}" for w in WEIGHTS]),
}


def run(out: pathlib.Path, quick: bool = False, only=None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = read_summary(out, only)
    makers = {"constraints": constraints, "penalised": penalised, "bkw": bkw_table}
    for part in PARTS:
        if only and part not in only:
            continue
        started = time.perf_counter()
        rows = makers[part](quick)
        write_csv(out / f"{part}.csv", rows)
        summary[part] = {"rows": rows, "seconds": time.perf_counter() - started}
    summary["quick"] = quick
    write_summary(out, summary)
    (out / "tables.md").write_text(_tables(summary))
    return summary


def _tables(summary: dict) -> str:
    return "\n\n".join(f"### {name}\n\n" + _markdown(summary[part]["rows"], columns)
                       for name, (part, columns) in TABLES.items() if part in summary) + "\n"


def _show(summary):
    print(_tables(summary))


main = command(run, __doc__, "small grids and one step size (smoke test)",
               parts="part (constraints, penalised, bkw)", show=_show)


if __name__ == "__main__":
    raise SystemExit(finish(main))
