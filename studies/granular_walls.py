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

import argparse
import math

import numpy

import granframe
from granframe.backends import NumpyBackend
from granframe.run.description import RunDescription
from granframe.run.refinement import grid_convergence
from granframe.run.runner import Simulation
from granframe.theory.walls import heated_walls_jump, heated_walls_profile
from granframe.tools.analysis import energy_balance
from granframe.tools.studykit import (cfl_time_step, draw, finish, json_text, number,
                                      output_folder, parse_study, print_table, relaxation_fit,
                                      run_study, save_figure, study_arguments)
from granframe.velocity.moments import FieldMoments


def description(e: float, knudsen: float, cells: int, n_modes: int, support: float,
                final: float, time_step: float, quadrature: str = "auto",
                snapshot_interval: float | None = None,
                start: str = "maxwellian") -> RunDescription:
    """3D hard spheres between diffuse walls at T_w = 1, from the Maxwellian of T = 1
    (``start = "maxwellian"``) or from the local Maxwellian of the Navier-Stokes profile
    with the temperature jump (``"navier-stokes"``,
    :func:`~granframe.theory.walls.heated_walls_maxwellian`: the run then relaxes in a few
    mean free times, not in the heat-conduction time); f is stored every
    ``snapshot_interval`` (None: at the end only), the points a run can be resumed from."""
    initial = ({"name": "maxwellian"} if start == "maxwellian" else
               {"name": "space_function",
                "function": "granframe.theory.walls:heated_walls_maxwellian",
                "params": {"restitution": e, "knudsen": knudsen}})
    return RunDescription(
        title=f"heated walls, e = {e:g}, Kn = {knudsen:g}, {cells} cells, N = {n_modes}",
        grid={"dimension": 3, "n_modes": n_modes, "support_radius": support},
        kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial=initial, integrator="ssp_rk2", conservative=True,
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
    fit = relaxation_fit(times, values, (times[-1] / 2, times[-1] / 3), 1.0,
                         ([-numpy.inf, -numpy.inf, 0.1], [numpy.inf, numpy.inf, 20.0]),
                         accepted=(0.2, 10.0))
    if fit is None:
        return {"steady": math.nan, "spread": math.nan}
    return {"steady": fit["steady"], "spread": fit["spread"]}


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


def against_jump(ds, e: float, knudsen: float) -> dict:
    """The run's last profile against Navier-Stokes with the temperature jump
    (:func:`~granframe.theory.walls.heated_walls_jump`), which has no free parameter: the
    middle (x = 1/2, linear between the cell centres), the wall cells (mean of both), and
    ``bulk T`` / ``bulk rho``: the largest |kinetic / Navier-Stokes - 1| over the cells whose
    centres are at least 2 lambda_b from both walls (NaN where no cell is: the Knudsen
    layers fill the gap); ``T(1/2) swing``, ``rho(1/2) swing``: half the range of the
    middle's value over the run's last third (the sound the start excites, which the run
    has not damped: the time's share of the error)."""
    theory = heated_walls_jump(e, knudsen)
    cells = ds.sizes["x"]
    x = ds.x.values
    distance = numpy.abs(x - 0.5)
    t_ns = numpy.interp(distance, theory["distance"], theory["temperature"])
    rho_ns = theory["pressure"] / t_ns
    temperature, density = ds.temperature.values[-1], ds.density.values[-1]

    def middle(values):
        return float(numpy.interp(0.5, x, values))

    def wall(values):
        return float(0.5 * (values[0] + values[-1]))

    times = ds.time.values
    late = times >= times[-1] * 2.0 / 3.0
    swings = {}
    for name, history in (("T", ds.temperature.values), ("rho", ds.density.values)):
        middles = numpy.array([numpy.interp(0.5, x, values) for values in history[late]])
        swings[f"{name}(1/2) swing"] = float(0.5 * (middles.max() - middles.min()))
    bulk = numpy.minimum(x, 1.0 - x) >= 2.0 * theory["lambda_b"]
    worst = {}
    for name, kinetic_values, ns in (("T", temperature, t_ns), ("rho", density, rho_ns)):
        worst[f"bulk {name}"] = (float(numpy.max(numpy.abs(kinetic_values[bulk] / ns[bulk]
                                                           - 1.0)))
                                 if bulk.any() else math.nan)
    return {"T(1/2)": middle(temperature), "NS T(1/2)": float(theory["temperature"][0]),
            "rho(1/2)": middle(density), "NS rho(1/2)": float(theory["density"][0]),
            "T wall cell": wall(temperature), "NS T wall cell": wall(t_ns),
            "rho wall cell": wall(density), "NS rho wall cell": wall(rho_ns),
            "NS T_b": theory["T_b"], "lambda_b": theory["lambda_b"],
            "bulk cells": int(bulk.sum()), "cells": cells, **worst, **swings}


#: the numbers of a run against Navier-Stokes with the jump that get error bars from a
#: refinement (:func:`error_bars`)
REFINED = ("T(1/2)", "rho(1/2)", "T wall cell", "rho wall cell")


def error_bars(rows: list[dict], spacings: list) -> dict:
    """Each of :data:`REFINED` over a refinement (``rows`` coarse to fine, ``spacings``
    their h): the finest value, the observed order, the Richardson estimate and the grid
    convergence index (:func:`granframe.run.refinement.grid_convergence`), and the
    Navier-Stokes value beside it."""
    out = {}
    for key in REFINED:
        result = grid_convergence([row[key] for row in rows], spacings)
        out[key] = {name: result[name] for name in ("value", "order", "convergence",
                                                    "extrapolated", "error_bar")}
        out[key]["navier-stokes"] = rows[-1][f"NS {key}"]
    return out


def figure(stores, path) -> None:
    """T and rho of each run (cell averages, markers) against Navier-Stokes with the
    temperature jump of its e and Kn (lines, :func:`against_jump`)."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="tight")
    drawn = set()
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        description = RunDescription.from_toml(ds.attrs["description_toml"])
        e = description.restitution.params["value"]
        knudsen = description.knudsen / math.sqrt(2.0)
        label = (f"e = {e:g}, Kn = {knudsen:g}, N = {description.grid.n_modes}, "
                 f"{ds.sizes['x']} cells")
        line, = axes[0].plot(ds.x.values, ds.temperature.values[-1], "o", ms=4, label=label)
        axes[1].plot(ds.x.values, ds.density.values[-1], "o", ms=4, color=line.get_color())
        if (e, knudsen) in drawn:
            continue
        drawn.add((e, knudsen))
        theory = heated_walls_jump(e, knudsen)
        y = theory["distance"]
        x = numpy.concatenate([0.5 - y[::-1], 0.5 + y[1:]])
        for ax, key in zip(axes, ("temperature", "density")):
            ax.plot(x, numpy.concatenate([theory[key][::-1], theory[key][1:]]), "-",
                    color=line.get_color(), lw=1)
    axes[0].set_ylabel("T")
    axes[1].set_ylabel("rho")
    for ax in axes:
        ax.set_xlabel("x")
    low, high = axes[1].get_ylim()          # room above the profiles for the legend
    axes[1].set_ylim(low, high + 0.35 * (high - low))
    axes[1].legend(*axes[0].get_legend_handles_labels(), fontsize=7, loc="upper right")
    fig.suptitle("heated walls (T_w = 1), 3D hard spheres: granframe (markers), granular "
                 "Navier-Stokes with the temperature jump (lines)", fontsize=9)
    save_figure(fig, path, dpi=120)


def run_member(args, out, n_modes: int, cells: int, time_step: float):
    """One run of the study at (N, cells, dt): its table row and store."""
    e, kn = args.restitution, args.knudsen
    interval = None if args.snapshot_every is None else args.snapshot_every * time_step
    run = Simulation(description(e, kn, cells, n_modes, args.support, args.final,
                                 time_step, args.quadrature, interval, args.start))
    store = out / f"walls_e{e:g}_kn{kn:g}_c{cells}_n{n_modes}.zarr"
    result = run_study(run, store, args, **({"resume": True} if args.resume
                                            else {"overwrite": True}))
    ds = granframe.open_run(store, time_axis="steps")
    theory = heated_walls_profile(e, kn)
    row = {"e": e, "Kn": kn, "cells": cells, "N": n_modes, "S": args.support,
           "quadrature": args.quadrature, "start": args.start, "dt": time_step,
           "final": args.final, "seconds": result.wall_seconds,
           "steps": int(ds.sizes["time"]) - 1, **kinetic(ds, run.problem.operator, kn),
           "NS rho_b": theory["rho_b"], "NS T_min/T_b": theory["T_min/T_b"],
           "NS rho_max/rho_b": theory["rho_max/rho_b"], **against_jump(ds, e, kn),
           "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]}
    (store.with_suffix(".json")).write_text(json_text(row, indent=1))
    return row, store


def refinement(text: str) -> tuple[str, list[int]]:
    """An argparse type: ``n-modes=N1,N2,...`` or ``cells=C1,C2,...``, three or more
    increasing integers (the family of :func:`error_bars`)."""
    name, _, values = text.partition("=")
    try:
        members = [int(v) for v in values.split(",")]
    except ValueError:
        members = []
    if (name not in ("n-modes", "cells") or len(members) < 3
            or any(b <= a for a, b in zip(members[:-1], members[1:])) or members[0] < 1):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not allowed: must be n-modes=N1,N2,N3 or cells=C1,C2,C3, three or "
            "more increasing integers, coarse to fine")
    return name, members


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=24, cells=12, final=3.0,
                             quick={"cells": 6, "final": 0.3})
    parser.add_argument("--knudsen", type=number(0.0), default=0.2, help="the Knudsen number")
    parser.add_argument("--start", choices=("navier-stokes", "maxwellian"),
                        default="navier-stokes",
                        help="the initial data: the local Maxwellian of Navier-Stokes with "
                             "the temperature jump (steady in a few mean free times), or the "
                             "Maxwellian at rest with T = 1 (the heat-conduction time)")
    parser.add_argument("--refine", type=refinement, default=None,
                        metavar="n-modes=N1,N2,N3 | cells=C1,C2,C3",
                        help="run the study at three or more resolutions, coarse to fine, "
                             "all at the finest member's time step, and give its numbers "
                             "error bars (observed order, Richardson, grid convergence index)")
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
    if args.refine is None:
        family, spacings = [(args.n_modes, args.cells)], None
    else:
        name, values = args.refine
        family = [(v, args.cells) if name == "n-modes" else (args.n_modes, v) for v in values]
        spacings = [1.0 / v for v in values]
    time_step = (args.final / args.steps if args.steps else min(
        cfl_time_step(cells, args.final, {"n_modes": n, "support_radius": args.support})
        for n, cells in family))
    rows, stores = [], []
    for n_modes, cells in family:
        row, store = run_member(args, out, n_modes, cells, time_step)
        rows.append(row)
        stores.append(store)
    print_table(rows, {"e": "g", "Kn": "g", "N": "d", "cells": "d", "seconds": ".0f",
                       "T(1/2)": ".5f", "NS T(1/2)": ".5f", "rho(1/2)": ".5f",
                       "NS rho(1/2)": ".5f", "T wall cell": ".5f", "NS T wall cell": ".5f",
                       "bulk T": ".2g", "bulk rho": ".2g", "unsteadiness": ".2g",
                       "residual": ".2g"})
    if spacings is not None:
        bars = error_bars(rows, spacings)
        for key, v in bars.items():
            shown = (f"{v['value']:.5f} ± {v['error_bar']:.2g} (order {v['order']:.3g})"
                     if math.isfinite(v["error_bar"]) else f"{v['value']:.5f}")
            print(f"{key}: {shown}, {v['convergence']}; Navier-Stokes {v['navier-stokes']:.5f}")
        name = (f"walls_e{args.restitution:g}_kn{args.knudsen:g}_refine_{args.refine[0]}"
                f"{'-'.join(map(str, args.refine[1]))}.json")
        (out / name).write_text(json_text({"family": family, "spacings": spacings,
                                           "rows": rows, "error bars": bars}, indent=1))
        print(f"table: {out / name}")
    draw(figure, stores, out / "walls.png")


if __name__ == "__main__":
    raise SystemExit(finish(main))
