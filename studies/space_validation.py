"""The validation tables of docs/space.md, from the functions of tests/test_space_validation.py
(:mod:`granframe.testing.space_validation`).

    python studies/space_validation.py --out docs/figures/space

writes space_validation.md there (about a minute on 2 cores) and prints it.
"""
import argparse
import pathlib
import time

import numpy

from granframe.testing import space_validation as T
from granframe.velocity.grid import VelocityGrid

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", required=True, help="folder of space_validation.md")
folder = pathlib.Path(parser.parse_args().out)

out = []
w = out.append
started = time.time()

w("## Validation of the space solver (tests/test_space_validation.py)\n")
w("### 1. Data uniform in x against the space-homogeneous run\n")
w("2D velocity grid N = 24, S = 3 (L = 6.62, h = 0.552); Maxwell molecules, e = 0.5, "
  "knudsen 0.5; 8 cells in blocks of 4; dt = 0.004, 10 steps to t = 0.04; f compared at "
  "t = 0, 0.02, 0.04 and the fields at those times (the homogeneous snapshots' fields as a space run counts them, granframe.velocity.moments). Periodic runs: fast_spectral, data "
  "two Maxwellians moving apart; specular runs: direct_spectral, data even in "
  "v_1 (an anisotropic Gaussian and a Maxwellian; fast_spectral's Q commutes with v_1 -> -v_1 only to its quadrature error, 2.6e-6 of max |Q| at this resolution, and makes an odd part of 2e-8 of max f by t = 0.02, which a specular wall reflects). The penalised specular run differs by 4e-10: the penalisation's Maxwellian has the grid momentum of f, which for f even in v_1 is -L h^2 sum f(-L, v_2) (the node -L has no mirror), and the projection onto the Nyquist-free modes leaves f(-L, .) at about 1e-5 of max f here (u_1 = 1.7e-4). Differences: max over "
  "cells and times, f relative to max f, rho, T, P relative to their largest value, u "
  "absolute, q relative to rho T^{3/2}.\n")
w("| ends | integrator | heat bath | operator | f | rho | u | T | P | q |")
w("|---|---|---|---|---|---|---|---|---|---|")
for ends, integrator, bath in [("periodic", "rk4", 0.0), ("periodic", "penalised_ars222", 0.5),
                               ("specular", "rk4", 0.5), ("specular", "penalised_ars222", 0.0)]:
    d = T.uniform_difference(ends, integrator, bath)
    op = "fast_spectral" if ends == "periodic" else "direct_spectral"
    w(f"| {ends} | {integrator} | {bath} | {op} | " + " | ".join(f"{d[k]:.1e}" for k in
      ("f", "rho", "u", "T", "P", "q")) + " |")
w("")

w("### 2. Free transport: L1 error against the exact cell averages and observed order\n")
g = VelocityGrid(**T.TRANSPORT_GRID)
w(f"Velocity grid 2D N = 16, S = 2.8 (L = {g.half_width:.3f}, h = {g.spacing:.3f}, max|c| = "
  f"{g.half_width - g.spacing:.3f}), no collisions, [0, 1], t = 0.2. Periodic: "
  "f0 = (1 + 0.5 sin 2 pi x) M_{0.6}(v) (`sinusoidal_mode`), exact "
  "`free_transport_sine` per node; specular walls: f0 = M_{0.6}(v) (1 + 0.3 cos pi x + "
  "0.3 sin(pi x) tanh v_1), exact `specular_images_cell_averages` (method of images). "
  "Error: sum |f - exact| dx dv / sum |exact| dx dv. dt = 0.8 x the CFL limit on 20 cells "
  "(2 cfl dx / max|c|), times 20/cells (upwind, MUSCL with the mc limiter: fixed Courant "
  "number) or (20/cells)^{5/3} (WENO5, WENO-Z weights, the default), the last step of each run ending at "
  "t = 0.2.\n")
for ends in ("periodic", "specular"):
    w(f"**{ends}**\n")
    w("| cells | upwind | order | muscl | order | weno5 (dt ~ dx^5/3) | order | weno5 (fixed Courant) | order |")
    w("|---|---|---|---|---|---|---|---|---|")
    table = {}
    for rec in ("upwind", "muscl", "weno5"):
        table[rec] = [T.convergence(rec, ends, n)[0] for n in (20, 40, 80, 160)]
    # WENO5 at the fixed Courant number of MUSCL: the SSPRK3 time error is then O(dx^3)
    fixed = []
    for n in (20, 40, 80, 160):
        grid = g
        dt = T.dividing_step(0.2, 0.8 * 2 * 0.5 * (1 / n) / (grid.half_width - grid.spacing))
        initial = ({"name": "sinusoidal_mode", "field": "density", "amplitude": T.AMPLITUDE,
                    "temperature": T.T0} if ends == "periodic" else
                   {"name": "space_function", "function": T.walls_function})
        ds = T.run_dataset(final_time=0.2, time_step=dt, grid=T.TRANSPORT_GRID, **T.COLLISIONS,
                   initial=initial, output={"snapshot_interval": 0.2},
                   space={"cells": n, "reconstruction": "weno5", "left": ends, "right": ends,
                          "collisions": False})
        edges = numpy.linspace(0, 1, n + 1)
        ref = T.exact_transport(g, ends, edges, float(ds.time.values[-1]))
        fixed.append(numpy.abs(ds.f.values[-1] - ref).sum() / numpy.abs(ref).sum())
    table["fixed"] = fixed
    orders = {k: [None] + T.orders(v) for k, v in table.items()}
    for i, n in enumerate((20, 40, 80, 160)):
        cells = []
        for k in ("upwind", "muscl", "weno5", "fixed"):
            o = orders[k][i]
            cells += [f"{table[k][i]:.3e}", "" if o is None else f"{o:.2f}"]
        w(f"| {n} | " + " | ".join(cells) + " |")
    w("")

