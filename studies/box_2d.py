"""A collisionless gas in a square box with four diffuse walls at different temperatures
and velocities, against its exact steady state on the velocity nodes (docs/space.md, "Two
dimensions", "The collisionless box").

The box [0, 1]^2: the wall x = 0 at T = 1 at rest, x = 1 at T = 1.5 at rest, y = 0 at
T = 1.2 sliding at +0.3 along v_1, y = 1 at T = 0.8 sliding at -0.2 along v_1 (full
accommodation). 2D velocities N = 16, S = 3.5, no collisions (``space.collisions =
false``), MUSCL, dt the transport's CFL limit on both axes, to t = 24. The exact steady
state (:class:`granframe.space.exact_box.FreeMolecularBox`, derived in its module notes)
is solved with 512 panels a wall and averaged over each cell on a 512 x 512 midpoint grid;
its own bar is the difference from 256 panels and a 256 x 256 grid.

The runs start from the exact state's cell averages (``--start exact``, the default): the
exchange between the walls has slow modes (the view-factor operator's second eigenvalue is
close to 1), which the scheme's numerical diffusion damps on coarse cells only, so that from
the Maxwellian at rest at T = 1 (``--start maxwellian``) a run on C x C cells needs a time
that grows with C to settle (12 x 12 cells: its mean T is 3e-3 below the exact one at
t = 24, 1e-4 at t = 96). From the exact state, what a run moves away from it by t = 24 is
the scheme's error at steady state. Reported for each C of ``--cells``: the mean over the
cells of |rho - rho_exact|, |u_1 - ..|, |u_2 - ..|, |T - ..| and of int |f - f_exact| dv,
the observed orders between successive C, and the L1 change of f over the last 2.4 (how
steady the run is). Two more measures tell a discontinuity smeared by the scheme from an
error that stays:

- ``bound_T``: the mean over the cells of sum_j |dT/df_j| |f_j - f_exact,j| (dT/df_j =
  h^d (|v_j - u|^2 / d - T) / rho at the exact state), which bounds |T - T_exact| to first
  order: the cells' T error cannot stay above it, nor fall slower than it once the
  nodes' errors no longer cancel in T;
- ``block<B>_<field>``: the fields of the run and of the exact state both averaged onto
  the same fixed grid of B x B blocks (B = 4, 8 blocks a side, whatever the cells) before
  they are compared: the error in the mean over a fixed region, which a conservative
  scheme's smearing of a discontinuity moves only by the mass its band carries across the
  region's edges.

    python studies/box_2d.py --out DIR [--cells 8,16,32] [--start exact] [--reconstruction muscl]

writes ``box_2d.csv``, ``box_2d.md``, ``box_2d.png`` (rho, T and the speed of the finest
run and of the exact state) and each run's f at t = 24 (``box_<C>.npy``). About 15 minutes
for 8, 16, 32 cells, and 99 more for 64 (each run on one core, beside other jobs).
"""

from __future__ import annotations

import argparse
import itertools
import math
import pathlib
import time

import numpy

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space.exact_box import FreeMolecularBox
from granframe.space.transport import box_step_limit
from granframe.tools.studykit import finish, mean_distances, numbers, write_csv
from granframe.velocity.grid import VelocityGrid

GRID = {"dimension": 2, "n_modes": 16, "support_radius": 3.5}
FINAL = 24.0
#: (T_w, U_w) of the walls left, right, bottom, top
WALLS = ((1.0, 0.0), (1.5, 0.0), (1.2, 0.3), (0.8, -0.2))
FIELDS = ("rho", "u1", "u2", "T")
#: the fixed grids of blocks (blocks a side) the errors of the means over regions are
#: measured on
BLOCKS = (4, 8)


def description(cells: int, final: float = FINAL,
                reconstruction: str = "muscl") -> RunDescription:
    """The collisionless run on ``cells`` x ``cells`` cells, ten snapshots."""
    grid = VelocityGrid(**GRID)
    limit = box_step_limit(grid, (1.0 / cells, 1.0 / cells), 0.5)
    steps = 10 * math.ceil(final / limit / 10 * (1 - 1e-12))
    walls = {side: {"name": "diffuse", "temperature": t, "velocity": u}
             for side, (t, u) in zip(("left", "right", "bottom", "top"), WALLS)}
    return RunDescription.from_dict({
        "title": f"collisionless box, four diffuse walls, {cells}^2 cells",
        "grid": GRID, "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "maxwellian"}, "operator": {"name": "fast_spectral"},
        "backend": {"name": "numpy", "threads": 1}, "time_step": final / steps,
        "final_time": final, "output": {"snapshot_interval": final / 10},
        "space": {"cells": [cells, cells], "collisions": False,
                  "reconstruction": reconstruction, **walls}})


