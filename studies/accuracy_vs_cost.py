"""Accuracy against cost of the spectral operators, with Pareto fronts (docs/accuracy-vs-cost.md).

    python studies/accuracy_vs_cost.py --out docs/figures/accuracy      # about 15 min, 2 cores
    python studies/accuracy_vs_cost.py --out /tmp/accuracy --quick      # seconds (CI smoke test)

Run it on a quiet machine: the cost axis is measured wall time. Five scenes, each a sweep
over method (fast / direct), N, N_rho, the circle or sphere rule, precision (float64 /
float32) and, for time to solution, the time step:

Per evaluation (error of Q(f) at the grid points against a reference, cost = median time
of one evaluation after a warm-up):

- ``bkw_2d``, ``bkw_3d``: elastic Maxwell molecules, the BKW solution at t = 6.5; the
  reference is its exact df/dt;
- ``hard_spheres_tanh_3d``: hard spheres, tanh restitution law (e0 = 0.2), f0 a sum of two
  Maxwellians (densities 0.6 and 0.4, T = 1 and 0.6, drifts 0.8 e1 and (-0.9, 0.4, 0));
  the reference is the fast method at N = 48 (N_rho = 48, Lebedev degree 29),
  whose grid contains the coarse grids' points; its quadrature error is measured against
  N_rho = 64 with Lebedev degree 41 (the report's ``reference_check``). (The direct method
  is no reference here: it fits in memory only for N <= 16, where f is not resolved and
  its Galerkin sum differs from the fast method's circular one by aliasing.)

Time to solution (max |T/T_exact - 1| over t in [0, 2] against the exact law, cost = wall
time of the whole run; classical RK4, state in float64):

- ``heated_2d``: the review's heated Maxwell problem, e = 0.5, tau = 0.1, T0 = 8 (S = 12);
- ``heated_3d``: the same in 3D from T0 = 1.5 (S = 5).

A configuration is on the Pareto front when no other one is cheaper and as accurate
(within 10 %, see :func:`pareto`). Errors are floored at 1e-16 for the log scale.
"""

from __future__ import annotations

import itertools
import pathlib
import textwrap
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
from matplotlib import ticker  # noqa: E402

import granframe as gf  # noqa: E402
from granframe.backends import preferred_backend
from granframe.tools.bench import median_time  # noqa: E402
from granframe.model.exact import bkw  # noqa: E402
from granframe.tools.studykit import (command, finish, read_summary, save_figure, write_csv,  # noqa: E402
                                write_summary)
from granframe.testing import heated_maxwell_error  # noqa: E402

PRECISIONS = ("float64", "float32")
REFERENCE_N = 48


def _sphere(dimension, rule):
    """('circle', M), ('product', n) or ('lebedev', order) -> a surface quadrature."""
    kind, size = rule
    if kind == "circle":
        return gf.CircleTrapezoid(size)
    return gf.SphereProduct(size) if kind == "product" else gf.Lebedev(size)


def _rule_label(rule, dimension) -> str:
    kind, size = rule
    points = _sphere(dimension, rule).n_points
    return {"circle": f"circle M={size}", "product": f"product n={size} (M={points})",
            "lebedev": f"Lebedev {size} (M={points})"}[kind]


# -- scenes ----------------------------------------------------------------------------------
def _bkw_problem(dimension):
    def problem(n_modes):
        grid = gf.VelocityGrid(dimension, n_modes, 5.0)
        f, dfdt = bkw(grid, 6.5)
        return grid, f, dfdt
    return problem


def _mixture_f(grid):
    f = grid.maxwellian(density=0.6, velocity=[0.8, 0.0, 0.0], temperature=1.0)
    return f + grid.maxwellian(density=0.4, velocity=[-0.9, 0.4, 0.0], temperature=0.6)


HARD_SPHERES_TANH = ("hard_spheres", ("tanh", {"asymptotic_value": 0.2}))
SUPPORT_3D = 4.0


class _Reference:
    """Q on the N = 48 grid, computed once (the coarse grids' points are a subset)."""

    def __init__(self):
        self.q = None

    def __call__(self, n_modes):
        if REFERENCE_N % n_modes:
            raise ValueError(f"N = {n_modes} must divide {REFERENCE_N}")
        if self.q is None:
            fine = gf.VelocityGrid(3, REFERENCE_N, SUPPORT_3D)
            self.q = _operator("fast_spectral", fine, HARD_SPHERES_TANH, 48,
                               ("lebedev", 29), "float64")(_mixture_f(fine))
        grid = gf.VelocityGrid(3, n_modes, SUPPORT_3D)
        step = REFERENCE_N // n_modes
        return grid, _mixture_f(grid), self.q[::step, ::step, ::step]


