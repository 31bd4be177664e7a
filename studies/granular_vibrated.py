r"""A granular gas driven by a vibrating wall (no gravity): the steady state, the power the
wall puts in against the collisional dissipation, and the temperature against the energy
balance of a uniform gas (the leading order of Kumaran's theory of dilute vibrated gases).

x in [0, 1]: the vibrating wall (speed amplitude V = A omega, in the limit A -> 0;
docs/space.md, "Vibrating walls") at x = 0, elastic (specular) as in the kinetic theories
of vibrated gases, a specular wall at x = 1, mean density 1, 2D velocities with the hard-disk
kernel B = |g| / (2 pi), knudsen eps. The wall puts in, per unit time,

    P_in = sum over the arriving particles of what the layer adds = Phi Delta e,

with Phi = rho_w sqrt(T_w / (2 pi)) the arriving flux of a Maxwellian gas at the wall and
Delta e = 2 V^2 (1 + O(V^2 / T)) per particle (:func:`granframe.space.exact.
vibrating_wall_heating`); the collisions take out (d/2) rho T zeta(T) / eps per unit
volume, zeta = zeta_1 rho sqrt(T) for hard disks (the Maxwellian's rate,
:func:`granframe.theory.cooling.maxwellian_cooling_rate`). A uniform gas (rho = 1, T) in
balance has

    sqrt(T / (2 pi)) Delta e(V, T) = (d/2) zeta_1 T^{3/2} / eps,
    T = 2 eps V^2 / (sqrt(2 pi) (d/2) zeta_1)  at leading order,

the scaling T ~ V^2 / (1 - e^2) of Kumaran (Phys. Rev. E 59 (1999) 4188; J. Fluid Mech.
364 (1998) 163: the mean square velocity ~ <U^2> / (1 - e^2) for a symmetric wall motion)
and of McNamara & Luding (Phys. Rev. E 58 (1998) 813: the power ~ V^2). It assumes a
uniform gas, which the run is only where the dissipation over the box is small against
the conduction across it: (1 - e^2) / eps^2 small (the granular Navier-Stokes profile's
parameter, docs/granular.md, section 1), and a Maxwellian gas at the wall.

For each e the wall speed is chosen so that the uniform gas has T = 1 (the velocity grid
fits T = 1); the run starts from that gas and goes to ``--final``. Reported: the mean T
against the theory, the profiles, the power put in and dissipated at the end (their rates
from the last steps' ``wall_energy`` and from Q at the last snapshot), the energy's rate of
change (steadiness), the resolution warnings.

Run: ``python studies/granular_vibrated.py --out DIR``.
"""

from __future__ import annotations

import functools
import math
import time

import numpy
import scipy.optimize

import granframe
from granframe.run.description import RunDescription
from granframe.run.refinement import grid_convergence
from granframe.run.runner import Simulation
from granframe.space import exact
from granframe.theory.cooling import maxwellian_cooling_rate
from granframe.tools.studykit import (
    cfl_time_step,
    draw,
    finish,
    json_text,
    number,
    numbers,
    output_folder,
    parse_study,
    print_table,
    run_study,
    save_figure,
    study_arguments,
)

DIMENSION = 2
#: snapshots of f over a run
SNAPSHOTS = 8


def cooling_coefficient(e: float) -> float:
    """zeta_1 = zeta / (rho sqrt(T)) of a Maxwellian of hard disks, B = |g| / (2 pi)."""
    return maxwellian_cooling_rate(e, 1.0, 1.0, dimension=DIMENSION, speed_exponent=1.0)


@functools.lru_cache(maxsize=64)
def wall_speed_ratio(e: float, knudsen: float) -> float:
    """x = V / sqrt(T) of the uniform gas in balance (module notes), with the wall's whole
    heating: Delta e(V, T) = T H(V / sqrt(T)) (the specular layer has no speed of its own),
    so the balance reads H(x) = sqrt(2 pi) (d/2) zeta_1 / eps (Brent's method, from the
    leading order H = 2 x^2)."""
    target = math.sqrt(2 * math.pi) * 0.5 * DIMENSION * cooling_coefficient(e) / knudsen
    lead = math.sqrt(0.5 * target)
    return scipy.optimize.brentq(
        lambda x: math.log(exact.vibrating_wall_heating(x, 1.0, 1.0, "specular", speeds=1000)
                           / target), 0.7 * lead, 1.1 * lead, xtol=1e-12)


def uniform_temperature(e: float, knudsen: float, speed: float) -> float:
    """T = (V / x)^2 of the uniform gas in balance (:func:`wall_speed_ratio`)."""
    return (speed / wall_speed_ratio(e, knudsen)) ** 2