def stepped(cells: int, start=None, reconstruction: str = "muscl") -> tuple:
    """f at t = 24 of the run on ``cells`` x ``cells`` cells from ``start`` (cell averages;
    None: the description's Maxwellian), the relative L1 change of f over the last tenth
    of the run, and the steps."""
    d = description(cells, reconstruction=reconstruction)
    problem = Simulation(d).problem
    state = problem.state(problem.f0 if start is None else start)
    steps = round(d.final_time / d.time_step)
    before = None
    for k in range(steps):
        if k == steps - steps // 10:
            before = problem.snapshot(state)
        state = problem.step(k * d.time_step, state, d.time_step)
    f = problem.snapshot(state)
    return f, float(numpy.abs(f - before).sum() / numpy.abs(f).sum()), steps


def fields(grid, f) -> dict:
    """rho, u_1, u_2, T (C, C) of cell averages f (C, C, *grid)."""
    counts = f.shape[:2]
    rows = [grid.moments(cell) for cell in f.reshape((-1,) + tuple(grid.shape))]
    return {"rho": numpy.array([r["mass"] for r in rows]).reshape(counts),
            "u1": numpy.array([r["bulk_velocity"][0] for r in rows]).reshape(counts),
            "u2": numpy.array([r["bulk_velocity"][1] for r in rows]).reshape(counts),
            "T": numpy.array([r["temperature"] for r in rows]).reshape(counts)}


def temperature_bound(grid, f, exact) -> float:
    """The mean over the cells of sum_j |dT/df_j| |f_j - exact_j|, dT/df_j = h^d (|v_j - u|^2
    / d - T) / rho at the fields of ``exact`` (cell averages (C, C, *grid) both): the first-
    order bound of |T(f) - T(exact)| that the nodes' errors reach when they do not cancel."""
    d, h = grid.dimension, grid.cell_volume
    points = numpy.asarray(grid.points(), dtype=float)
    mesh = numpy.meshgrid(*([points] * d), indexing="ij")
    state = fields(grid, exact)
    velocity = (state["u1"], state["u2"]) + (0.0,) * (d - 2)
    spread = sum((m - numpy.asarray(u)[(...,) + (None,) * d]) ** 2
                 for m, u in zip(mesh, velocity))
    rho, temperature = (state[k][(...,) + (None,) * d] for k in ("rho", "T"))
    weight = h * numpy.abs(spread / d - temperature) / rho
    return float((weight * numpy.abs(f - exact)).sum(axis=tuple(range(2, 2 + d))).mean())


def averaged(values, cells: int):
    """Cell averages (R, R, ...) of a finer grid averaged onto ``cells`` x ``cells``."""
    k = values.shape[0] // cells
    return values.reshape((cells, k, cells, k) + values.shape[2:]).mean(axis=(1, 3))


def errors(rows, runs, grid, fine, rough) -> None:
    """Add to each row (``cells``) the errors of its run (``runs[cells]``, f at the end)
    from the exact state's cell averages on the finest cells (``fine``; ``rough``: the
    coarser exact state, for its bar): the fields' and f's mean L1 distances, the bound
    on T's, the distances over the fixed blocks, and the orders between successive
    rows."""
    for row in rows:
        c = row["cells"]
        exact_f = averaged(fine, c)
        truth = fields(grid, exact_f)
        row.update({f"L1_{k}": v for k, v in mean_distances(fields(grid, runs[c]), truth).items()})
        row.update({f"exact_bar_{k}": v for k, v in
                    mean_distances(fields(grid, averaged(rough, c)), truth).items()})
        row["L1_f"] = float(numpy.abs(runs[c] - exact_f).sum(axis=(2, 3)).mean()
                            * grid.cell_volume)
        row["bound_T"] = temperature_bound(grid, runs[c], exact_f)
        for b in BLOCKS:
            if c % b == 0:
                row.update({f"block{b}_{k}": v for k, v in mean_distances(
                    fields(grid, averaged(runs[c], b)),
                    fields(grid, averaged(fine, b))).items()})
    measures = [f"L1_{k}" for k in FIELDS + ("f",)] + ["bound_T"] + [
        f"block{b}_{k}" for b in BLOCKS for k in FIELDS]
    for previous, row in itertools.pairwise(rows):
        ratio = math.log(row["cells"] / previous["cells"])
        row.update({f"order_{m}": math.log(previous[m] / row[m]) / ratio
                    for m in measures if m in previous and m in row})


def _orders(row, names) -> str:
    """The row's orders of the measures ``names``, "—" where it has none."""
    return ", ".join(f"{row[f'order_{m}']:.2f}" if f"order_{m}" in row else "—"
                     for m in names)


