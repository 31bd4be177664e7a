"""Where time integrators fail: stability maps over (dt, eps) and (dt, tau) (docs/stability.md).

    python studies/stability_map.py --out docs/figures/stability      # about 18 min, 2 cores
    python studies/stability_map.py --out /tmp/stability --quick      # seconds (CI)

2D Maxwell molecules on S = 4 (N_rho = 16, M = 16), 200 fixed steps per point.

- ``collisions``: d_t f = Q(f, f)/eps, elastic (e = 1), no heat bath, from two Maxwellians
  (densities 0.6 / 0.4, drifts (0.8, 0) / (-1.2, 0.3), T = 0.8 / 0.5). The temperature is
  conserved exactly, so T(t) = T0 is the reference. Schemes: rk4, if_rk4, penalised_euler,
  penalised_ars222 over dt in [1e-3, 1] and eps in [1e-4, 1]; N = 32.
- ``heat_bath``: d_t f = Q(f, f) + 0.1 Delta f, e = 0.5, from the same data; the reference
  is the exact heated Maxwell law. Schemes: rk4 and if_rk4 over dt and N from 16 to 128:
  refining the grid raises the heat bath's stiffness tau max|k|^2 as N^2 (tau is kept
  fixed so that the heated state T_inf = 1.07 fits the box at every point).

A point is *unstable* when f stops being finite or max |f| exceeds 10 times the larger of
max f0 and the peak of the Maxwellian at the exact temperature (so that a gas that cools
and concentrates is not called unstable), *inaccurate* when stable with
max |T/T_exact - 1| > 1e-3, *accurate* otherwise. Each map
draws the predicted explicit limit of :mod:`granframe.stepping.stability`, dt = interval / rate.
"""

from __future__ import annotations

import math
import pathlib
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
from matplotlib import ticker  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

import granframe as gf  # noqa: E402
from granframe.equations.homogeneous import HomogeneousBoltzmann  # noqa: E402
from granframe.model.exact import heated_maxwell_temperature  # noqa: E402
from granframe.stepping.stability import step_limit  # noqa: E402
from granframe.tools.studykit import (command, finish, read_summary, save_figure, write_csv,  # noqa: E402
                                write_summary)

STEPS = 200
ACCURATE = 1e-3


def _equation(restitution, knudsen, heat_bath, n_modes=32):
    grid = gf.VelocityGrid(2, n_modes, 4.0)
    operator = gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel("maxwell"),
        gf.restitution_law("constant", value=restitution),
        backend=gf.array_backend("numpy", threads=1), radial_points=16,
        sphere=gf.CircleTrapezoid(16))
    f0 = grid.maxwellian(0.6, [0.8, 0.0], 0.8) + grid.maxwellian(0.4, [-1.2, 0.3], 0.5)
    return grid, HomogeneousBoltzmann(operator, heat_bath, knudsen), f0


def classify(scheme, restitution, knudsen, heat_bath, dt, steps=STEPS, n_modes=32) -> dict:
    """Run ``steps`` fixed steps; return the class, the worst temperature error and the
    predicted explicit limit."""
    grid, equation, f = _equation(restitution, knudsen, heat_bath, n_modes)
    integrator = gf.time_integrator(scheme)
    limit = step_limit(integrator, equation, f)
    rho, T0, peak = grid.mass(f), grid.temperature(f), float(numpy.abs(f).max())
    worst, verdict = 0.0, "accurate"
    for i in range(steps):
        f = integrator.step(equation, i * dt, f, dt)
        exact = heated_maxwell_temperature((i + 1) * dt, T0, restitution, heat_bath,
                                           rho / knudsen)
        bound = 10 * max(peak, rho / (2 * math.pi * exact))
        if not numpy.all(numpy.isfinite(f)) or numpy.abs(f).max() > bound:
            verdict = "unstable"
            break
        worst = max(worst, abs(grid.temperature(f) / exact - 1))
    if verdict != "unstable" and worst > ACCURATE:
        verdict = "inaccurate"
    bounded = limit is not None and math.isfinite(limit.limit)
    return {"verdict": verdict, "T_error": worst if verdict != "unstable" else None,
            "predicted_limit": limit.limit if bounded else None,
            "limited_by": limit.dominant if bounded else None}


def maps(quick: bool) -> dict:
    if quick:
        return {"collisions": dict(schemes=("rk4", "penalised_euler"), axis="eps",
                                   values=(1e-3, 1.0), dts=(0.01, 0.1), steps=20)}
    dts = tuple(numpy.logspace(-3, 0, 10))
    return {
        "collisions": dict(schemes=("rk4", "if_rk4", "penalised_euler", "penalised_ars222"),
                           axis="eps", values=tuple(numpy.logspace(-4, 0, 9)), dts=dts,
                           steps=STEPS),
        "heat_bath": dict(schemes=("rk4", "if_rk4"), axis="N",
                          values=(16, 24, 32, 48, 64, 96, 128), dts=dts, steps=STEPS),
    }


MARKERS = {"accurate": ("o", "C2"), "inaccurate": ("s", "C1"), "unstable": ("x", "C3")}