def _operator(method, grid, physics, radial, rule, precision):
    kernel, (law, params) = physics
    backend = gf.array_backend(preferred_backend())
    kernel, law = gf.collision_kernel(kernel), gf.restitution_law(law, **params)
    if method == "direct_spectral":
        return gf.collision_operator(method, grid, kernel, law, backend=backend)
    return gf.collision_operator(method, grid, kernel, law, backend=backend,
                                 radial_points=radial, sphere=_sphere(grid.dimension, rule),
                                 precision=precision)


MAXWELL_ELASTIC = ("maxwell", ("constant", {"value": 1.0}))


def scenes(quick: bool) -> dict:
    """Each scene: kind, physics, problem and the configurations swept."""
    def product(direct_sizes, sizes, radials, rules):
        fast = [dict(method="fast_spectral", N=n, N_rho=r, rule=s, precision=p)
                for n, r, s, p in itertools.product(sizes, radials, rules, PRECISIONS)]
        direct = [dict(method="direct_spectral", N=n, N_rho=None, rule=None, precision="float64")
                  for n in direct_sizes]
        return fast + direct

    if quick:
        return {
            "bkw_2d": dict(kind="evaluation", physics=MAXWELL_ELASTIC, problem=_bkw_problem(2),
                           configs=product((16,), (16, 32), (16,), [("circle", 16)])),
            "heated_2d": dict(kind="solution", dimension=2, support=12.0, T0=8.0,
                              configs=[dict(method="fast_spectral", N=32, N_rho=16,
                                            rule=("circle", 8), precision=p, dt=0.1)
                                       for p in PRECISIONS]),
        }
    lebedev = [("lebedev", 7), ("lebedev", 11), ("lebedev", 17)]
    product_rules = [("product", 2), ("product", 4), ("product", 6)]
    return {
        "bkw_2d": dict(kind="evaluation", physics=MAXWELL_ELASTIC, problem=_bkw_problem(2),
                       configs=product((16, 24, 32), (16, 24, 32, 48, 64), (10, 20, 40),
                                       [("circle", m) for m in (8, 16, 32)])),
        "bkw_3d": dict(kind="evaluation", physics=MAXWELL_ELASTIC, problem=_bkw_problem(3),
                       configs=product((8, 12, 16), (12, 16, 24, 32, 48), (10, 20, 30),
                                       product_rules + lebedev)),
        "hard_spheres_tanh_3d": dict(
            kind="evaluation", physics=HARD_SPHERES_TANH, problem=_Reference(),
            configs=product((8, 12, 16), (12, 16, 24), (10, 20, 30),
                            product_rules + lebedev)),
        "heated_2d": dict(kind="solution", dimension=2, support=12.0, T0=8.0, configs=[
            dict(method="fast_spectral", N=n, N_rho=r, rule=("circle", m), precision=p, dt=dt)
            for n, r, m, p, dt in itertools.product((32, 48, 64), (16, 32), (8, 16, 32),
                                                     PRECISIONS, (0.01, 0.02, 0.05))]),
        "heated_3d": dict(kind="solution", dimension=3, support=5.0, T0=1.5, configs=[
            dict(method="fast_spectral", N=n, N_rho=r, rule=s, precision=p, dt=dt)
            for n, r, s, p, dt in itertools.product(
                (16, 24, 32), (16, 30), [("product", 2), ("product", 4), ("lebedev", 11)],
                PRECISIONS, (0.05, 0.1))]),
    }


# -- measurements ----------------------------------------------------------------------------
def measure_evaluation(scene: dict, config: dict, repeats: int) -> dict:
    """Error max |Q - Q_ref| / max |Q_ref| at the grid points and the time of one evaluation."""
    grid, f, reference = scene["problem"](config["N"])
    start = time.perf_counter()
    operator = _operator(config["method"], grid, scene["physics"], config["N_rho"],
                         config["rule"], config["precision"])
    precompute = time.perf_counter() - start
    q = operator(f)
    error = float(numpy.abs(q - reference).max() / numpy.abs(reference).max())
    seconds = median_time(lambda: operator(f), repeats, operator.backend)
    return dict(error=error, seconds=seconds, precompute_s=precompute)


def measure_solution(scene: dict, config: dict) -> dict:
    """Max relative temperature error over t in [0, 2] and the wall time of the run
    (operator set-up included)."""
    grid = gf.VelocityGrid(scene["dimension"], config["N"], scene["support"])
    start = time.perf_counter()
    operator = _operator("fast_spectral", grid, ("maxwell", ("constant", {"value": 0.5})),
                         config["N_rho"], config["rule"], config["precision"])
    precompute = time.perf_counter() - start
    steps = round(2.0 / config["dt"])
    error, _ = heated_maxwell_error(operator, 0.5, initial_temperature=scene["T0"],
                                    time_step=config["dt"], steps=steps)
    return dict(error=float(error), seconds=time.perf_counter() - start,
                precompute_s=precompute)


