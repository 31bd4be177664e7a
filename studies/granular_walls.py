r"""A granular gas heated by two diffuse walls (no gravity), 3D inelastic hard spheres,
against the granular Navier-Stokes equations with the first-Sonine coefficients.

Both walls at T_w = 1, x in [0, 1], mean density 1; eps = sqrt(2) Kn (lambda_mfp =
eps / (sqrt 2 rho), docs/granular.md). The steady state has u = 0 and, to Navier-Stokes
order, a uniform pressure p = rho T; the energy balance

    d q / dx = -(3/2) zeta rho T,     q = -kappa dT/dx - mu d rho/dx = -kappa_0 (kappa* - mu*) dT/dx

(with rho = p/T: mu d rho/dx = -mu (p/T^2) dT/dx = -kappa_0 mu* dT/dx, since mu =
kappa_0 T mu*/n), kappa_0 = (75/64) eps sqrt(pi T), zeta = nu_0 zeta*, nu_0 = 16 n sqrt(T) /
(5 eps sqrt(pi)). With w = T^{3/2} it is w'' = C p^2 w^{-1/3},
C = 6.144 zeta* / (pi eps^2 (kappa* - mu*)); in units of the gas at the wall (T_b, rho_b =
p/T_b), W = (T/T_b)^{3/2} solves

    W'' = Lambda W^{-1/3},  W(0) = W(1) = 1,   Lambda = C rho_b^2,

and the mass fixes rho_b: rho_b int_0^1 W^{-2/3} dx = 1. So T_min/T_b and rho_max/rho_b
follow from e and eps alone, whatever the temperature jump T_w - T_b at the walls: those
are compared with the kinetic run (T_b and rho_b its profiles extrapolated to the walls);
:func:`granframe.theory.walls.heated_walls_profile` solves the problem.

Run: ``python studies/granular_walls.py --out DIR [--restitution 0.9] [--knudsen 0.2]``;
a run of hours stores f every ``--snapshot-every STEPS`` steps and continues where it was
killed with ``--resume`` (bitwise the run that was not killed).
"""

from __future__ import annotations

import math

import numpy
import scipy.optimize

import granframe
from granframe.backends import NumpyBackend
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.theory.walls import heated_walls_profile
from granframe.tools.analysis import energy_balance
from granframe.tools.studykit import (cfl_time_step, draw, finish, json_text, number,
                                      output_folder, parse_study, print_table, run_study,
                                      save_figure, study_arguments)
from granframe.velocity.moments import FieldMoments


def description(e: float, knudsen: float, cells: int, n_modes: int, support: float,
                final: float, time_step: float, quadrature: str = "auto",
                snapshot_interval: float | None = None) -> RunDescription:
    """3D hard spheres between diffuse walls at T_w = 1, from the Maxwellian of T = 1; f is
    stored every ``snapshot_interval`` (None: at the end only), the points a run can be
    resumed from."""
    return RunDescription(
        title=f"heated walls, e = {e:g}, Kn = {knudsen:g}, {cells} cells, N = {n_modes}",
        grid={"dimension": 3, "n_modes": n_modes, "support_radius": support},
        kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial={"name": "maxwellian"}, integrator="ssp_rk2", conservative=True,
        operator={"name": "fast_spectral", "quadrature": quadrature},
        knudsen=math.sqrt(2.0) * knudsen, time_step=time_step, final_time=final,
        output={"snapshot_interval": snapshot_interval or final},
        space={"cells": cells, "reconstruction": "muscl",
               "left": {"name": "diffuse", "temperature": 1.0},
               "right": {"name": "diffuse", "temperature": 1.0}})


def at_walls(values, cells: int) -> float:
    """The profile's value at x = 0 and x = 1 (mean of both), by the quadratic through the
    first three cell averages (their centres) extrapolated to the wall."""
    centres = (numpy.arange(3) + 0.5) / cells
    ends = []
    for side in (values[:3], values[::-1][:3]):
        ends.append(numpy.polyval(numpy.polyfit(centres, side, 2), 0.0))
    return float(numpy.mean(ends))


