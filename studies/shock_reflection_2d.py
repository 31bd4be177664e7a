"""A plane shock reflected from the walls of a square, near the Euler limit, against an
independent finite-volume solution of the Euler equations.

A shock of Mach number M = 1.5 moves into gas at rest (rho = 1, T = 1) in the unit square
with specular walls, along -(cos 30 deg, sin 30 deg): its front n . x = 0.6 meets the bottom
wall obliquely from t = 0 and the left wall from t = 0.047 (at its top), reflects from both
as it runs along them and reaches the corner (0, 0) at t = 0.28, while the gas behind it
(Rankine-Hugoniot, :func:`granframe.theory.euler.shock_states`: rho = 1.588, T = 1.680,
moving at U = 0.786
along the shock's motion) leaves the top and the right walls, which send rarefactions in.
The gas is granframe's with 2D velocities (gamma = 2): elastic Maxwell molecules,
eps = 1e-4, penalised ARS(2,2,2) with the conservative correction, the fast spectral
operator on 2D N = 32, S = 4, MUSCL, dt the transport's CFL limit on both axes, on C x C
cells for each C of ``--cells``, to t = 0.35. The data are
:func:`granframe.theory.euler.plane_states_maxwellian` as cell averages.

The reference: the Euler equations (gamma = 2, reflecting walls) by
:func:`granframe.theory.euler.euler_finite_volumes` on R x R cells (MUSCL-minmod, HLL,
SSP RK2; no code shared with the kinetic scheme), its data the conserved averages over
4 x 4 points of each cell. Reported for each C: the L1 distance (mean over the cells) of
rho, u_1, u_2 and T from the reference averaged onto the C x C cells (through the
conserved quantities), the same between the kinetic runs of successive C, and the
reference's own bar, the distance of its R / 2 run from its R run on the kinetic cells.

    python studies/shock_reflection_2d.py --out DIR [--cells 16,32] [--reference 256]

writes ``shock_reflection_2d.csv``, ``shock_reflection_2d.md`` and
``shock_reflection_2d.png`` (density maps of the finest kinetic run and of the reference,
and both along the bottom row of cells) there.
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
from granframe.theory.cells import conserved_block_average
from granframe.theory.euler import euler_finite_volumes, shock_states
from granframe.tools.studykit import finish, number, numbers, refinement_row, write_csv
from granframe.velocity.grid import VelocityGrid

GRID = {"dimension": 2, "n_modes": 32, "support_radius": 4.0}
GAMMA = 2.0
MACH = 1.5
ANGLE = math.radians(30.0)
OFFSET = 0.6
FINAL = 0.35
KNUDSEN = 1e-4
NORMAL = (math.cos(ANGLE), math.sin(ANGLE))


def states() -> tuple:
    """(rho, u_1, u_2, T) ahead of the shock (n . x < 0.6, at rest) and behind it."""
    behind = shock_states(MACH, GAMMA)
    u = -behind["velocity"]
    return ((1.0, 0.0, 0.0, 1.0),
            (behind["rho_2"], u * NORMAL[0], u * NORMAL[1], behind["T_2"]))


def description(cells: int) -> RunDescription:
    """The kinetic run on ``cells`` x ``cells`` cells."""
    grid = VelocityGrid(**GRID)
    limit = box_step_limit(grid, (1.0 / cells, 1.0 / cells), 0.5)
    steps = math.ceil(FINAL / limit * (1 - 1e-12))
    low, high = states()
    return RunDescription.from_dict({
        "title": f"plane shock M = {MACH:g} reflected, eps = {KNUDSEN:g}, {cells}^2 cells",
        "grid": GRID, "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "space_function",
                    "function": "granframe.theory.euler:plane_states_maxwellian",
                    "params": {"normal": list(NORMAL), "offset": OFFSET, "low": list(low),
                               "high": list(high)}},
        "operator": {"name": "fast_spectral"}, "integrator": "penalised_ars222",
        "conservative": True, "knudsen": KNUDSEN, "time_step": FINAL / steps,
        "final_time": FINAL, "output": {"snapshot_interval": FINAL},
        "space": {"cells": [cells, cells], "reconstruction": "muscl", "left": "specular",
                  "right": "specular", "bottom": "specular", "top": "specular"}})


def kinetic(cells: int, out: pathlib.Path) -> tuple[dict, float]:
    """rho, u_1, u_2, T at t = FINAL of the kinetic run on ``cells``^2 cells, and its wall
    seconds."""
    began = time.perf_counter()
    store = out / f"kinetic_{cells}.zarr"
    Simulation(description(cells)).run(store, progress=False, overwrite=True)
    ds = granframe.open_run(store)
    velocity = ds.velocity.values[-1]
    return ({"rho": ds.density.values[-1], "u1": velocity[..., 0], "u2": velocity[..., 1],
             "T": ds.temperature.values[-1]}, time.perf_counter() - began)


def reference(cells: int) -> dict:
    """The Euler equations on ``cells``^2 cells to t = FINAL from the conserved averages
    of the data over 4 x 4 points per cell."""
    points = (numpy.arange(4 * cells) + 0.5) / (4 * cells)
    x, y = numpy.meshgrid(points, points, indexing="ij")
    side = NORMAL[0] * x + NORMAL[1] * y >= OFFSET
    low, high = states()
    rho, u1, u2, t = (numpy.where(side, b, a) for a, b in zip(low, high))
    fine = {"rho": rho, "u1": u1, "u2": u2, "T": t}
    data = conserved_block_average(fine, cells, 2)
    solution = euler_finite_volumes(data["rho"], numpy.array([data["u1"], data["u2"]]),
                                    data["T"], (1.0 / cells, 1.0 / cells), [FINAL],
                                    boundaries=(("reflecting",) * 2,) * 2, dimension=2)
    return {"rho": solution["density"][-1], "u1": solution["velocity"][-1][0],
            "u2": solution["velocity"][-1][1], "T": solution["temperature"][-1]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    parser.add_argument("--out", required=True)
    parser.add_argument("--cells", type=numbers(5, kind=int, low_open=False), default=[16, 32])
    parser.add_argument("--reference", type=number(16, kind=int), default=256)
    args = parser.parse_args(argv)
    cells = sorted(args.cells)
    if any(args.reference % (2 * c) for c in cells):
        parser.error(f"--reference {args.reference} must be a multiple of twice every "
                     f"--cells value ({cells})")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    began = time.perf_counter()
    fine, coarse = reference(args.reference), reference(args.reference // 2)
    reference_seconds = time.perf_counter() - began
    rows, runs = [], {}
    for c in cells:
        runs[c], seconds = kinetic(c, out)
        row = {"cells": c, "seconds": round(seconds, 1),
               **refinement_row(runs, c, fine, coarse,
                                lambda fields, n: conserved_block_average(fields, n, 2))}
        rows.append(row)
        print(row, flush=True)
    write_csv(out / "shock_reflection_2d.csv", rows, list(rows[-1]))  # the last has every key
    fields = ("rho", "u1", "u2", "T")
    title = (f"Plane shock, M = {MACH:g} at 30 degrees, reflected from specular walls, "
             f"gamma = 2, eps = {KNUDSEN:g}, t = {FINAL}; reference R = {args.reference} "
             f"({reference_seconds:.0f} s)")
    lines = [title, "",
             "| cells | " + " | ".join(f"L1 {k}" for k in fields)
             + " | reference bar (rho, T) | change from C/2 (rho, T) | seconds |",
             "|---" * 8 + "|"]
    for row in rows:
        change = (f"{row['change_rho']:.2e}, {row['change_T']:.2e}" if "change_rho" in row
                  else "")
        lines.append(f"| {row['cells']} | " + " | ".join(f"{row[f'L1_{k}']:.3e}"
                                                          for k in fields)
                     + f" | {row['reference_bar_rho']:.1e}, {row['reference_bar_T']:.1e} | "
                     f"{change} | {row['seconds']} |")
    (out / "shock_reflection_2d.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    _figure(out / "shock_reflection_2d.png", runs[cells[-1]], fine, cells[-1],
            args.reference)
    return 0


def _figure(path, run: dict, truth: dict, cells: int, resolution: int) -> None:
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    from granframe.tools.studykit import save_figure

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), layout="constrained")
    for ax, values, n, title in ((axes[0], run["rho"], cells, f"kinetic, {cells}^2 cells"),
                                 (axes[1], truth["rho"], resolution,
                                  f"Euler, {resolution}^2 cells")):
        centres = (numpy.arange(n) + 0.5) / n
        mesh = ax.pcolormesh(centres, centres, values.T, shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="density")
        ax.set_aspect("equal")
        ax.set_title(f"{title}, t = {FINAL}", fontsize=9)
    averaged = conserved_block_average(truth, cells, 2)
    centres = (numpy.arange(cells) + 0.5) / cells
    fine = (numpy.arange(resolution) + 0.5) / resolution
    axes[2].plot(centres, run["rho"][:, 0], "o", ms=3,
                 label=f"kinetic {cells}^2, y = {centres[0]:.3f}")
    axes[2].plot(centres, averaged["rho"][:, 0], "s", ms=3, mfc="none",
                 label=f"Euler averaged onto {cells}^2")
    axes[2].plot(fine, truth["rho"][:, resolution // (2 * cells)], "-", lw=1,
                 label=f"Euler {resolution}^2 near y = {centres[0]:.3f}")
    axes[2].set_xlabel("x")
    axes[2].set_ylabel("density along the bottom row")
    axes[2].legend(fontsize=7)
    save_figure(fig, path, dpi=110)


if __name__ == "__main__":
    raise SystemExit(finish(main))
