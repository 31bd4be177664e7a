"""Isotropy of the rectangle: a density mode and a shear mode along the diagonal of a
periodic square against the same modes on a line along that direction.

On the periodic unit square the wave vector [1, 1] has wavelength 1/sqrt(2) along the
diagonal e = (1, 1)/sqrt(2). The same physics on a line is the mode 1 on the periodic
interval [0, 1/sqrt(2)], with v_1 along e; for the shear mode the transverse velocity
(component 2 of the square's mode, along (-1, 1)/sqrt(2)) is the line's u_2. The gas:
inelastic Maxwell molecules, e = 0.9, eps = 0.05, the direct spectral operator (isotropic
to round-off: the fast one at coarse quadratures is not, docs/space.md "Two dimensions"),
2D N = 24, S = 3.5, SSP RK2 collisions, MUSCL, dt at each run's CFL limit (so that it
refines with the cells), to t = 0.1.

The line's run on ``--line`` cells (and on half of them, its own error bar) gives, through
its Fourier series in s = (x + y)/sqrt(2) (the cell averages deconvolved, exact for the
band-limited profile), the reference profile; the square's cells are compared with its
averages over each cell (6 x 6 Gauss points). Reported for each C x C square: the largest
and the mean differences of rho, u along e, u across e and T, and the observed orders
between successive C: the square's own space error, which falls at the scheme's order
until the velocity grid's anisotropy (the nodes are not invariant under the rotation by
45 degrees) sets a floor.

    python studies/isotropy_2d.py --out DIR [--cells 8,16,32] [--line 128]

writes ``isotropy_2d.csv`` and ``isotropy_2d.md`` there (23 minutes on two cores beside
another study).
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
from granframe.tools.studykit import finish, number, numbers, write_csv
from granframe.velocity.grid import VelocityGrid

GRID = {"dimension": 2, "n_modes": 24, "support_radius": 3.5}
FINAL = 0.1
KNUDSEN = 0.05
MODES = {"density": {"field": "density", "amplitude": 0.1},
         "shear": {"field": "velocity", "component": 2, "amplitude": 0.1}}
FIELDS = ("rho", "u_along", "u_across", "T")


def _description(space: dict, mode: dict, dt: float) -> RunDescription:
    return RunDescription.from_dict({
        "title": "isotropy", "grid": GRID, "kernel": "maxwell",
        "restitution": {"name": "constant", "value": 0.9},
        "initial": {"name": "sinusoidal_mode", **mode}, "operator": {"name": "direct_spectral"},
        "integrator": "ssp_rk2", "knudsen": KNUDSEN, "time_step": dt, "final_time": FINAL,
        "output": {"snapshot_interval": FINAL}, "space": space})


def _step(spacing: tuple) -> float:
    """The largest dt dividing FINAL within the CFL limit of cells of widths ``spacing``
    (one width: a line's; two: a square's): each run at its own limit, so that dt and the
    cells refine together."""
    grid = VelocityGrid(**GRID)
    limit = (box_step_limit(grid, spacing, 0.5) if len(spacing) > 1 else
             2 * 0.5 * spacing[0] / (grid.half_width - grid.spacing))
    return FINAL / math.ceil(FINAL / limit * (1 - 1e-12))


def square(cells: int, mode: str) -> dict:
    """The fields at t = FINAL of the square's run, (C, C) each, the velocity split along
    and across the diagonal."""
    d = _description({"cells": [cells, cells], "reconstruction": "muscl"},
                     {**MODES[mode], "mode": [1, 1]}, _step((1.0 / cells,) * 2))
    ds = Simulation(d).run(None, progress=False).dataset
    u = ds.velocity.values[-1]
    return {"rho": ds.density.values[-1], "u_along": (u[..., 0] + u[..., 1]) / math.sqrt(2),
            "u_across": (u[..., 1] - u[..., 0]) / math.sqrt(2), "T": ds.temperature.values[-1]}


def line(cells: int, mode: str) -> dict:
    """The fields at t = FINAL of the line's run on [0, 1/sqrt(2)], (cells,) each."""
    d = _description({"cells": cells, "length": 1.0 / math.sqrt(2), "reconstruction": "muscl"},
                     {**MODES[mode], "mode": 1}, _step((1.0 / (math.sqrt(2) * cells),)))
    ds = Simulation(d).run(None, progress=False).dataset
    u = ds.velocity.values[-1]
    return {"rho": ds.density.values[-1], "u_along": u[:, 0], "u_across": u[:, 1],
            "T": ds.temperature.values[-1]}


