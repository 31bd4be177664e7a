"""A lid-driven cavity of an elastic and of a granular gas: the steady state and its
refinement columns.

The unit square with four diffuse walls at T = 1; the top one (the lid) slides along x at
U = ``--lid`` (0.3: Mach 0.21 against the 2D gas's sound speed sqrt(2)). The gas starts at
rest, rho = T = 1, 2D velocities, hard spheres (B = |g| / (2 pi)), eps = ``--knudsen`` x
sqrt(2) (Kn = lambda_mfp / 1 = ``--knudsen``, docs/space.md "Knudsen number and mean free
path"), restitution e for each value of ``--restitution`` (1, then 0.9: the walls then heat
a gas that cools by its collisions). The fast spectral operator, SSP RK2 with the
conservative correction, MUSCL, dt the transport's CFL limit on both axes, on C x C cells
for each C of ``--cells``, to t = ``--final``.

No published table of this cavity (2D velocities, hard spheres, inelastic) was found, so
the numbers stand on their refinement columns alone: for each C the steady values below
and their change from the coarser C. Reported over the last time unit (the window):
- the lid's force on the gas per unit length (the x-momentum that enters through the lid
  per unit time and length, from the wall records), and the heat the walls put into the
  gas per unit time (all four walls; zero in the elastic steady state, where the lid's work
  leaves through the walls; the gas's dissipation in the granular one) and the balance,
  that heat less the change of the gas's energy over the window per unit time: zero for
  e = 1, the dissipation rate for e < 1, against the dissipation of local Maxwellians
  with the run's last fields, sum_cells rho T zeta_M(rho, T) / eps dA
  (:func:`granframe.theory.cooling.maxwellian_cooling_rate`; d/2 = 1; the cooling state's
  a_2 and the gradients make the difference);
- the mean and the smallest T, u_1 at the centre (the mean of the four central cells),
  the smallest u_1 on the vertical centre line and the largest |u_2| on the horizontal one;
- steadiness: the largest change of T and of u_1 over the window.

    python studies/cavity_2d.py --out DIR [--cells 8,16] [--restitution 1,0.9]
        [--knudsen 1] [--lid 0.3] [--final 6] [--n-modes 24] [--support 3.5]

writes ``cavity_2d.csv``, ``cavity_2d.md`` and ``cavity_2d.png`` (T and the speed with
streamlines of the finest run at each e) there.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space.transport import box_step_limit
from granframe.theory.cooling import maxwellian_cooling_rate
from granframe.tools.studykit import finish, number, numbers, save_figure, write_csv
from granframe.velocity.grid import VelocityGrid

QUANTITIES = ("lid force", "wall heat", "balance", "Maxwellian dissipation", "mean T", "min T", "u1 centre",
              "min u1 centre line", "max |u2| centre line", "change T", "change u1")


def description(cells: int, e: float, knudsen: float, lid: float, final: float,
                n_modes: int, support: float) -> RunDescription:
    """The cavity on ``cells`` x ``cells`` cells (module notes)."""
    grid = {"dimension": 2, "n_modes": n_modes, "support_radius": support}
    limit = box_step_limit(VelocityGrid(**grid), (1.0 / cells, 1.0 / cells), 0.5)
    steps = 4 * math.ceil(final / limit / 4 * (1 - 1e-12))         # four snapshots
    wall = {"name": "diffuse", "temperature": 1.0}
    return RunDescription.from_dict({
        "title": f"lid-driven cavity, e = {e:g}, Kn = {knudsen:g}, lid {lid:g}, "
                 f"{cells}^2 cells, N = {n_modes}",
        "grid": grid, "kernel": "hard_spheres", "restitution": {"name": "constant", "value": e},
        "initial": {"name": "maxwellian"}, "operator": {"name": "fast_spectral"},
        "integrator": "ssp_rk2", "conservative": True, "knudsen": knudsen * math.sqrt(2.0),
        "time_step": final / steps, "final_time": final,
        "output": {"snapshot_interval": final / 4},
        "space": {"cells": [cells, cells], "reconstruction": "muscl", "left": wall,
                  "right": wall, "bottom": wall, "top": {**wall, "velocity": lid}}})


def steady_values(ds, e: float, knudsen: float, window: float = 1.0) -> dict:
    """The quantities of the module notes from the records of a run over its last
    ``window`` of time (at most its last half)."""
    t = ds.step_time.values
    window = min(window, 0.5 * (t[-1] - t[0]))
    start = max(1, int(numpy.argmax(t >= t[-1] - window - 1e-12)))
    span = t[-1] - t[start - 1]
    walls = list(ds.wall.values)
    momentum = ds.wall_momentum.values[start:, walls.index("top"), 0].sum() / span
    heat = ds.wall_energy.values[start:].sum() / span
    energy = ds.kinetic_energy.values
    change = (energy[-1] - energy[start - 1]) / span
    temperature = ds.temperature.values
    u = ds.velocity.values
    c = temperature.shape[1]
    middle = slice(c // 2 - 1, c // 2 + 1)
    centre_column = u[-1][middle, :, 0].mean(axis=0)
    centre_row = u[-1][:, middle, 1].mean(axis=1)
    rho = ds.density.values[-1]
    zeta = maxwellian_cooling_rate(e, rho, temperature[-1], dimension=2, speed_exponent=1.0)
    dissipation = (rho * temperature[-1] * zeta).mean() / (knudsen * math.sqrt(2.0))
    return {"lid force": float(momentum), "wall heat": float(heat),
            "balance": float(heat - change), "Maxwellian dissipation": float(dissipation),
            "mean T": float(temperature[-1].mean()),
            "min T": float(temperature[-1].min()),
            "u1 centre": float(u[-1][middle, middle, 0].mean()),
            "min u1 centre line": float(centre_column.min()),
            "max |u2| centre line": float(numpy.abs(centre_row).max()),
            "change T": float(numpy.abs(temperature[-1] - temperature[start - 1]).max()),
            "change u1": float(numpy.abs(u[-1][..., 0] - u[start - 1][..., 0]).max())}


def figure(stores: dict, path) -> None:
    """T and the speed |u| with streamlines of the finest run at each e."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(len(stores), 2, figsize=(10, 4.6 * len(stores)), squeeze=False,
                             layout="constrained")
    for row, (e, store) in enumerate(stores.items()):
        ds = granframe.open_run(store)
        x, y = ds.x.values, ds.y.values
        temperature = ds.temperature.values[-1]
        u = ds.velocity.values[-1]
        mesh = axes[row, 0].pcolormesh(x, y, temperature.T, shading="nearest", cmap="inferno")
        fig.colorbar(mesh, ax=axes[row, 0], label="T")
        speed = numpy.hypot(u[..., 0], u[..., 1])
        mesh = axes[row, 1].pcolormesh(x, y, speed.T, shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=axes[row, 1], label="|u|")
        axes[row, 1].streamplot(x, y, u[..., 0].T, u[..., 1].T, color="w", density=0.8,
                                linewidth=0.6)
        for ax in axes[row]:
            ax.set_aspect("equal")
            ax.set_title(f"e = {e:g}, {len(x)}^2 cells, t = {float(ds.time.values[-1]):g}",
                         fontsize=9)
    save_figure(fig, path, dpi=110)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--out", required=True)
    parser.add_argument("--cells", type=numbers(4, kind=int), default=[8, 16])
    parser.add_argument("--restitution", type=numbers(0.0), default=[1.0, 0.9])
    parser.add_argument("--knudsen", type=number(0.0), default=1.0)
    parser.add_argument("--lid", type=number(0.0), default=0.3)
    parser.add_argument("--final", type=number(1.0, low_open=False), default=6.0)
    parser.add_argument("--n-modes", type=number(8, kind=int, low_open=False), default=24)
    parser.add_argument("--support", type=number(0.0), default=3.5)
    args = parser.parse_args(argv)
    if any(e > 1.0 for e in args.restitution):
        parser.error(f"--restitution {args.restitution}: each e must be in (0, 1]")
    if min(args.cells) < 5:
        parser.error(f"--cells {args.cells}: MUSCL needs at least 5 cells per side")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows, finest = [], {}
    for e in args.restitution:
        previous = None
        for cells in sorted(args.cells):
            began = time.perf_counter()
            store = out / f"cavity_e{e:g}_c{cells}.zarr"
            Simulation(description(cells, e, args.knudsen, args.lid, args.final,
                                   args.n_modes, args.support)).run(
                store, progress=False, overwrite=True)
            values = steady_values(granframe.open_run(store), e, args.knudsen)
            row = {"e": e, "cells": cells, **values,
                   "seconds": round(time.perf_counter() - began, 1)}
            if previous is not None:
                row.update({f"change from {previous['cells']} {key}": values[key] - previous[key]
                            for key in ("lid force", "mean T", "u1 centre",
                                        "min u1 centre line")})
            rows.append(row)
            previous = row
            finest[e] = store
            print(row, flush=True)
    write_csv(out / "cavity_2d.csv", rows, fields=list(dict.fromkeys(
        key for row in rows for key in row)))
    title = (f"Lid-driven cavity, Kn = {args.knudsen:g}, lid {args.lid:g}, 2D hard spheres, "
             f"N = {args.n_modes}, S = {args.support:g}, t = {args.final:g} (window: the "
             "last time unit)")
    lines = [title, "",
             "| e | cells | " + " | ".join(QUANTITIES) + " | seconds |",
             "|---" * (len(QUANTITIES) + 3) + "|"]
    for row in rows:
        lines.append(f"| {row['e']:g} | {row['cells']} | "
                     + " | ".join(f"{row[key]:.4g}" for key in QUANTITIES)
                     + f" | {row['seconds']} |")
    (out / "cavity_2d.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    figure(finest, out / "cavity_2d.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
