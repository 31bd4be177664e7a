r"""A granular shock: gas driven into a wall at rest (the piston problem in the wall's frame),
elastic and inelastic, against Rankine-Hugoniot and granular Euler hydrodynamics.

The gas (rho_1 = 1, T_1 = 1, u = -U) fills [0, ell] between two specular walls; a shock
leaves the wall at x = 0 and the gas behind it is at rest (a rarefaction leaves the far
wall, and the runs stop before it reaches the shock). 2D velocities with the Maxwell
kernel B = 1/(2 pi): Rankine-Hugoniot does not depend on the kernel (only on
gamma = (d+2)/d = 2), and for this kernel the energy the collisions take out of any f is
exact in rho and T (:func:`granframe.theory.cooling.maxwellian_cooling_rate`), so that the
granular Euler equations

    d_t rho + d_x (rho u) = 0,   d_t (rho u) + d_x (rho u^2 + p) = 0,
    d_t E + d_x (u (E + p)) = -(1 - e^2) rho^2 T d / (8 eps),   p = rho T,
    E = rho u^2/2 + d rho T/2,

are the limit eps -> 0 at fixed (1 - e^2)/eps of the kinetic run. They are solved here by
an independent finite-volume scheme (:func:`granframe.theory.euler.granular_euler_piston`);
for e = 1 the post-shock state and the shock speed are exact
(:func:`granframe.theory.euler.rankine_hugoniot`).

Run: ``python studies/granular_shock.py --out DIR [--restitution 1] [--knudsen 1e-3]``.
"""

from __future__ import annotations

import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.theory.euler import granular_euler_piston, piston_speed, rankine_hugoniot
from granframe.tools.studykit import (cfl_time_step, draw, finish, json_text, number,
                                      output_folder, parse_study, print_table, run_study,
                                      save_figure, study_arguments)

DIMENSION = 2
GAMMA = (DIMENSION + 2) / DIMENSION


def description(speed: float, e: float, knudsen: float, cells: int, length: float,
                final: float, n_modes: int, support: float, time_step: float) -> RunDescription:
    """The kinetic piston problem: 2D Maxwell kernel, MUSCL, penalised ARS(2,2,2) (the
    Euler limit at small eps), the conservative correction, moments every step."""
    state = {"density": 1.0, "temperature": 1.0, "velocity": -speed}
    return RunDescription(
        title=f"granular shock, U = {speed:g}, e = {e:g}, eps = {knudsen:g}, {cells} cells",
        grid={"dimension": DIMENSION, "n_modes": n_modes, "support_radius": support},
        kernel="maxwell", restitution={"name": "constant", "value": e},
        initial={"name": "riemann", "left": state, "right": state},
        operator={"name": "fast_spectral"}, integrator="penalised_ars222", knudsen=knudsen,
        conservative=True, time_step=time_step, final_time=final,
        output={"snapshot_interval": final},
        space={"cells": cells, "length": length, "left": "specular", "right": "specular"})


def shock_position(x, density, upstream: float = 1.0) -> float:
    """Where the density, read from the far side, first climbs above halfway between the
    upstream density and the largest density ahead of the wall region: the last crossing
    of (rho_1 + rho_max)/2 from the wall, linearly interpolated between cell centres; 0
    while the density nowhere exceeds rho_1 by 1e-3 (no shock yet)."""
    if float(numpy.max(density)) < upstream + 1e-3:
        return 0.0
    level = 0.5 * (upstream + float(numpy.max(density)))
    above = numpy.nonzero(density >= level)[0]
    i = int(above[-1])
    if i + 1 >= len(x):
        return float(x[-1])
    a, b = density[i], density[i + 1]
    return float(x[i] + (x[i + 1] - x[i]) * (a - level) / (a - b))


def shock_track(times, x, density):
    """The shock position at each time and its speed: the slope of the least-squares line
    through the positions of the last two thirds of the run."""
    positions = numpy.array([shock_position(x, rho) for rho in density])
    late = times >= times[-1] / 3.0
    slope = numpy.polyfit(times[late], positions[late], 1)[0]
    return positions, float(slope)