def pareto(records, rtol: float = 0.1) -> list[bool]:
    """True for the configurations on the Pareto front of (cost, error).

    r is dominated by a strictly cheaper o whose error is at most (1 + rtol) times r's
    (errors that close are the same for a user), or by an equally costly o with a smaller
    error. The tolerance keeps configurations that buy only round-off off the front.
    """
    def dominates(o, r):
        if o["seconds"] < r["seconds"]:
            return o["error"] <= (1 + rtol) * r["error"]
        return o["seconds"] == r["seconds"] and o["error"] < r["error"]

    return [not any(dominates(o, r) for o in records if o is not r) for r in records]


TARGETS = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7)


def cheapest(rows, targets=TARGETS) -> dict:
    """For each target error, the cheapest configuration that meets it (None if none)."""
    chosen = {}
    for target in targets:
        meeting = [r for r in rows if float(r["error"]) <= target]
        best = min(meeting, key=lambda r: float(r["seconds"])) if meeting else None
        chosen[f"{target:.0e}"] = None if best is None else {
            k: best[k] for k in FIELDS if k not in ("scene", "pareto")}
    return chosen


def reference_check() -> dict:
    """The hard-sphere reference against the same N = 48 operator with more quadrature
    (N_rho = 64, Lebedev degree 41): its own quadrature error."""
    grid = gf.VelocityGrid(3, REFERENCE_N, SUPPORT_3D)
    f = _mixture_f(grid)
    finer = _operator("fast_spectral", grid, HARD_SPHERES_TANH, 64, ("lebedev", 41),
                      "float64")(f)
    reference = _Reference()
    reference(REFERENCE_N)
    return {"N": REFERENCE_N, "finer_quadrature": "N_rho = 64, Lebedev 41",
            "max_rel_difference": float(numpy.abs(reference.q - finer).max()
                                        / numpy.abs(finer).max())}


# -- report ----------------------------------------------------------------------------------
FIELDS = ["scene", "method", "N", "N_rho", "rule", "precision", "dt", "error", "seconds",
          "precompute_s", "pareto"]


def _row(name, scene, config, result):
    dimension = scene.get("dimension") or (2 if name.endswith("2d") else 3)
    return {"scene": name, "method": config["method"], "N": config["N"],
            "N_rho": config["N_rho"] or "",
            "rule": _rule_label(config["rule"], dimension) if config["rule"] else "",
            "precision": config["precision"], "dt": config.get("dt", ""),
            "error": max(result["error"], 1e-16), "seconds": result["seconds"],
            "precompute_s": result["precompute_s"]}


#: What each scene's figure says it is: physics, data and reference (all dimensionless).
CAPTIONS = {
    "bkw_2d": "2D elastic Maxwell molecules (e = 1, kernel exponent λ = 0), BKW solution at "
              "t = 6.5, S = 5; reference: its exact ∂f/∂t",
    "bkw_3d": "3D elastic Maxwell molecules (e = 1, kernel exponent λ = 0), BKW solution at "
              "t = 6.5, S = 5; reference: its exact ∂f/∂t",
    "hard_spheres_tanh_3d": "3D hard spheres (kernel exponent λ = 1), tanh restitution law "
                            "e0 = 0.2, f0 two Maxwellians, S = 4; reference: fast operator at "
                            f"N = {REFERENCE_N}, N_ρ = 48, Lebedev 29",
    "heated_2d": "2D heated Maxwell molecules (λ = 0), e = 0.5, heat bath τ = 0.1, T0 = 8, "
                 "S = 12, RK4 to t = 2; reference: the exact temperature law",
    "heated_3d": "3D heated Maxwell molecules (λ = 0), e = 0.5, heat bath τ = 0.1, T0 = 1.5, "
                 "S = 5, RK4 to t = 2; reference: the exact temperature law",
}


def _swept(rows) -> str:
    """The values each swept setting takes in ``rows``, for the caption."""
    def values(key, numeric=True):
        found = {r[key] for r in rows if r[key] not in ("", None)}
        return ", ".join(f"{v:g}" if numeric else str(v)
                         for v in sorted(found, key=lambda v: (str(type(v)), v)))
    parts = [f"N ∈ {{{values('N')}}}", f"N_ρ ∈ {{{values('N_rho')}}}"]
    rules = values("rule", numeric=False)
    if rules:
        parts.append(f"quadrature ∈ {{{rules}}}")
    parts.append(f"precision ∈ {{{values('precision', numeric=False)}}}")
    if any(r["dt"] not in ("", None) for r in rows):
        parts.append(f"time step Δt ∈ {{{values('dt')}}}")
    return "swept: " + "; ".join(parts) + f"; {len(rows)} configurations"


