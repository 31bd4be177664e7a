r"""Heat conductivity and shear viscosity of 3D hard spheres in space, against N.

An elastic gas (e = 1) of 3D hard spheres between two diffuse walls at x = 0 and x = 1,
at temperatures 0.9 and 1.1 and moving along v_2 with -0.1 and +0.1: a Fourier flow and a
Couette flow at once. In the geometry of the run (u_1 = 0, everything a function of x)
the Burnett terms that would couple the two vanish (q_1 and P_12 are odd in x, a product
of two x-derivatives is even), so in the bulk

.. math:: q_1 = -\kappa\, \partial_x T, \qquad P_{12} = -\eta\, \partial_x u_2,

each up to O(Kn^3). With granframe's hard-sphere kernel B = |g|/(4 pi) and Q/eps the
cross section is pi sigma^2 = 1/eps (docs/space.md, "Knudsen number and mean free path"),
and the first Sonine approximations of Chapman and Enskog (unit mass, k_B = 1) are

.. math:: \eta_{CE} = \frac{5}{16\sigma^2}\sqrt{\frac{T}{\pi}} = \frac{5}{16}\,\varepsilon
          \sqrt{\pi T}, \qquad
          \kappa_{CE} = \frac{75}{64\sigma^2}\sqrt{\frac{T}{\pi}} = \frac{75}{64}\,
          \varepsilon\sqrt{\pi T}

(the converged Sonine series is 1.016 eta_CE and 1.025 kappa_CE; Chapman and Cowling,
The Mathematical Theory of Non-Uniform Gases, 3rd ed., section 10.21).

Each run: N in ``--modes``, S = 3, 8 cells, dt = 0.02 (at the CFL limit of MUSCL, 0.85 of
SSP RK2's collision limit), eps = 0.05 sqrt(2) (Kn = lambda/ell = eps/(sqrt 2 rho) = 0.05
at rho = 1), to t = 1 from the local Maxwellians of the Navier-Stokes profiles with the
jumps at the walls guessed (:func:`initial_profile`). At the last step, in the bulk cells
(two cells from each wall), kappa(x) = -q_1 / dT/dx and eta(x) = -P_12 / du_2/dx with
centred differences, each against its CE value at the cell's T. The steady state is checked
by the uniformity of the energy flux q_1 + P_12 u_2 and of P_12 over the bulk, and by their
change over the last half of the run. The resolution indicators of the last snapshot
(:meth:`granframe.velocity.moments.FieldMoments.resolution`) come with each row.

``python studies/space_transport.py --out DIR --modes 16,20,24 [--dt 0.01]`` runs (one N
at a time, each writing ``DIR/run_N{N}_dt{dt}.npz``) and writes ``DIR/transport.csv`` and
``DIR/transport.md`` from all the runs found in DIR; ``--table`` only writes the table.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import time

import numpy

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.tools.studykit import finish, number, numbers, write_csv

#: the walls: temperatures and tangential velocities (along v_2)
WALL_T = (0.9, 1.1)
WALL_U = (-0.1, 0.1)
KNUDSEN = 0.05
EPS = KNUDSEN * math.sqrt(2.0)
CELLS, DT, FINAL, SUPPORT = 8, 0.02, 1.0, 3.0
#: guessed bulk gradients (the jumps at the walls about 1.1 and 0.55 mean free paths
#: times the gradient, each side)
GRADIENT_T, GRADIENT_U = 0.164, 0.18
#: cells left out next to each wall (the Knudsen layers)
LAYER = 2


def initial_profile(x, v1, v2, v3):
    """Local Maxwellians of T = 1 + GRADIENT_T (x - 1/2), u_2 = GRADIENT_U (x - 1/2) and
    rho = 1/T (a uniform pressure)."""
    temperature = 1.0 + GRADIENT_T * (x - 0.5)
    u2 = GRADIENT_U * (x - 0.5)
    density = 1.0 / temperature
    return (density * (2.0 * math.pi * temperature) ** -1.5
            * numpy.exp(-(v1 ** 2 + (v2 - u2) ** 2 + v3 ** 2) / (2.0 * temperature)))


def description(modes: int, dt: float = DT) -> RunDescription:
    walls = [{"name": "diffuse", "temperature": t, "velocity": u}
             for t, u in zip(WALL_T, WALL_U)]
    return RunDescription(
        title=f"Fourier-Couette flow, 3D hard spheres, N = {modes}",
        grid={"dimension": 3, "n_modes": modes, "support_radius": SUPPORT},
        kernel="hard_spheres", restitution={"name": "constant", "value": 1.0},
        initial={"name": "space_function", "function": initial_profile},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", knudsen=EPS,
        conservative=True, time_step=dt, final_time=FINAL,
        output={"snapshot_interval": FINAL / 2},
        health={"edge_tolerance": 1e-6},
        space={"cells": CELLS, "length": 1.0, "left": walls[0], "right": walls[1]})


def run(out: pathlib.Path, modes: int, dt: float = DT) -> None:
    """One run, its fields at every step and f at the last snapshot into
    run_N{modes}_dt{dt}.npz."""
    started = time.perf_counter()
    ds = Simulation(description(modes, dt)).run(None, progress=False).dataset
    seconds = time.perf_counter() - started
    numpy.savez_compressed(
        out / f"run_N{modes}_dt{dt:g}.npz", seconds=seconds, modes=modes, dt=dt, x=ds.x.values,
        step_time=ds.step_time.values, temperature=ds.temperature.values,
        density=ds.density.values, velocity=ds.velocity.values,
        pressure=ds.pressure_tensor.values, heat_flux=ds.heat_flux.values,
        f=ds.f.values[-1], snapshot_time=ds.time.values)
    print(f"N = {modes}: {seconds:.0f} s", flush=True)


def ratios(z, k: int = -1) -> dict:
    """kappa / kappa_CE and eta / eta_CE in the bulk cells at record ``k`` of a run's
    fields ``z``, their means and spreads (max - min over the bulk, relative to the mean),
    and the spreads of the energy flux q_1 + P_12 u_2 and of P_12 over the bulk."""
    x, temperature = z["x"], z["temperature"][k]
    heat, shear, u2 = z["heat_flux"][k, :, 0], z["pressure"][k, :, 0, 1], z["velocity"][k, :, 1]
    bulk = slice(LAYER, len(x) - LAYER)
    width = x[2:] - x[:-2]
    gradient_t = ((temperature[2:] - temperature[:-2]) / width)[bulk.start - 1:bulk.stop - 1]
    gradient_u = ((u2[2:] - u2[:-2]) / width)[bulk.start - 1:bulk.stop - 1]
    scale = EPS * numpy.sqrt(math.pi * temperature[bulk])
    kappa = -heat[bulk] / gradient_t / (75.0 / 64.0 * scale)
    eta = -shear[bulk] / gradient_u / (5.0 / 16.0 * scale)
    energy = (heat + shear * u2)[bulk]

    def spread(values):
        return float((values.max() - values.min()) / abs(values.mean()))

    return {"kappa": float(kappa.mean()), "kappa_spread": spread(kappa),
            "eta": float(eta.mean()), "eta_spread": spread(eta),
            "energy_flux_spread": spread(energy), "shear_stress_spread": spread(shear[bulk]),
            "energy_flux": float(energy.mean())}


def table(out: pathlib.Path) -> list[dict]:
    """The rows of transport.csv and transport.md from the runs in ``out``."""
    from granframe.backends import NumpyBackend
    from granframe.run.monitors import cell_resolution_report
    from granframe.velocity.moments import FieldMoments
    from granframe.velocity.grid import VelocityGrid

    rows = []
    runs = [numpy.load(path) for path in out.glob("run_N*.npz")]
    for z in sorted(runs, key=lambda z: (-float(z["dt"]), int(z["modes"]))):
        modes, dt = int(z["modes"]), float(z["dt"])
        grid = VelocityGrid(3, modes, SUPPORT)
        indicators = FieldMoments(grid, 1.0 / CELLS).resolution(z["f"], NumpyBackend())
        report = cell_resolution_report(grid, indicators, z["x"], 1e-3)
        now, half = ratios(z), ratios(z, len(z["step_time"]) // 2 - 1)
        rows.append({
            "N": modes, "h": round(grid.spacing, 4), "cells": CELLS, "S": SUPPORT,
            "Kn": KNUDSEN, "dt": dt, "t": round(float(z["step_time"][-1]), 6),
            "kappa/kappa_CE": round(now["kappa"], 4),
            "kappa spread": round(now["kappa_spread"], 4),
            "eta/eta_CE": round(now["eta"], 4), "eta spread": round(now["eta_spread"], 4),
            "heat_flux_shell bulk": float(f"{indicators[LAYER:-LAYER, 3].max():.3g}"),
            "heat_flux_shell": float(f"{report['heat_flux_shell']:.3g}"),
            "its cell": report["cells"]["heat_flux_shell"],
            "tail_error": float(f"{report['tail_error']:.3g}"),
            "tail cell": report["cells"]["spectral_tail"],
            "tail_error bulk": float(f"{3.0 * indicators[LAYER:-LAYER, 0].max():.3g}"),
            "warned": "; ".join(w.split(":")[0] for w in report["warnings"]) or "no",
            "energy flux spread": float(f"{now['energy_flux_spread']:.3g}"),
            "P12 spread": float(f"{now['shear_stress_spread']:.3g}"),
            "kappa change t/2 -> t": float(f"{now['kappa'] - half['kappa']:.2g}"),
            "eta change t/2 -> t": float(f"{now['eta'] - half['eta']:.2g}"),
            "seconds": round(float(z["seconds"]))})
    for previous, row in zip(rows, rows[1:]):
        if row["dt"] != previous["dt"]:
            continue
        row["kappa refinement"] = round(row["kappa/kappa_CE"] - previous["kappa/kappa_CE"], 4)
        row["eta refinement"] = round(row["eta/eta_CE"] - previous["eta/eta_CE"], 4)
    return rows


def write_table(out: pathlib.Path) -> None:
    rows = table(out)
    fields = list(dict.fromkeys(name for row in rows for name in row))
    write_csv(out / "transport.csv", rows, fields)
    lines = ["| " + " | ".join(fields) + " |", "|" + "---|" * len(fields)]
    lines += ["| " + " | ".join(str(row.get(name, "")) for name in fields) + " |"
              for row in rows]
    (out / "transport.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--modes", type=numbers(1, low_open=False, kind=int), default=[16, 20, 24])
    parser.add_argument("--dt", type=number(0.0), default=DT)
    parser.add_argument("--table", action="store_true", help="only write the table")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.table:
        for modes in args.modes:
            run(args.out, modes, args.dt)
    write_table(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