def description(e: float, knudsen: float, speed: float, cells: int, n_modes: int,
                support: float, final: float, time_step: float,
                temperature: float = 1.0) -> RunDescription:
    """The specular vibrating wall (V = ``speed``) at x = 0, a specular wall at x = 1,
    from the Maxwellian at rest at ``temperature``; :data:`SNAPSHOTS` snapshots."""
    return RunDescription(
        title=f"vibrated gas, e = {e:g}, eps = {knudsen:g}, V = {speed:.6g}",
        grid={"dimension": DIMENSION, "n_modes": n_modes, "support_radius": support},
        kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial={"name": "maxwellian", "temperature": temperature},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", conservative=True,
        knudsen=knudsen, time_step=time_step, final_time=final,
        output={"snapshot_interval": final / SNAPSHOTS},
        space={"cells": cells, "reconstruction": "muscl",
               "left": {"name": "vibrating", "speed": speed, "reflection": "specular"},
               "right": "specular"})


def balance(ds, operator, knudsen: float, window: int = 20) -> dict:
    """At the end of a run: the power the walls put in (``wall_energy`` over the last
    ``window`` steps over their time), the collisional dissipation rate at the last
    snapshot (sum_cells dx h^d sum Q |v|^2/2 / eps), the energy's rate of change over the
    window, and the last snapshot's profiles."""
    dt = float(ds.dt.values[-1])
    power = float(ds.wall_energy.values[-window:].sum()) / (window * dt)
    energy = ds.kinetic_energy.values
    change = float(energy[-1] - energy[-window - 1]) / (window * dt)
    grid = operator.grid
    dx = 1.0 / ds.sizes["x"]
    f = ds.f.values[-1]
    dissipation = float(numpy.sum(numpy.asarray(operator(f)) * grid.speed_squared())
                        * grid.cell_volume * 0.5 * dx / knudsen)
    return {"power in": power, "dissipation": dissipation, "change": change,
            "residual": (power + dissipation - change) / power,
            "density": ds.density.values[-1], "temperature": ds.temperature.values[-1]}


