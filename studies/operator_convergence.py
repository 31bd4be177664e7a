"""Convergence tables of the spectral operators (docs/validation.md).

Run: ``python studies/operator_convergence.py`` (about two minutes on 2 cores).
Prints Markdown tables:

1. BKW (elastic Maxwell molecules): max |Q(f) - df/dt| / max |df/dt| at t = 6.5
   against N, fast method with quadrature refined so that N is the limit.
2. Fast against direct (hard spheres, Toscani law) against N_rho and M.
3. Heated Maxwell molecules (the review's test) and the effect of R.
"""

from __future__ import annotations

import time

import numpy

import granframe as gf
from granframe.model.exact import bkw
from granframe.backends import preferred_backend
from granframe.testing import heated_maxwell_error


def backend():
    return gf.array_backend(preferred_backend())


def bkw_table():
    rows = ["| d | N | h | fast, max rel. error | direct, max rel. error |", "|---|---|---|---|---|"]
    for dimension, sizes, sphere in [(2, (16, 24, 32, 48, 64), lambda n: gf.CircleTrapezoid(32)),
                                     (3, (16, 24, 32, 40), lambda n: gf.Lebedev(17 if n < 40
                                                                                 else 21))]:
        for n in sizes:
            grid = gf.VelocityGrid(dimension, n, 5.0)
            f, dfdt = bkw(grid, 6.5)
            kernel, law = gf.collision_kernel("maxwell"), gf.restitution_law("constant", value=1.0)
            q = gf.collision_operator("fast_spectral", grid, kernel, law, backend=backend(),
                                      radial_points=48, sphere=sphere(n))(f)
            scale = numpy.abs(dfdt).max()
            direct = "—"
            if (dimension == 2 and n <= 32) or (dimension == 3 and n <= 12):
                qd = gf.collision_operator("direct_spectral", grid, kernel, law)(f)
                direct = f"{numpy.abs(qd - dfdt).max() / scale:.2e}"
            rows.append(f"| {dimension} | {n} | {grid.spacing:.3f} | "
                        f"{numpy.abs(q - dfdt).max() / scale:.2e} | {direct} |")
    return "\n".join(rows)


def fast_direct_table():
    grid = gf.VelocityGrid(2, 32, 5.0)
    kernel = gf.collision_kernel("hard_spheres")
    law = gf.restitution_law("toscani", strength=0.3, exponent=1.0)
    f = grid.maxwellian(velocity=[0.3, 0.0], temperature=2.5) + grid.maxwellian(
        density=0.5, velocity=[-0.6, 0.4], temperature=2.0)
    reference = gf.collision_operator("direct_spectral", grid, kernel, law)(f)
    rows = ["| N_rho | M | max \\|Q_fast − Q_direct\\| / max \\|Q_direct\\| |", "|---|---|---|"]
    for n_radial, m in [(4, 4), (8, 8), (16, 8), (16, 16), (32, 16), (32, 32), (64, 64)]:
        q = gf.collision_operator("fast_spectral", grid, kernel, law, backend=backend(),
                                  radial_points=n_radial, sphere=gf.CircleTrapezoid(m))(f)
        rows.append(f"| {n_radial} | {m} | "
                    f"{numpy.abs(q - reference).max() / numpy.abs(reference).max():.2e} |")
    return "\n".join(rows)


def heated(support_radius):
    grid = gf.VelocityGrid(2, 64, support_radius)
    op = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("maxwell"),
                               gf.restitution_law("constant", value=0.5), backend=backend(),
                               radial_points=32, sphere=gf.CircleTrapezoid(16))
    start = time.perf_counter()
    error, drift = heated_maxwell_error(op, restitution=0.5)
    return grid, error, drift, time.perf_counter() - start


def heated_table():
    rows = ["| S | L | R | max_t \\|T/T_exact − 1\\| | mass drift | wall time |",
            "|---|---|---|---|---|---|"]
    for s in (10.0, 12.0):
        grid, error, drift, wall = heated(s)
        rows.append(f"| {s:g} | {grid.half_width:.3f} | {grid.truncation_radius:g} | "
                    f"{error:.2e} | {drift:.1e} | {wall:.1f} s |")
    return "\n".join(rows)


if __name__ == "__main__":
    print("## BKW\n\n" + bkw_table() + "\n")
    print("## Fast against direct\n\n" + fast_direct_table() + "\n")
    print("## Heated Maxwell molecules\n\n" + heated_table())
