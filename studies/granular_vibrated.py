r"""A granular gas driven by a vibrating wall (no gravity): the period-averaged steady state,
the energy put in per period against the collisional dissipation, and the scaling of the
temperature with the wall's speed A omega.

x in [0, 1]: the vibrating diffuse wall (T_w, A, omega; docs/space.md, "Moving and
vibrating walls") at x = 0, a specular wall at x = 1, mean density 1, e = 0.9, 2D
velocities with the kernel B = |g|/(2 pi). Over a period the vibrating wall sends back, per
particle, the energy of a wall at rest at

    T_eff = T_w + 2 c_2 (A omega)^2 / (d + 1),   c_2 = 1/2 - pi/8,

to second order in A omega / sqrt(T_w) (the expansion of <J2/J0> in docs/space.md, at
fixed arriving flux). For a kernel proportional to |g| the kinetic equation has no speed of
its own: with the walls at T_eff the steady state is that at T_w with every velocity
scaled by sqrt(T_eff/T_w), so the density profile does not change and the temperature
profile is multiplied by T_eff/T_w. The study measures both, and the energy balance: per
period, what the wall puts in (the run's ``wall_energy`` over the period's steps) against
the collisional dissipation (sum_cells dx h^d sum Q |v|^2/2 / eps at eight snapshots of the
last period, periodic trapezoid rule) and the energy's change.

Run: ``python studies/granular_vibrated.py --out DIR --speeds 0,0.5,1``.
"""

from __future__ import annotations

import math
import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space import exact
from granframe.tools.studykit import (cfl_time_step, finish, json_text, number, numbers,
                                      output_folder, save_figure, study_arguments)

DIMENSION = 2
#: c_2 of the period mean <J2/J0> = (d+1) T_w/2 + T_w (c_2 eps^2 + ...), docs/space.md
C2 = exact.VIBRATING_WALL_COEFFICIENTS[0]
#: snapshots of f per period (the dissipation's periodic trapezoid rule)
SNAPSHOTS = 8


def effective_temperature(speed: float, temperature: float = 1.0) -> float:
    """T_eff = T_w + 2 c_2 (A omega)^2 / (d + 1): the wall at rest that puts in, per
    particle sent back, the vibrating wall's period-mean energy (second order)."""
    return temperature + 2.0 * C2 * speed * speed / (DIMENSION + 1)


def description(e: float, knudsen: float, speed: float, period: float, cells: int,
                n_modes: int, support: float, periods: int, steps_per_period: int,
                wall_temperature: float = 1.0) -> RunDescription:
    """The vibrating wall (A omega = ``speed``; a resting diffuse wall if 0) at x = 0 and a
    specular wall at x = 1, from the Maxwellian at rest at T_w; ``periods`` periods of
    ``steps_per_period`` SSP RK2 steps, f stored :data:`SNAPSHOTS` times per period."""
    omega = 2.0 * math.pi / period
    if speed > 0.0:
        left = {"name": "vibrating", "temperature": wall_temperature,
                "amplitude": speed / omega, "frequency": omega}
    else:
        left = {"name": "diffuse", "temperature": wall_temperature}
    return RunDescription(
        title=f"vibrated gas, e = {e:g}, eps = {knudsen:g}, A omega = {speed:g}",
        grid={"dimension": DIMENSION, "n_modes": n_modes, "support_radius": support},
        kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial={"name": "maxwellian", "temperature": wall_temperature},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", conservative=True,
        knudsen=knudsen, time_step=period / steps_per_period, final_time=periods * period,
        output={"snapshot_interval": period / SNAPSHOTS},
        space={"cells": cells, "reconstruction": "muscl", "left": left, "right": "specular"})


def period_balance(ds, operator, knudsen: float, period: float) -> dict:
    """Over the last period: the energy the walls put in (sum of ``wall_energy`` over its
    steps), the collisional dissipation (its rate at the snapshots of the period, periodic
    trapezoid rule, times the period), the change of the energy, and the period means of
    rho(x) and T(x) (the step moments)."""
    steps = ds.time.values
    dt = float(ds.dt.values[-1])
    per = int(round(period / dt))
    injected = float(ds.wall_energy.values[-per:].sum())
    energy = ds.kinetic_energy.values
    change = float(energy[-1] - energy[-per - 1])
    grid = operator.grid
    dx = 1.0 / ds.sizes["x"]
    f = ds.f.values[-SNAPSHOTS:]
    rates = [float(numpy.sum(numpy.asarray(operator(fi)) * grid.speed_squared())
                   * grid.cell_volume * 0.5 * dx / knudsen) for fi in f]
    dissipation = float(numpy.mean(rates)) * period
    return {"time": float(steps[-1]), "injected": injected, "dissipation": dissipation,
            "change": change, "residual": (injected + dissipation - change) / injected,
            "density": ds.density.values[-per:].mean(axis=0),
            "temperature": ds.temperature.values[-per:].mean(axis=0)}