def profile(averages):
    """The band-limited periodic function of s in [0, 1) (in periods) whose averages over
    the n equal cells [j/n, (j + 1)/n] are ``averages``: its Fourier coefficients, the
    averages' divided by exp(i pi k/n) sinc(k/n)."""
    n = len(averages)
    coefficients = numpy.fft.rfft(averages) / n
    k = numpy.arange(len(coefficients))
    # the average of exp(2 pi i k s) over [j/n, (j + 1)/n] is exp(2 pi i k j/n) times
    # exp(i pi k/n) sinc(k/n)
    coefficients = coefficients / (numpy.sinc(k / n) * numpy.exp(1j * numpy.pi * k / n))

    def evaluate(s):
        s = numpy.asarray(s, dtype=float)
        phases = numpy.exp(2j * numpy.pi * numpy.multiply.outer(s, k))
        weights = numpy.where(k == 0, 1.0, 2.0)
        if n % 2 == 0:
            weights[-1] = 1.0
        return (phases * (weights * coefficients)).real.sum(axis=-1)

    return evaluate


def on_square(reference: dict, cells: int) -> dict:
    """The reference profiles averaged over every cell of the C x C square (6 x 6
    Gauss-Legendre points): the phase in periods is s = x + y."""
    nodes, weights = numpy.polynomial.legendre.leggauss(6)
    edges = numpy.arange(cells) / cells
    points = (edges[:, None] + 0.5 * (nodes[None, :] + 1.0) / cells)     # (C, 6)
    w = 0.5 * weights
    phase = points[:, None, :, None] + points[None, :, None, :]         # (C, C, 6, 6)
    out = {}
    for name, values in reference.items():
        f = profile(values)
        out[name] = (f(phase % 1.0) * w[:, None] * w[None, :]).sum(axis=(-2, -1))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder of the tables")
    parser.add_argument("--cells", type=numbers(5, low_open=False, kind=int),
                        default=[8, 16, 32], help="cells a side of the squares")
    parser.add_argument("--line", type=number(8, low_open=False, kind=int), default=128,
                        help="cells of the line's reference run (and half of them)")
    args = parser.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cells = sorted(args.cells)
    rows = []
    for mode in MODES:
        began = time.perf_counter()
        fine, coarse = line(args.line, mode), line(args.line // 2, mode)
        previous = None
        for c in cells:
            run = square(c, mode)
            truth = on_square(fine, c)
            bar = on_square(coarse, c)
            row = {"mode": mode, "cells": c, "dt": _step((1.0 / c,) * 2)}
            for name in FIELDS:
                error = numpy.abs(run[name] - truth[name])
                row[f"max_{name}"] = float(error.max())
                row[f"mean_{name}"] = float(error.mean())
                row[f"bar_{name}"] = float(numpy.abs(bar[name] - truth[name]).max())
                if previous is not None:
                    row[f"order_{name}"] = (math.log(previous[f"mean_{name}"]
                                                     / row[f"mean_{name}"])
                                            / math.log(c / previous["cells"]))
            row["seconds"] = round(time.perf_counter() - began, 1)
            rows.append(row)
            previous = row
            print({k: (f"{v:.3g}" if isinstance(v, float) else v) for k, v in row.items()},
                  flush=True)
    write_csv(out / "isotropy_2d.csv", rows, sorted({k for r in rows for k in r},
                                                    key=lambda k: list(rows[-1]).index(k)
                                                    if k in rows[-1] else 99))
    lines = [(f"Modes along the diagonal of the periodic unit square against the line "
              f"({args.line} cells), t = {FINAL}, eps = {KNUDSEN}, e = 0.9, 2D N = 24, "
              "direct operator, MUSCL, dt at each run's CFL limit"), "",
             ("| mode | cells | mean rho | order | mean u along | order | mean u across | "
              "order | mean T | order | max rho | line's bar (rho) |"),
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        def order(name, r=r):
            value = r.get(f"order_{name}")
            return "" if value is None else f"{value:.2f}"
        lines.append(f"| {r['mode']} | {r['cells']}^2 | {r['mean_rho']:.3g} | {order('rho')} "
                     f"| {r['mean_u_along']:.3g} | {order('u_along')} | "
                     f"{r['mean_u_across']:.3g} | {order('u_across')} | {r['mean_T']:.3g} | "
                     f"{order('T')} | {r['max_rho']:.3g} | {r['bar_rho']:.2g} |")
    text = "\n".join(lines) + "\n"
    (out / "isotropy_2d.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