w("### 3. Free-molecular heat transfer between diffuse walls\n")
r = T.free_molecular(samples=11)
g = VelocityGrid(**T.WALLS_GRID)
w(f"Walls at T1 = {T.T1} (x = 0) and T2 = {T.T2} (x = 1), full accommodation, no collisions; "
  f"initial gas uniform Maxwellian at rest, T = {T.T_GAS}; velocity grid 2D N = 24, S = 3 "
  f"(h = {g.spacing:.3f}: the slowest moving nodes |v_1| = h cross the interval in "
  f"{1 / g.spacing:.2f}); 10 cells, upwind, dt = {r['dt']:.4g} (0.9 x CFL), t = 30. "
  "Distance: max over the cells, relative (u_1: absolute) to the grid closed form "
  "`free_molecular_walls_grid` (the run's mass and nodes v_1 = 0). It levels at 2e-8 (q_1) "
  "to 2e-11 (rho): the node -L, which moves both ways, holds in the run a profile linear "
  "in x between the two walls' emissions at |v_1| = L (relative size exp(-L^2/(2 T2)) = "
  "3e-10), which the closed form replaces by its mean; q_1 weighs it by L^3/2.\n")
w("| t | rho | u_1 | T | P_11 | q_1 |")
w("|---|---|---|---|---|---|")
for t, e in r["history"]:
    w(f"| {t:.2f} | " + " | ".join(f"{e[k]:.1e}" for k in ("rho", "u1", "T", "P11", "q1")) + " |")
w(f"\nAt t = 30, max |f - f_grid| / max f_grid = {r['f']:.1e}.\n")
s, c = r["steady"], r["continuum"]
w("Grid closed form against the continuous one (`free_molecular_walls`): the grid's "
  "quadrature error (the kink of the half-range data at v_1 = 0, and the nodes v_1 = 0, which "
  "keep the initial data).\n")
w("| | grid | continuum | relative difference |")
w("|---|---|---|---|")
for name, key in (("rho", "rho"), ("T", "T"), ("P_11", "P11"), ("q_1", "q1")):
    w(f"| {name} | {s[key]:.6f} | {c[key]:.6f} | {(s[key] - c[key]) / c[key]:+.2e} |")
w(f"| n1, n2 | {s['n1']:.5f}, {s['n2']:.5f} | {c['n1']:.5f}, {c['n2']:.5f} | |")
w("")

w("### 4. Diffuse walls: mass, and relaxation to the wall Maxwellian\n")
w(f"Maxwell molecules, e = 1, walls at T_w = {T.T_WALL}, full accommodation; initial "
  "density 1 + 0.5 sin 2 pi x at rest, T = 0.8; 10 cells, MUSCL, rk4, dt = 0.9 x CFL, "
  "t = 6. Distance from the wall Maxwellian: max over the cells of |rho/rho_mean - 1|, "
  "|u|, |T/T_w - 1|.\n")
for label, kwargs in [("knudsen 0.1, N = 16, S = 3 (the test)", {}),
                      ("knudsen 1, N = 16, S = 3", {"knudsen": 1.0}),
                      ("knudsen 0.1, N = 24, S = 3", {"grid_table": {"dimension": 2,
                                                     "n_modes": 24, "support_radius": 3.0}})]:
    t0 = time.time()
    r = T.relaxation(**kwargs)
    w(f"**{label}**: {r['steps']} steps of dt = {r['dt']:.4g}; max |mass/mass(0) - 1| = "
      f"{r['mass']:.1e}; max |wall_mass| / mass = {r['wall_mass']:.1e}; energy entered "
      f"through the walls {r['wall_energy']:.4f}; {time.time() - t0:.1f} s.\n")
    w("| t | rho | u | T |")
    w("|---|---|---|---|")
    for t, e in r["history"]:
        w(f"| {t:.2f} | {e['rho']:.2e} | {e['u']:.2e} | {e['T']:.2e} |")
    w("")
w(f"(tables computed in {time.time() - started:.0f} s)")
folder.mkdir(parents=True, exist_ok=True)
(folder / "space_validation.md").write_text("\n".join(out) + "\n")
print("\n".join(out))