def _log_ticks(axis, values) -> None:
    """Labels at the powers of ten only, and at 2 and 5 times them where ``values`` span
    less than two decades (no crowded minor labels)."""
    values = numpy.asarray(values, dtype=float)
    if numpy.log10(values.max() / values.min()) < 2:
        axis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(ticker.FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(ticker.NullFormatter())


def _figure(name, scene, rows, out):
    fig, ax = plt.subplots(figsize=(8, 6), constrained_layout=True)
    styles = {("fast_spectral", "float64"): ("o", "C0", "fast_spectral, float64"),
              ("fast_spectral", "float32"): ("s", "C1", "fast_spectral, float32"),
              ("direct_spectral", "float64"): ("^", "C2", "direct_spectral, float64")}
    for key, (marker, colour, label) in styles.items():
        chosen = [r for r in rows if (r["method"], r["precision"]) == key]
        if chosen:
            ax.loglog([r["seconds"] for r in chosen], [r["error"] for r in chosen], marker,
                      color=colour, ms=4, alpha=0.6,
                      label=f"{label} ({len(chosen)} configuration"
                            f"{'s' if len(chosen) > 1 else ''})")
    front = sorted((r for r in rows if r["pareto"]), key=lambda r: r["seconds"])
    ax.loglog([r["seconds"] for r in front], [r["error"] for r in front], "k-", lw=1.2,
              drawstyle="steps-post", label="Pareto front (no cheaper configuration "
                                            "within 10 % of its error)")
    ax.loglog([r["seconds"] for r in front], [r["error"] for r in front], "kD", ms=3.5,
              mfc="none", label="configurations on the front")
    if scene["kind"] == "evaluation":
        cost = "wall time of one evaluation of Q, median (s)"
        what = r"relative error of Q, $\max|Q - Q_{ref}|\,/\,\max|Q_{ref}|$ (dimensionless)"
    else:
        cost = "wall time to solution, t from 0 to 2, set-up included (s)"
        what = r"temperature error $\max_{t \in [0, 2]} |T/T_{exact} - 1|$ (dimensionless)"
    lines = [f"{name}: {CAPTIONS.get(name, '')}", _swept(rows),
             "errors floored at 1e-16 for the log scale; all quantities but the wall time "
             "dimensionless"]
    ax.set(xlabel=cost, ylabel=what,
           title="\n".join(textwrap.fill(line, 118) for line in lines))
    ax.title.set_fontsize(8)
    _log_ticks(ax.xaxis, [r["seconds"] for r in rows])
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, out / f"{name}.png")


def run(out: pathlib.Path, quick: bool = False, only=None) -> dict:
    """Measure every scene (or those in ``only``), write ``<scene>.csv`` and ``<scene>.png``,
    and update ``summary.json``."""
    out.mkdir(parents=True, exist_ok=True)
    summary = read_summary(out, only)
    repeats = 3 if quick else 7
    for name, scene in scenes(quick).items():
        if only and name not in only:
            continue
        started = time.perf_counter()
        rows = []
        for config in scene["configs"]:
            result = (measure_evaluation(scene, config, repeats) if scene["kind"] == "evaluation"
                      else measure_solution(scene, config))
            rows.append(_row(name, scene, config, result))
        for row, flag in zip(rows, pareto(rows)):
            row["pareto"] = flag
        write_csv(out / f"{name}.csv", rows, FIELDS)
        _figure(name, scene, rows, out)
        float32 = [r["error"] for r in rows if r["precision"] == "float32"]
        summary[name] = {
            "configurations": len(rows), "wall_seconds": time.perf_counter() - started,
            "front": [{k: r[k] for k in FIELDS if k not in ("scene", "pareto")}
                      for r in sorted(rows, key=lambda r: r["seconds"]) if r["pareto"]],
            "cheapest_for_target": cheapest(rows),
            "best_error_float64": min(r["error"] for r in rows if r["precision"] == "float64"),
            "best_error_float32": min(float32) if float32 else None,
        }
        print(f"{name}: {len(rows)} configurations in {summary[name]['wall_seconds']:.0f} s",
              flush=True)
    if not quick and (not only or "hard_spheres_tanh_3d" in only):
        summary["reference_check"] = reference_check()
    write_summary(out, summary)
    return summary


main = command(run, __doc__, "two small scenes (smoke test)", parts="scene")


if __name__ == "__main__":
    raise SystemExit(finish(main))
