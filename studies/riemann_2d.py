"""The Euler limit on a rectangle: a two-dimensional Riemann problem at eps = 1e-4 against
an independent finite-volume solution of the Euler equations.

The data are Liska & Wendroff's configuration 4 (R. Liska & B. Wendroff, SIAM J. Sci.
Comput. 25 (2003) 995; Lax & Liu's configuration 4, four shocks): on [0, 1]^2 about
(1/2, 1/2), (rho, u_1, u_2, p) = (1.1, 0, 0, 1.1) upper right, (0.5065, 0.8939, 0, 0.35)
upper left, (1.1, 0.8939, 0.8939, 1.1) lower left, (0.5065, 0, 0.8939, 0.35) lower right,
as Maxwellians of T = p / rho, to t = 0.25, with specular walls on the four sides. The gas
is granframe's with 2D velocities, so the Euler equations it tends to have gamma = 2 (not
the paper's 1.4): the waves differ from the paper's figures, and the reference is the
Euler equations with gamma = 2 and reflecting walls solved here by
:func:`granframe.theory.euler.euler_quadrants` (MUSCL-minmod, HLL, SSP RK2; no code
shared with the kinetic scheme) on R x R cells.

The kinetic runs: elastic Maxwell molecules, eps = 1e-4, penalised ARS(2,2,2) with the
conservative correction, the fast spectral operator on 2D N = 48, S = 3.5, MUSCL, dt the
transport's CFL limit on both axes, on C x C cells for each C of ``--cells``. The gas
leaving the walls x = 0 and y = 0 cools the region next to the corner (0, 0): T = 0.149
at (0.09, 0.09) in the Euler solution on 64 x 64 cells (sqrt(T) = 0.39). N = 32 (h = 0.48)
does not resolve it: its 32 x 32 run stopped on a singular Gram system of the conservative
correction (a cell too cold for its weight); N = 48 (h = 0.32) runs. Reported for each C:
the L1 distance (mean over the cells) of rho, u_1, u_2 and T from the reference averaged
onto the C x C cells, and the same between the kinetic runs of successive C (the kinetic
scheme's own refinement); the reference's own error bar is the distance of its R / 2 run
from its R run on the kinetic cells.

    python studies/riemann_2d.py --out DIR [--cells 16,32] [--reference 256]

writes ``riemann_2d.csv``, ``riemann_2d.md`` and ``riemann_2d.png`` (density maps of the
finest kinetic run and of the reference, and both along the diagonal) there. About 35
minutes on two cores for 16 and 32 cells and R = 256.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import time

import numpy

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space.transport import box_step_limit
from granframe.theory.cells import conserved_block_average
from granframe.theory.euler import LISKA_WENDROFF_4, euler_quadrants
from granframe.tools.studykit import finish, number, numbers, refinement_row, write_csv
from granframe.velocity.grid import VelocityGrid

GRID = {"dimension": 2, "n_modes": 48, "support_radius": 3.5}
FINAL = 0.25
KNUDSEN = 1e-4
STATES = LISKA_WENDROFF_4
FIELDS = ("rho", "u1", "u2", "T")


def _state(rho, u1, u2, p) -> dict:
    return {"density": rho, "velocity": [u1, u2], "temperature": p / rho}


def description(cells: int = 32, quick: bool = False) -> RunDescription:
    """The kinetic run on ``cells`` x ``cells`` cells (``quick``: 16 cells, to t = 0.05)."""
    if quick:
        cells = 16
    final = 0.05 if quick else FINAL
    grid = VelocityGrid(**GRID)
    limit = box_step_limit(grid, (1.0 / cells, 1.0 / cells), 0.5)
    steps = math.ceil(final / limit * (1 - 1e-12))
    return RunDescription.from_dict({
        "title": f"Liska-Wendroff 4, gamma = 2, eps = {KNUDSEN:g}, {cells} x {cells} cells",
        "grid": GRID, "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "quadrants", **{name: _state(*values)
                                            for name, values in STATES.items()}},
        "operator": {"name": "fast_spectral"}, "integrator": "penalised_ars222",
        "conservative": True, "knudsen": KNUDSEN, "time_step": final / steps,
        "final_time": final, "output": {"snapshot_interval": final},
        "space": {"cells": [cells, cells], "reconstruction": "muscl", "left": "specular",
                  "right": "specular", "bottom": "specular", "top": "specular"}})


def kinetic(cells: int, out: pathlib.Path | None = None) -> tuple[dict, float]:
    """The fields at t = 0.25 of the kinetic run on ``cells`` x ``cells`` cells, and its
    wall seconds."""
    began = time.perf_counter()
    store = None if out is None else out / f"kinetic_{cells}.zarr"
    result = Simulation(description(cells)).run(store, progress=False, overwrite=True)
    import granframe

    ds = result.dataset if store is None else granframe.open_run(store)
    velocity = ds.velocity.values[-1]
    return ({"rho": ds.density.values[-1], "u1": velocity[..., 0], "u2": velocity[..., 1],
             "T": ds.temperature.values[-1]}, time.perf_counter() - began)


def reference(cells: int, dimension: int = 2) -> dict:
    """The Euler equations on ``cells`` x ``cells`` cells to t = 0.25, gamma = (d + 2) / d
    of the velocity ``dimension`` d (2: gamma = 2), reflecting walls."""
    return euler_quadrants(STATES, cells, FINAL, dimension=dimension)


def averaged(fields: dict, cells: int, dimension: int = 2) -> dict:
    """Fields of R x R cells averaged onto ``cells`` x ``cells`` through the conserved
    quantities (:func:`granframe.theory.cells.conserved_block_average`)."""
    return conserved_block_average(fields, cells, dimension)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder of the tables and the figure")
    parser.add_argument("--cells", type=numbers(8, low_open=False, kind=int),
                        default=[16, 32], help="kinetic cells a side (default 16,32)")
    parser.add_argument("--reference", type=number(16, low_open=False, kind=int),
                        default=256, help="cells a side of the Euler reference (default 256)")
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
               **refinement_row(runs, c, fine, coarse, averaged)}
        rows.append(row)
        print(row, flush=True)
    write_csv(out / "riemann_2d.csv", rows, list(rows[-1]))   # the last row has every key
    lines = [(f"Liska-Wendroff 4 with gamma = 2, t = {FINAL}, eps = {KNUDSEN:g}; reference: "
              f"Euler FV on {args.reference}^2 ({reference_seconds:.0f} s for it and its "
              f"{args.reference // 2}^2 run)"), "",
             ("| cells | L1 rho | L1 u1 | L1 u2 | L1 T | reference bar rho | change rho | "
              "seconds |"), "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['cells']}^2 | {row['L1_rho']:.4g} | {row['L1_u1']:.4g} | "
                     f"{row['L1_u2']:.4g} | {row['L1_T']:.4g} | "
                     f"{row['reference_bar_rho']:.2g} | "
                     f"{row.get('change_rho', float('nan')):.4g} | {row['seconds']} |")
    text = "\n".join(lines) + "\n"
    (out / "riemann_2d.md").write_text(text)
    print(text)
    _figure(out / "riemann_2d.png", runs[cells[-1]], fine, cells[-1], args.reference)
    return 0


def _figure(path, run: dict, truth: dict, cells: int, resolution: int) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 4.4), layout="constrained")
    axes = fig.subplots(1, 3)
    low, high = min(run["rho"].min(), truth["rho"].min()), max(run["rho"].max(),
                                                               truth["rho"].max())
    for ax, values, n, title in ((axes[0], run["rho"], cells, f"kinetic, {cells}^2 cells"),
                                 (axes[1], truth["rho"], resolution,
                                  f"Euler FV, {resolution}^2 cells")):
        centres = (numpy.arange(n) + 0.5) / n
        mesh = ax.pcolormesh(centres, centres, values.T, shading="nearest", vmin=low,
                             vmax=high)
        ax.contour(centres, centres, values.T, levels=20, colors="k", linewidths=0.4)
        ax.set(title=f"density, {title}", xlabel="x", ylabel="y", aspect="equal")
    fig.colorbar(mesh, ax=axes[:2], label="ρ")
    diagonal = (numpy.arange(cells) + 0.5) / cells
    axes[2].plot(diagonal, numpy.diag(run["rho"]), "o", ms=3, label=f"kinetic {cells}^2")
    fine = (numpy.arange(resolution) + 0.5) / resolution
    axes[2].plot(fine, numpy.diag(truth["rho"]), "-", lw=1, label=f"Euler {resolution}^2")
    axes[2].set(xlabel="x = y", ylabel="ρ on the diagonal", title=f"t = {FINAL}")
    axes[2].legend()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    raise SystemExit(finish(main))