def steady_estimate(times, values) -> dict:
    """The steady value of a ratio that still relaxes when the run ends (at t_f): v(t) =
    a + b exp(-k t) fitted by least squares to the values over t >= t_f/2 (``steady`` = a)
    and over t >= t_f/3; ``spread`` = the two fits' difference in a, the estimate's
    uncertainty. A fitted rate k outside [0.2, 10] (per unit time) is no relaxation the
    run has followed (a ratio not yet levelling off, or noise): NaN, as for a failed fit."""
    estimates = []
    for start in (times[-1] / 2, times[-1] / 3):
        keep = times >= start
        t, v = times[keep], values[keep]
        try:
            (a, _, rate), _ = scipy.optimize.curve_fit(
                lambda s, a, b, k: a + b * numpy.exp(-k * (s - t[0])), t, v,
                p0=(v[-1], v[0] - v[-1], 1.0),
                bounds=([-numpy.inf, -numpy.inf, 0.1], [numpy.inf, numpy.inf, 20.0]))
        except (RuntimeError, ValueError):
            return {"steady": math.nan, "spread": math.nan}
        if not 0.2 <= rate <= 10.0:
            return {"steady": math.nan, "spread": math.nan}
        estimates.append(float(a))
    return {"steady": estimates[0], "spread": abs(estimates[0] - estimates[1])}


def kinetic(ds, operator, knudsen: float) -> dict:
    """T_min/T_b, rho_max/rho_b (and their :func:`steady_estimate` from their history:
    the runs end before the gas is steady), the jump T_w - T_b and the energy budget of a
    run, and ``fields error by cell``: the velocity-resolution indicator of every cell's
    final f (the change of its fields without the outermost shell of modes,
    :meth:`~granframe.velocity.moments.FieldMoments.resolution`), of which the run's report
    names only the largest."""
    cells = ds.sizes["x"]
    t_b = at_walls(ds.temperature.values[-1], cells)
    rho_b = at_walls(ds.density.values[-1], cells)
    budget = energy_balance(ds, operator, math.sqrt(2.0) * knudsen)
    fields = FieldMoments(operator.grid, 1.0 / cells).resolution(ds.f.values[-1],
                                                                 NumpyBackend())[:, 4]
    errors = [float(f"{value:.3g}") for value in fields]
    ratios = {}
    for name, profiles, extreme in (("T_min/T_b", ds.temperature.values, numpy.min),
                                    ("rho_max/rho_b", ds.density.values, numpy.max)):
        history = numpy.array([extreme(p) / at_walls(p, cells) for p in profiles])
        estimate = steady_estimate(ds.time.values, history)
        ratios |= {name: float(history[-1]), f"{name} steady": estimate["steady"],
                   f"{name} steady spread": estimate["spread"]}
    return {"T_b": t_b, "rho_b": rho_b, **ratios, "jump": 1.0 - t_b,
            "heat": budget["heat"], "dissipation": budget["dissipation"],
            "unsteadiness": budget["unsteadiness"], "residual": budget["residual"],
            "fields error by cell": errors}