def figure(stores, path) -> None:
    """T(x) / T_uniform and rho(x) of each run at its end, and mean T / T_uniform over time."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), layout="tight")
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        d = RunDescription.from_toml(ds.attrs["description_toml"])
        e = d.restitution.params["value"]
        speed = d.space.left.params["speed"]
        uniform = uniform_temperature(e, d.knudsen, speed)
        line, = axes[0].plot(ds.x.values, ds.temperature.values[-1] / uniform, "o-", ms=3,
                             lw=0.8, label=f"e = {e:g}, V = {speed:.3g}, N = {d.grid.n_modes}")
        axes[1].plot(ds.x.values, ds.density.values[-1], "o-", ms=3, lw=0.8,
                     color=line.get_color())
        mean = (ds.temperature.values * ds.density.values).mean(axis=1)
        axes[2].plot(ds.time.values, mean / uniform, lw=0.8, color=line.get_color())
    axes[0].set_ylabel("T / T of the uniform balance")
    axes[1].set_ylabel("density")
    axes[2].set_ylabel("mean rho T / T of the uniform balance")
    axes[2].set_xlabel("t")
    for ax in axes[:2]:
        ax.set_xlabel("x (vibrating wall at 0, specular at 1)")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"gas driven by a vibrating specular wall, eps = {d.knudsen:g}", fontsize=9)
    save_figure(fig, path, dpi=120)


#: the numbers of a run that get error bars from a refinement (:func:`error_bars`)
REFINED = ("mean T / T uniform", "T(0) / T uniform", "T(1) / T uniform",
           "rho max / rho min")


def run_member(args, out, n_modes: int, cells: int):
    """The runs of every e at one resolution (N, cells; the time step at the CFL limit of
    the cells): their table rows and stores."""
    grid = {"n_modes": n_modes, "support_radius": args.support}
    dt = cfl_time_step(cells, args.final / SNAPSHOTS, grid)
    rows, stores = [], []
    for e in args.restitutions:
        began = time.perf_counter()
        speed = wall_speed_ratio(e, args.knudsen)          # T uniform = 1
        run = Simulation(description(e, args.knudsen, speed, cells, n_modes, args.support,
                                     args.final, dt))
        store = out / f"vibrated_e{e:g}_k{args.knudsen:g}_c{cells}_n{n_modes}.zarr"
        result = run_study(run, store, args, overwrite=True)
        seconds = time.perf_counter() - began
        ds = granframe.open_run(store, time_axis="steps")
        end = balance(ds, run.problem.operator, args.knudsen)
        temperature, density = end.pop("temperature"), end.pop("density")
        uniform = uniform_temperature(e, args.knudsen, speed)
        rows.append({"e": e, "eps": args.knudsen, "V": speed, "cells": cells, "N": n_modes,
                     "S": args.support, "dt": dt, "final": args.final, "seconds": seconds,
                     "T uniform": uniform,
                     "mean T / T uniform": float((temperature * density).mean() / uniform),
                     "T(0) / T uniform": float(temperature[0] / uniform),
                     "T(1) / T uniform": float(temperature[-1] / uniform),
                     "rho max / rho min": float(density.max() / density.min()),
                     "(1 - e^2) / eps^2": (1 - e * e) / args.knudsen ** 2,
                     **end, "T profile": temperature.tolist(),
                     "density profile": density.tolist(),
                     "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]})
        stores.append(store)
    return rows, stores


def error_bars(members: list, spacings: list) -> list[dict]:
    """For each e, each of :data:`REFINED` over a refinement (``members``: the rows of each
    resolution, coarse to fine, ``spacings`` their h): the finest value, the observed
    order, the Richardson estimate and the grid convergence index
    (:func:`granframe.run.refinement.grid_convergence`)."""
    out = []
    for k, row in enumerate(members[-1]):
        entry = {"e": row["e"]}
        for key in REFINED:
            result = grid_convergence([m[k][key] for m in members], spacings)
            entry[key] = {name: result[name] for name in ("value", "order", "convergence",
                                                          "extrapolated", "error_bar")}
        out.append(entry)
    return out


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=32, cells=16, final=40.0,
                             quick={"n_modes": 24, "cells": 8, "final": 2.0,
                                    "restitutions": [0.9]})
    parser.add_argument("--knudsen", type=number(0.0), default=0.5, help="the Knudsen number eps")
    parser.add_argument("--restitutions", type=numbers(0.0), default=[0.99, 0.95, 0.9, 0.8],
                        help="e values, comma-separated (the default: 0.99,0.95,0.9,0.8)")
    parser.add_argument("--refine", choices=("n-modes", "cells"), default=None,
                        help="run the study at three resolutions, the given one and two "
                             "coarser (N x 2/3 and x 3/4 from N, or cells / 4 and / 2), and "
                             "give its numbers error bars from them (observed order, "
                             "Richardson, grid convergence index)")
    args = parse_study(parser, argv)
    for e in args.restitutions:
        if e >= 1.0:
            parser.error(f"argument --restitutions: {e:g} is not allowed: each e must be below "
                         "1 (an elastic gas driven by the wall has no steady state)")
    out = output_folder(args, figure, "vibrated.png")
    if out is None:
        return
    if args.refine == "n-modes":
        family = [(round(args.n_modes / 2), args.cells), (round(args.n_modes * 2 / 3),
                                                          args.cells),
                  (args.n_modes, args.cells)]
        spacings = [1.0 / n for n, _ in family]
    elif args.refine == "cells":
        family = [(args.n_modes, args.cells // 4), (args.n_modes, args.cells // 2),
                  (args.n_modes, args.cells)]
        spacings = [1.0 / c for _, c in family]
    else:
        family, spacings = [(args.n_modes, args.cells)], None
    members = []
    for n_modes, cells in family:
        rows, stores = run_member(args, out, n_modes, cells)
        members.append(rows)
    print_table(rows, {"e": "g", "V": ".4g", "N": "d", "cells": "d", "seconds": ".0f",
                       "mean T / T uniform": ".4f", "T(0) / T uniform": ".4f",
                       "T(1) / T uniform": ".4f", "rho max / rho min": ".4f",
                       "power in": ".5g", "dissipation": ".5g", "residual": ".2g"})
    table = out / f"vibrated_k{args.knudsen:g}_c{args.cells}_n{args.n_modes}.json"
    table.write_text(json_text(rows, indent=1))
    print(f"table: {table}")
    if spacings is not None:
        bars = error_bars(members, spacings)
        for entry in bars:
            print(f"e = {entry['e']:g}: " + "; ".join(
                f"{key} {v['value']:.4f} ± {v['error_bar']:.2g} (order {v['order']:.3g}, "
                f"{v['convergence']})" if v["order"] is not None else
                f"{key} {v['value']:.4f} ({v['convergence']})" for key, v in entry.items()
                if key != "e"))
        (out / f"vibrated_refine_{args.refine}.json").write_text(
            json_text({"family": family, "spacings": spacings, "error bars": bars}, indent=1))
    draw(figure, stores, out / "vibrated.png")


if __name__ == "__main__":
    raise SystemExit(finish(main))