def plateau(x, values, position: float) -> float:
    """The mean of ``values`` over the cells in [0.3, 0.7] x the shock position (away from
    the wall's layer and the shock)."""
    inside = (x >= 0.3 * position) & (x <= 0.7 * position)
    return float(numpy.mean(values[inside]))


def cell_averages(values, cells: int):
    """Averages of fine reference profiles (the last axis) over ``cells`` kinetic cells,
    each a whole number of fine ones."""
    return values.reshape(*values.shape[:-1], cells, -1).mean(axis=-1)


def compare(store, speed: float, e: float, knudsen: float, length: float) -> dict:
    """The kinetic run against Rankine-Hugoniot (shock speed, rho_2, T_2: elastic) and
    against granular Euler (the L1 distance of rho and T behind the shock over the run's
    last state; ``bulk rho``, ``bulk T``: the largest relative difference over the cells in
    [0.15, 0.75] x Euler's shock position, away from the wall's layer and the shock; the
    wall cell's rho and T, the shock position; any e), with ``history``:
    the wall cell's rho and T and the shock position at a quarter, half, three quarters and
    the whole of the run, against granular Euler's (averaged over the same cells)."""
    ds = granframe.open_run(store, time_axis="steps")
    t = ds.time.values
    x = ds.x.values
    cells = len(x)
    density, temperature = ds.density.values, ds.temperature.values
    positions, shock = shock_track(t, x, density)
    quarters = [t[-1] * q for q in (0.25, 0.5, 0.75, 1.0)]
    reference = granular_euler_piston(speed, e, knudsen, length, quarters,
                               cells=cells * max(1, 4000 // cells))
    rho_coarse = cell_averages(reference["density"], cells)
    t_coarse = cell_averages(reference["temperature"], cells)
    rho_ref, t_ref = rho_coarse[-1], t_coarse[-1]
    rows = [int(numpy.argmin(abs(t - q))) for q in quarters]
    history = {"times": quarters,
               "T wall": [float(temperature[i][0]) for i in rows],
               "Euler T wall": [float(v) for v in t_coarse[:, 0]],
               "rho wall": [float(density[i][0]) for i in rows],
               "Euler rho wall": [float(v) for v in rho_coarse[:, 0]],
               "shock position": [float(positions[i]) for i in rows],
               "Euler shock position": [shock_position(x, r) for r in rho_coarse]}
    ref_position = shock_position(x, rho_ref)
    behind = x <= 1.2 * max(ref_position, positions[-1])
    bulk = (x >= 0.15 * ref_position) & (x <= 0.75 * ref_position)
    dx = length / cells
    row = {"U": speed, "e": e, "eps": knudsen, "cells": cells,
           "N": int(ds.sizes["v1"]), "final": float(t[-1]), "steps": int(len(t) - 1),
           "shock speed": shock, "shock position": float(positions[-1]),
           "Euler shock position": ref_position,
           "rho wall": float(density[-1][0]), "Euler rho wall": float(rho_ref[0]),
           "T wall": float(temperature[-1][0]), "Euler T wall": float(t_ref[0]),
           "L1 rho": float(numpy.sum(abs(density[-1] - rho_ref)[behind]) * dx),
           "L1 T": float(numpy.sum(abs(temperature[-1] - t_ref)[behind]) * dx),
           "bulk rho": float(numpy.max(abs(density[-1] / rho_ref - 1.0)[bulk])),
           "bulk T": float(numpy.max(abs(temperature[-1] / t_ref - 1.0)[bulk])),
           "mass drift": float(abs(ds.mass.values[-1] / ds.mass.values[0] - 1.0)),
           "largest negative mass share": float(ds.negative_mass_fraction.values.max()),
           "history": history}
    if e == 1.0:
        exact_state = rankine_hugoniot(speed, GAMMA)
        row.update({"rho_2": plateau(x, density[-1], positions[-1]),
                    "T_2": plateau(x, temperature[-1], positions[-1]),
                    "RH rho_2": exact_state["rho_2"], "RH T_2": exact_state["T_2"],
                    "RH shock speed": exact_state["shock_speed"], "mach": exact_state["mach"]})
    return row


def figure(stores, path) -> None:
    """rho and T at the last time of each run (lines with markers) against granular Euler
    (black), and the wall cell's T over time."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), layout="tight")
    drawn = set()
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        d = RunDescription.from_toml(ds.attrs["description_toml"])
        e, eps = d.restitution.params["value"], d.knudsen
        speed = -d.initial.params["left"]["velocity"]
        length = d.space.length
        t = ds.time.values
        label = f"e = {e:g}, eps = {eps:g}, {ds.sizes['x']} cells"
        line, = axes[0].plot(ds.x.values, ds.density.values[-1], ".-", ms=3, lw=0.8,
                             label=label)
        axes[1].plot(ds.x.values, ds.temperature.values[-1], ".-", ms=3, lw=0.8,
                     color=line.get_color())
        axes[2].plot(t, ds.temperature.values[:, 0], "-", color=line.get_color(), lw=1)
        key = (speed, e, eps, length, float(t[-1]))
        if key in drawn:
            continue
        drawn.add(key)
        times = numpy.linspace(0.0, t[-1], 41)[1:]
        ref = granular_euler_piston(speed, e, eps, length, times)
        axes[0].plot(ref["x"], ref["density"][-1], "k-", lw=0.8)
        axes[1].plot(ref["x"], ref["temperature"][-1], "k-", lw=0.8)
        axes[2].plot(ref["time"], ref["temperature"][:, :len(ref["x"]) // 100].mean(axis=1),
                     "k--", lw=0.8)
    axes[0].set_ylabel("density")
    axes[1].set_ylabel("temperature")
    axes[2].set_ylabel("T in the wall cell")
    for ax in axes[:2]:
        ax.set_xlabel("x")
    axes[2].set_xlabel("t")
    axes[0].legend(fontsize=7)
    fig.suptitle("gas driven into a wall: granframe (colours), granular Euler (black)",
                 fontsize=9)
    save_figure(fig, path, dpi=120)


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=48, cells=100, final=0.2,
                             quick={"n_modes": 24, "cells": 40, "final": 0.1})
    parser.set_defaults(restitution=1.0, support=4.5)
    parser.add_argument("--knudsen", type=number(0.0), default=1e-3, help="the Knudsen number")
    parser.add_argument("--mach", type=number(1.0), default=1.5,
                        help="the elastic shock's Mach number, which fixes U")
    parser.add_argument("--length", type=number(0.0), default=1.0, help="the tube length")
    args = parse_study(parser, argv)
    out = output_folder(args, figure, "shock.png")
    if out is None:
        return
    speed = piston_speed(args.mach, GAMMA)
    grid = {"n_modes": args.n_modes, "support_radius": args.support}
    time_step = cfl_time_step(args.cells, args.final, grid, length=args.length)
    began = time.perf_counter()
    run = Simulation(description(speed, args.restitution, args.knudsen, args.cells,
                                 args.length, args.final, args.n_modes, args.support,
                                 time_step))
    store = out / (f"shock_e{args.restitution:g}_eps{args.knudsen:g}_c{args.cells}"
                   f"_n{args.n_modes}.zarr")
    result = run_study(run, store, args, overwrite=True)
    seconds = time.perf_counter() - began
    row = {**compare(store, speed, args.restitution, args.knudsen, args.length),
           "seconds": seconds, "dt": time_step,
           "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]}
    print_table([row], {key: ".5g" for key in ("U", "eps", "shock speed", "RH shock speed",
                                               "rho_2", "RH rho_2", "T_2", "RH T_2",
                                               "L1 rho", "L1 T", "mass drift")})
    store.with_suffix(".json").write_text(json_text(row, indent=1))
    print(f"table: {store.with_suffix('.json')}")
    draw(figure, [store], out / "shock.png")


if __name__ == "__main__":
    raise SystemExit(finish(main))