def figure(stores, path) -> None:
    """T/T_b and rho/rho_b of each run (cell averages, markers) against the Navier-Stokes
    profile of its e and Kn (lines)."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="tight")
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        description = RunDescription.from_toml(ds.attrs["description_toml"])
        e = description.restitution.params["value"]
        knudsen = description.knudsen / math.sqrt(2.0)
        cells = ds.sizes["x"]
        temperature, density = ds.temperature.values[-1], ds.density.values[-1]
        t_b, rho_b = at_walls(temperature, cells), at_walls(density, cells)
        theory = heated_walls_profile(e, knudsen)
        y = theory["distance"]
        x = numpy.concatenate([0.5 - y[::-1], 0.5 + y[1:]])
        profile = numpy.concatenate([theory["T/T_b"][::-1], theory["T/T_b"][1:]])
        label = f"e = {e:g}, Kn = {knudsen:g}, N = {description.grid.n_modes}, {cells} cells"
        line, = axes[0].plot(ds.x.values, temperature / t_b, "o", ms=4, label=label)
        axes[0].plot(x, profile, "-", color=line.get_color(), lw=1)
        axes[1].plot(ds.x.values, density / rho_b, "o", ms=4, color=line.get_color())
        axes[1].plot(x, 1.0 / profile, "-", color=line.get_color(), lw=1)
    axes[0].set_ylabel("T / T_b")
    axes[1].set_ylabel("rho / rho_b")
    for ax in axes:
        ax.set_xlabel("x")
    low, high = axes[1].get_ylim()          # room above the profiles for the legend
    axes[1].set_ylim(low, high + 0.35 * (high - low))
    axes[1].legend(*axes[0].get_legend_handles_labels(), fontsize=7, loc="upper right")
    fig.suptitle("heated walls, 3D hard spheres: granframe (markers), granular "
                 "Navier-Stokes (lines); T_b, rho_b at the walls", fontsize=9)
    save_figure(fig, path, dpi=120)


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=24, cells=12, final=3.0,
                             quick={"cells": 6, "final": 0.3})
    parser.add_argument("--knudsen", type=number(0.0), default=0.2, help="the Knudsen number")
    parser.add_argument("--steps", type=number(1, kind=int, low_open=False), default=None,
                        help="steps to the final time (default: the transport's CFL limit)")
    parser.add_argument("--snapshot-every", type=number(1, kind=int, low_open=False),
                        default=None, metavar="STEPS",
                        help="store f every STEPS steps (default: at the end only): the "
                             "points from which --resume continues a killed run")
    parser.add_argument("--resume", action="store_true",
                        help="continue the run in OUT's store where it stopped (a new one "
                             "if there is none) instead of starting it again")
    args = parse_study(parser, argv)
    out = output_folder(args, figure, "walls.png")
    if out is None:
        return
    e, kn = args.restitution, args.knudsen
    grid = {"n_modes": args.n_modes, "support_radius": args.support}
    time_step = (args.final / args.steps if args.steps
                 else cfl_time_step(args.cells, args.final, grid))
    interval = None if args.snapshot_every is None else args.snapshot_every * time_step
    run = Simulation(description(e, kn, args.cells, args.n_modes, args.support, args.final,
                                 time_step, args.quadrature, interval))
    store = out / f"walls_e{e:g}_kn{kn:g}_c{args.cells}_n{args.n_modes}.zarr"
    result = run_study(run, store, args, **({"resume": True} if args.resume
                                            else {"overwrite": True}))
    seconds = result.wall_seconds
    ds = granframe.open_run(store, time_axis="steps")
    measured = kinetic(ds, run.problem.operator, kn)
    theory = heated_walls_profile(e, kn)
    row = {"e": e, "Kn": kn, "cells": args.cells, "N": args.n_modes, "S": args.support,
           "quadrature": args.quadrature, "dt": time_step, "final": args.final,
           "seconds": seconds,
           "steps": int(ds.sizes["time"]) - 1, **measured,
           "NS rho_b": theory["rho_b"], "NS T_min/T_b": theory["T_min/T_b"],
           "NS rho_max/rho_b": theory["rho_max/rho_b"],
           "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]}
    print_table([row], {"e": "g", "Kn": "g", "N": "d", "cells": "d", "seconds": ".0f",
                        "T_b": ".5g", "rho_b": ".5g", "T_min/T_b": ".5g",
                        "NS T_min/T_b": ".5g", "rho_max/rho_b": ".5g",
                        "NS rho_max/rho_b": ".5g"})
    (store.with_suffix(".json")).write_text(json_text(row, indent=1))
    print(f"table: {store.with_suffix('.json')}")
    draw(figure, [store], out / "walls.png")


if __name__ == "__main__":
    raise SystemExit(finish(main))