def markdown(rows, start: str, reconstruction: str, exact_seconds: float) -> str:
    """The rows of :func:`errors` as markdown tables: the cells' errors with their orders,
    then those over each of :data:`BLOCKS`."""
    lines = [(f"collisionless box, walls (T, U) = {WALLS}, from the {start} state to "
              f"t = {FINAL}, {reconstruction}; exact state {exact_seconds:.0f} s"), "",
             "Mean over the cells of the differences from the exact state (orders below):", "",
             ("| cells | rho | u1 | u2 | T | int abs(f - f_exact) dv | bound on T | exact bar "
              "rho, T | change over the last 2.4 | seconds |"),
             "|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['cells']}^2 | {row['L1_rho']:.3g} | {row['L1_u1']:.3g} | "
                     f"{row['L1_u2']:.3g} | {row['L1_T']:.3g} | {row['L1_f']:.3g} | "
                     f"{row['bound_T']:.3g} | {row['exact_bar_rho']:.1g}, "
                     f"{row['exact_bar_T']:.1g} | {row['steady_change']:.1g} | "
                     f"{row['seconds']} |")
        if "order_L1_rho" in row:
            names = [f"L1_{k}" for k in FIELDS + ("f",)] + ["bound_T"]
            lines.append(f"| order | {_orders(row, names).replace(', ', ' | ')} | | | |")
    for b in BLOCKS:
        lines += ["", f"The fields averaged onto a fixed grid of {b} x {b} blocks, then compared:", "",
                  "| cells | rho | u1 | u2 | T | orders rho, u1, u2, T |", "|---|---|---|---|---|---|"]
        for row in rows:
            if f"block{b}_rho" in row:
                lines.append(f"| {row['cells']}^2 | " + " | ".join(
                    f"{row[f'block{b}_{k}']:.3g}" for k in FIELDS) + " | " + _orders(
                    row, [f"block{b}_{k}" for k in FIELDS]) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder of the table and the figure")
    parser.add_argument("--cells", type=numbers(5, low_open=False, kind=int),
                        default=[8, 16, 32], help="cells a side (default 8,16,32)")
    parser.add_argument("--start", choices=("exact", "maxwellian"), default="exact",
                        help="the initial data: the exact state's cell averages (default) or "
                             "the Maxwellian at rest at T = 1")
    parser.add_argument("--reconstruction", choices=("muscl", "weno5", "upwind"),
                        default="muscl", help="the transport's reconstruction (default muscl)")
    args = parser.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cells = sorted(args.cells)
    finest = cells[-1]
    if 256 % finest or any(finest % c for c in cells):
        parser.error(f"--cells {cells}: each must divide the largest, and the largest 256 "
                     "(the exact state's grids of 512 and 256 points a side)")
    grid = VelocityGrid(**GRID)
    rest = Simulation(description(cells[0])).problem.f0[0, 0]   # v = 0 keeps f0 there
    began = time.perf_counter()
    exact = FreeMolecularBox(grid, (1.0, 1.0), WALLS, 1.0, rest, panels=512)
    fine = exact.cell_averages((finest,) * 2, 512 // finest)    # 512 x 512 points
    coarse = FreeMolecularBox(grid, (1.0, 1.0), WALLS, 1.0, rest, panels=256)
    rough = coarse.cell_averages((finest,) * 2, 256 // finest)  # 256 x 256 points
    exact_seconds = time.perf_counter() - began
    rows, runs = [], {}
    for c in cells:
        began = time.perf_counter()
        start = averaged(fine, c) if args.start == "exact" else None
        f, change, steps = stepped(c, start, args.reconstruction)
        runs[c] = f
        numpy.save(out / f"box_{c}.npy", f)
        rows.append({"cells": c, "steps": steps, "seconds": round(time.perf_counter() - began, 1),
                     "steady_change": change})
        print(rows[-1], flush=True)
    errors(rows, runs, grid, fine, rough)
    write_csv(out / "box_2d.csv", rows, list(rows[-1]))
    text = markdown(rows, args.start, args.reconstruction, exact_seconds)
    (out / "box_2d.md").write_text(text)
    print(text)
    _figure(out / "box_2d.png", grid, runs[cells[-1]], averaged(fine, cells[-1]), cells[-1])
    return 0


def _figure(path, grid, run, truth, cells: int) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 8), layout="constrained")
    axes = fig.subplots(2, 3)
    centres = (numpy.arange(cells) + 0.5) / cells
    got, want = fields(grid, run), fields(grid, truth)
    for column, name in enumerate(("rho", "T", "speed")):
        pair = [(got, f"run, {cells}^2 cells"), (want, "exact steady state")]
        values = [numpy.hypot(v["u1"], v["u2"]) if name == "speed" else v[name]
                  for v, _ in pair]
        low, high = min(v.min() for v in values), max(v.max() for v in values)
        for row, (v, (_, title)) in enumerate(zip(values, pair)):
            ax = axes[row, column]
            mesh = ax.pcolormesh(centres, centres, v.T, shading="nearest", vmin=low,
                                 vmax=high)
            ax.set(title=f"{name}, {title}", xlabel="x", ylabel="y", aspect="equal")
        fig.colorbar(mesh, ax=axes[:, column], label=name)
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    raise SystemExit(finish(main))