def figure(stores, path) -> None:
    """Period-mean T(x) and rho(x) of each run; T divided by T_eff (dashed; T_eff =
    T_w + 2 c_2 (A omega)^2/(d+1)) lies on the run at rest with T_w = 1 where the wall
    acts as one at rest at T_eff."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="tight")
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        d = RunDescription.from_toml(ds.attrs["description_toml"])
        left = d.space.left.params
        speed = left.get("amplitude", 0.0) * left.get("frequency", 0.0)
        steps = int(round(SNAPSHOTS * d.output.snapshot_interval / d.time_step))
        density = ds.density.values[-steps:].mean(axis=0)
        temperature = ds.temperature.values[-steps:].mean(axis=0)
        wall = left.get("temperature", 1.0)
        line, = axes[0].plot(ds.x.values, temperature, "o-", ms=3, lw=0.8,
                             label=f"A omega = {speed:g}, T_w = {wall:.4g}, N = "
                                   f"{d.grid.n_modes}")
        axes[0].plot(ds.x.values, temperature / effective_temperature(speed, wall), "--",
                     color=line.get_color(), lw=0.8)
        axes[1].plot(ds.x.values, density, "o-", ms=3, lw=0.8, color=line.get_color())
    axes[0].set_ylabel("period-mean T (dashed: T / T_eff)")
    axes[1].set_ylabel("period-mean density")
    for ax in axes:
        ax.set_xlabel("x (vibrating wall at 0, specular at 1)")
    axes[0].legend(fontsize=7)
    fig.suptitle("vibrated granular gas, e = 0.9", fontsize=9)
    save_figure(fig, path, dpi=120)


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=32, cells=16, final=None)
    parser.set_defaults(support=4.0)
    parser.add_argument("--knudsen", type=number(0.0), default=0.1)
    parser.add_argument("--speeds", type=numbers(0.0, low_open=False), default=[0.0, 0.5, 1.0],
                        help="A omega values, comma-separated")
    parser.add_argument("--period", type=number(0.0), default=0.25)
    parser.add_argument("--periods", type=number(1, kind=int, low_open=False), default=24)
    parser.add_argument("--wall-temperature", type=number(0.0), default=1.0,
                        help="T_w of the vibrating (or resting) wall")
    args = parser.parse_args(argv)
    out = output_folder(args, figure, "vibrated.png")
    if out is None:
        return
    grid = {"n_modes": args.n_modes, "support_radius": args.support}
    limit = cfl_time_step(args.cells, args.period, grid)
    steps_per_period = SNAPSHOTS * math.ceil(args.period / limit / SNAPSHOTS - 1e-9)
    rows = []
    for speed in args.speeds:
        began = time.perf_counter()
        run = Simulation(description(args.restitution, args.knudsen, speed, args.period,
                                     args.cells, args.n_modes, args.support, args.periods,
                                     steps_per_period, args.wall_temperature))
        store = out / (f"vibrated_e{args.restitution:g}_u{speed:g}_tw{args.wall_temperature:g}"
                       f"_c{args.cells}.zarr")
        result = run.run(store, progress=False, overwrite=True)
        seconds = time.perf_counter() - began
        ds = granframe.open_run(store, time_axis="steps")
        balance = period_balance(ds, run.problem.operator, args.knudsen, args.period)
        row = {"A omega": speed, "e": args.restitution, "eps": args.knudsen,
               "cells": args.cells, "N": args.n_modes, "S": args.support,
               "period": args.period, "steps per period": steps_per_period,
               "periods": args.periods, "seconds": seconds,
               "T_w": args.wall_temperature,
               "T_eff/T_w": effective_temperature(speed, args.wall_temperature)
               / args.wall_temperature,
               **{k: v for k, v in balance.items() if k not in ("density", "temperature")},
               "mean T": float(balance["temperature"].mean()),
               "T profile": balance["temperature"].tolist(),
               "density profile": balance["density"].tolist(),
               "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]}
        rows.append(row)
        print(json_text({k: v for k, v in row.items() if "profile" not in k}))
    base = next((r for r in rows if r["A omega"] == 0.0), None)
    if base is not None:
        for row in rows:
            ratio = numpy.array(row["T profile"]) / numpy.array(base["T profile"])
            row["T/T(0) mean"] = float(ratio.mean())
            row["T/T(0) spread"] = float(ratio.max() - ratio.min())
            row["rho - rho(0) max"] = float(numpy.abs(numpy.array(row["density profile"])
                                                      - numpy.array(base["density profile"])
                                                      ).max())
            print(row["A omega"], row["T/T(0) mean"], row["T_eff/T_w"],
                  row["T/T(0) spread"], row["rho - rho(0) max"])
    (out / f"vibrated_e{args.restitution:g}_tw{args.wall_temperature:g}_c{args.cells}"
           f"_n{args.n_modes}.json").write_text(
        json_text(rows, indent=1))


if __name__ == "__main__":
    raise SystemExit(finish(main))