#: The axis label of each map's swept parameter.
AXES = {"eps": "Knudsen number ε (dimensionless)", "N": "number of modes N per dimension"}
#: What each map solves.
PHYSICS = {
    "collisions": r"$\partial_t f = Q(f, f)/\varepsilon$, elastic (e = 1), no heat bath, N = 32",
    "heat_bath": r"$\partial_t f = Q(f, f) + \tau\Delta_v f$, e = 0.5, heat bath τ = 0.1, "
                 "ε = 1",
}
LEGEND = {"accurate": f"accurate: max |T/T_exact - 1| ≤ {ACCURATE:g}",
          "inaccurate": f"inaccurate: stable, max |T/T_exact - 1| > {ACCURATE:g}",
          "unstable": "unstable: f not finite, or max |f| > 10 × max(max f0, peak of the "
                      "Maxwellian at the exact T)"}


def _figure(name, spec, rows, out):
    schemes = spec["schemes"]
    fig, axes = plt.subplots(1, len(schemes), figsize=(4.3 * len(schemes), 4.9),
                             constrained_layout=True, sharey=True, squeeze=False)
    for ax, scheme in zip(axes[0], schemes):
        chosen = [r for r in rows if r["scheme"] == scheme]
        for verdict, (marker, colour) in MARKERS.items():
            pts = [r for r in chosen if r["verdict"] == verdict]
            ax.loglog([r[spec["axis"]] for r in pts], [r["dt"] for r in pts], marker,
                      color=colour, label=LEGEND[verdict])
        predicted = sorted((r[spec["axis"]], r["predicted_limit"]) for r in chosen
                           if r["predicted_limit"] is not None and r["dt"] == chosen[0]["dt"])
        if predicted:
            x, y = zip(*predicted)
            ax.loglog(x, y, "k--", lw=1, label="predicted explicit limit Δt = interval / rate")
        ax.set(xlabel=AXES[spec["axis"]], title=f"integrator {scheme}")
        if spec["axis"] == "N":     # the swept N, without crowded minor labels
            ax.set_xticks(spec["values"], [str(v) for v in spec["values"]])
            ax.xaxis.set_minor_formatter(ticker.NullFormatter())
        ax.set_ylim(min(spec["dts"]) / 1.5, max(spec["dts"]) * 1.5)
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("time step Δt (dimensionless)")
    handles = [Line2D([], [], ls="none", marker=marker, color=colour, label=LEGEND[verdict])
               for verdict, (marker, colour) in MARKERS.items()]
    handles.append(Line2D([], [], color="k", ls="--", lw=1,
                          label="predicted explicit limit Δt = interval / rate"))
    fig.legend(handles=handles, loc="outside lower center", ncols=2 if len(schemes) > 2 else 1,
               fontsize=8)
    fig.suptitle(f"{name}: {PHYSICS.get(name, '')}\n2D Maxwell molecules (kernel exponent "
                 f"λ = 0), S = 4, N_ρ = 16, circle M = 16, f0 two Maxwellians\n"
                 f"{spec['steps']} fixed steps per point, one marker per run; all quantities "
                 "dimensionless", fontsize=10)
    save_figure(fig, out / f"{name}.png")


def run(out: pathlib.Path, quick: bool = False, only=None) -> dict:
    """Classify every point of every map (or those in ``only``); write ``<map>.csv``,
    ``<map>.png`` and update ``summary.json``."""
    out.mkdir(parents=True, exist_ok=True)
    summary = read_summary(out, only)
    for name, spec in maps(quick).items():
        if only and name not in only:
            continue
        started = time.perf_counter()
        rows = []
        for scheme in spec["schemes"]:
            for value in spec["values"]:
                for dt in spec["dts"]:
                    if spec["axis"] == "eps":
                        result = classify(scheme, 1.0, value, 0.0, dt, spec["steps"])
                    else:
                        result = classify(scheme, 0.5, 1.0, 0.1, dt, spec["steps"],
                                          n_modes=value)
                    rows.append({"scheme": scheme, spec["axis"]: float(value), "dt": float(dt),
                                 **result})
        fields = ["scheme", spec["axis"], "dt", "verdict", "T_error", "predicted_limit",
                  "limited_by"]
        write_csv(out / f"{name}.csv", rows, fields)
        _figure(name, spec, rows, out)
        summary[name] = {
            "wall_seconds": time.perf_counter() - started,
            "counts": {scheme: {v: sum(1 for r in rows if r["scheme"] == scheme
                                       and r["verdict"] == v) for v in MARKERS}
                       for scheme in spec["schemes"]},
            # points where the prediction and the observation disagree
            "unpredicted_blow_ups": [r for r in rows if r["verdict"] == "unstable" and (
                r["predicted_limit"] is None or r["dt"] <= r["predicted_limit"])],
            "stable_above_prediction": [r for r in rows if r["verdict"] != "unstable"
                                        and r["predicted_limit"] is not None
                                        and r["dt"] > r["predicted_limit"]],
        }
        print(f"{name}: {len(rows)} points in {summary[name]['wall_seconds']:.0f} s", flush=True)
    write_summary(out, summary)
    return summary


main = command(run, __doc__, "four points (smoke test)", parts="map")


if __name__ == "__main__":
    raise SystemExit(finish(main))
