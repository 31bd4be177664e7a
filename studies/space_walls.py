"""The cell next to a wall in a steady Couette flow (docs/space.md, "The cell next to a wall").

An elastic gas of Maxwell molecules (2D velocities, N = 16, S = 3.5, fast spectral operator
with the conservative correction, SSP RK2, eps = 0.08: mean free path
lambda = eps sqrt(pi T / 2) = 0.100 at rho = T = 1) between diffuse walls at T_w = 1 moving
along v_2 with -U/2 (x = 0) and +U/2 (x = 1), U = 0.5, MUSCL, dt at the transport's CFL
limit, from the Maxwellian moving with 0.38 (x - 1/2) along v_2 (near the steady profile)
to t = 6. In the steady state P_12 and the momentum flux along x are the same at every x;
the study compares the cells next to the walls with the bulk (the mean of the middle half
of the cells) at 8, 16, 32 and 64 cells (dx / lambda = 1.25 .. 0.16), with the walls' ghost
cells as granframe fills them (a linear extension through the wall,
:func:`granframe.space.boundaries._emitting_ghosts`) and, for comparison, with the even
extension f_{-1} = f_0 of the arriving values and the emission of the cell averages for the
leaving ones (``--even``, what the walls did before):

    python studies/space_walls.py                  # 8, 16, 32, 64 cells (about 25 min)
    python studies/space_walls.py --cells 8 16     # a quick look
    python studies/space_walls.py --even           # the even extension

Each row: the wall-cell P_12 over the bulk P_12 at both walls, P_11 of the wall cell over the
bulk as recorded and with the node -L left out (its content, which the collision operator
puts there, counts with the weight L^2 = 59.6 in the recorded P_11; it carries no
momentum flux), the wall momentum flux per unit time P_12 and P_11 (left wall, last step),
the bulk P_12 over the wall flux, and the change of P_12 over the last quarter of the run
relative to the bulk (how steady it is).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import time

import numpy

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space import boundaries
from granframe.tools.studykit import finish, number
from granframe.velocity.grid import VelocityGrid

GRID = {"dimension": 2, "n_modes": 16, "support_radius": 3.5}
KNUDSEN = 0.08
SPEED = 0.5
FINAL = 6.0
CELLS = (8, 16, 32, 64)


def shear_maxwellian(x, v1, v2):
    """The unit Maxwellian at T = 1 moving along v_2 with 0.76 U (x - 1/2)."""
    return numpy.exp(-(v1 ** 2 + (v2 - 0.76 * SPEED * (x - 0.5)) ** 2) / 2) / (2 * math.pi)


def couette_description(cells: int, final: float = FINAL) -> RunDescription:
    """The Couette run of the module notes on ``cells`` cells, dt the largest divisor of
    ``final`` below the CFL limit dx / (L - h)."""
    grid = VelocityGrid(**GRID)
    limit = (1.0 / cells) / (grid.half_width - grid.spacing)
    return RunDescription(
        title=f"Couette flow, eps = {KNUDSEN:g}, U = {SPEED:g}, {cells} cells",
        grid=GRID, kernel="maxwell", restitution={"name": "constant", "value": 1.0},
        initial={"name": "space_function", "function": shear_maxwellian},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", conservative=True,
        knudsen=KNUDSEN, time_step=final / math.ceil(final / limit), final_time=final,
        output={"snapshot_interval": final},
        space={"cells": cells, "reconstruction": "muscl",
               "left": {"name": "diffuse", "temperature": 1.0, "velocity": -0.5 * SPEED},
               "right": {"name": "diffuse", "temperature": 1.0, "velocity": 0.5 * SPEED}})


@contextlib.contextmanager
def even_extension():
    """The diffuse wall's ghost cells as the emission of each cell from its own arriving
    values, which keeps the arriving values themselves: f_{-(k+1)} = f_k there."""
    linear = boundaries.Diffuse.ghosts
    boundaries.Diffuse.ghosts = (lambda self, inside, grid, xp, *, t=0.0, side="left":
                                 self.emit(inside, grid, xp, t=t, side=side))
    try:
        yield
    finally:
        boundaries.Diffuse.ghosts = linear


def wall_cell_row(ds) -> dict:
    """The row of the module notes from a run's dataset."""
    cells = ds.sizes["x"]
    grid = VelocityGrid(**GRID)
    dt = float(ds.dt.values[-1])
    P = ds.pressure_tensor.values
    shear, normal = P[-1, :, 0, 1], P[-1, :, 0, 0]
    middle = slice(cells // 4, cells - cells // 4)
    bulk = shear[middle].mean()
    f = ds.f.values[-1]
    edge = grid.half_width ** 2 * f[:, 0].sum(axis=-1) * grid.cell_volume   # L^2 x node -L
    flux = ds.wall_momentum.values[-1, 0] / dt
    quarter = (3 * len(P)) // 4
    return {"cells": cells, "dx_lambda": 1.0 / cells / (KNUDSEN * math.sqrt(0.5 * math.pi)),
            "left": shear[0] / bulk, "right": shear[-1] / bulk,
            "P11": normal[0] / normal[middle].mean(),
            "P11_moving": (normal[0] - edge[0]) / (normal - edge)[middle].mean(),
            "flux_P12": flux[1], "flux_P11": flux[0], "bulk_flux": bulk / flux[1],
            "unsteady": numpy.abs(shear - P[quarter, :, 0, 1]).max() / abs(bulk)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=number(1, kind=int, low_open=False), nargs="+", default=list(CELLS))
    parser.add_argument("--even", action="store_true",
                        help="the even extension of the arriving values (for comparison)")
    args = parser.parse_args(argv)
    print("| cells | dx/lambda | P_12 wall cell / bulk (left, right) | |1 - ratio| order "
          "| P_11 / bulk (recorded, without node -L) | wall flux P_12, P_11 "
          "| bulk P_12 / wall flux | unsteady |")
    print("|---|---|---|---|---|---|---|---|")
    previous = None
    for cells in args.cells:
        start = time.time()
        with even_extension() if args.even else contextlib.nullcontext():
            ds = Simulation(couette_description(cells)).run(None, progress=False).dataset
        r = wall_cell_row(ds)
        error = abs(1.0 - 0.5 * (r["left"] + r["right"]))
        order = "" if previous is None else f"{math.log2(previous / error):.2f}"
        previous = error
        print(f"| {cells} | {r['dx_lambda']:.3f} | {r['left']:.4f}, {r['right']:.4f} | {order} "
              f"| {r['P11']:.4f}, {r['P11_moving']:.4f} | {r['flux_P12']:.6f}, "
              f"{r['flux_P11']:.6f} | {r['bulk_flux']:.4f} | {r['unsteady']:.1e} |  "
              f"({time.time() - start:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
