"""The Euler limit at every eps: the elastic Sod tube from eps = 1e-2 to 1e-10 at one step.

d_t f + v_1 d_x f = Q(f, f)/eps on x in [0, 1], 2D velocities, Maxwell molecules, the
fast spectral operator on the Sod grid of studies/space.py (N = 32, S = 3.5), specular
walls, MUSCL, penalised ARS(2,2,2) with the conservative correction, dt the transport's
CFL limit whatever eps (dt/eps from 0.7 to 7e7 at 50 cells), to t = 0.2. For every eps:

- the energy and mass drifts |E(t)/E(0) - 1|, |m(t)/m(0) - 1| (elastic, specular walls:
  both conserved), the lowest min f / max f(0) and the largest negative mass share;
- the L1 errors of rho, u_1, T against the exact Euler solution (gamma = 2, cell averages);
- the L1 distance to the eps -> 0 limit of the same scheme: the same transport with f
  relaxed to the discrete Maxwellian of every cell after every collision step
  (:class:`~granframe.stepping.integrators.EquilibriumProjection`, the kinetic scheme for
  the Euler equations of this velocity grid).

Then ``penalised_euler`` against ARS(2,2,2) at the same dt and at dt/2, eps = 1e-8: the
first-order scheme's O(dt) numerical viscosity.

    python studies/euler_limit.py --out DIR [--cells 50]

writes ``euler_limit.csv``, ``euler_limit_schemes.csv`` and ``euler_limit.md`` there and
prints the tables (about 15 minutes on 2 cores at 50 cells).
"""

from __future__ import annotations

import argparse
import pathlib
import time

import attrs
import numpy

from granframe.run.problems import make_problem
from granframe.run.runner import Simulation
from granframe.space.collisions import SingleModel, SplitStep
from granframe.stepping.integrators import EquilibriumProjection
from granframe.theory.euler import euler_riemann_cell_averages
from granframe.tools.space_cases import (GAMMA, SOD_FINAL, SOD_GRID, SOD_LEFT, SOD_RIGHT,
                                         euler_state, sod_description, sod_errors)
from granframe.tools.studykit import cfl_time_step, finish, mean_distances, number, write_csv

#: the knudsen numbers of the table
KNUDSEN = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
FINAL = SOD_FINAL


def fields(rho, velocity, temperature) -> dict:
    """The Sod tube's compared fields: rho, u_1, T per cell."""
    return {"rho": numpy.asarray(rho), "u": numpy.asarray(velocity)[:, 0],
            "T": numpy.asarray(temperature)}


def limit_fields(cells: int, final: float = FINAL, time_step: float | None = None) -> dict:
    """The fields at ``final`` of the eps -> 0 limit: the Sod tube's transport with every
    cell set to its discrete Maxwellian after every collision step (see the module notes),
    stepped by the problem itself (no store)."""
    description = sod_description(cells, 1.0, final=final)
    if time_step is not None:
        description = attrs.evolve(description, time_step=time_step)
    problem = make_problem(description)
    problem.integrator = SplitStep(SingleModel(EquilibriumProjection(), problem.equation),
                                   problem.transport)
    steps = round(final / description.time_step)
    state, t = problem.state(problem.f0), 0.0
    for _ in range(steps):
        state = problem.step(t, state, description.time_step)
        t += description.time_step
    record = problem.fields(problem.domain.to_cells(state))
    return fields(record["density"], record["velocity"], record["temperature"])


def sod_run(cells: int, knudsen: float, integrator: str = "penalised_ars222",
            final: float = FINAL, time_step: float | None = None) -> dict:
    """One Sod run: its last fields, drifts, positivity and seconds."""
    description = sod_description(cells, knudsen, final=final, integrator=integrator)
    if time_step is not None:
        description = attrs.evolve(description, time_step=time_step)
    started = time.perf_counter()
    ds = Simulation(description).run(None, progress=False).dataset
    seconds = time.perf_counter() - started
    energy, mass = ds.kinetic_energy.values, ds.mass.values
    f0_max = float(numpy.max(ds.f.values[0]))
    return {"fields": fields(ds.density.values[-1], ds.velocity.values[-1],
                             ds.temperature.values[-1]),
            "exact": sod_errors(ds), "steps": int(ds.sizes["step_time"] - 1),
            "dt": float(description.time_step),
            "energy_drift": float(abs(energy[-1] / energy[0] - 1)),
            "mass_drift": float(abs(mass[-1] / mass[0] - 1)),
            "min_f": float(numpy.min(ds.min_f.values)) / f0_max,
            "negative": float(numpy.max(ds.negative_mass_fraction.values)),
            "seconds": seconds}


def table(cells: int, knudsen=KNUDSEN) -> list[dict]:
    """The eps table (see the module notes)."""
    limit = limit_fields(cells)
    rows = []
    for eps in knudsen:
        run = sod_run(cells, eps)
        distance = mean_distances(run["fields"], limit)
        rows.append({"knudsen": eps, "dt_over_eps": run["dt"] / eps, "steps": run["steps"],
                     "energy_drift": run["energy_drift"], "mass_drift": run["mass_drift"],
                     "min_f": run["min_f"], "negative": run["negative"],
                     **{f"exact_{k}": v for k, v in run["exact"].items()},
                     **{f"limit_{k}": v for k, v in distance.items()},
                     "seconds": run["seconds"]})
        print(" ".join(f"{k}={v:.3g}" for k, v in rows[-1].items()), flush=True)
    limit_exact = mean_distances(limit, _exact(cells))
    rows.append({"knudsen": 0.0, **{f"exact_{k}": v for k, v in limit_exact.items()}})
    return rows


def _exact(cells: int, final: float = FINAL) -> dict:
    edges = numpy.linspace(0.0, 1.0, cells + 1)
    left, right = (euler_state(s) for s in (SOD_LEFT, SOD_RIGHT))
    exact = euler_riemann_cell_averages(left, right, GAMMA, edges, final)
    return {k: numpy.asarray(exact[k]) for k in ("rho", "u", "T")}


def schemes(cells: int, knudsen: float = 1e-8) -> list[dict]:
    """penalised_euler and ARS(2,2,2) at the CFL step and half of it: L1 errors against the
    exact Euler solution and against the eps -> 0 limit at the same step."""
    dt = cfl_time_step(cells, FINAL, SOD_GRID)
    rows = []
    for step in (dt, dt / 2):
        limit = limit_fields(cells, time_step=step)
        for integrator in ("penalised_ars222", "penalised_euler"):
            run = sod_run(cells, knudsen, integrator, time_step=step)
            rows.append({"integrator": integrator, "dt": step,
                         **{f"exact_{k}": v for k, v in run["exact"].items()},
                         **{f"limit_{k}": v for k, v in mean_distances(run["fields"], limit).items()},
                         "energy_drift": run["energy_drift"], "seconds": run["seconds"]})
            print(" ".join(f"{k}={v}" if isinstance(v, str) else f"{k}={v:.3g}"
                           for k, v in rows[-1].items()), flush=True)
    return rows


def _markdown(rows: list[dict], columns) -> str:
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        cells = []
        for c in columns:
            value = row.get(c, "")
            cells.append(value if isinstance(value, str)
                         else "" if value == "" else f"{value:.3g}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder of the tables")
    parser.add_argument("--cells", type=number(1, kind=int, low_open=False), default=50)
    args = parser.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    eps_rows = table(args.cells)
    scheme_rows = schemes(args.cells)
    write_csv(out / "euler_limit.csv", eps_rows)
    write_csv(out / "euler_limit_schemes.csv", scheme_rows)
    text = (f"Sod tube, {args.cells} cells, t = {FINAL}, 2D N = 32, S = 3.5, fast_spectral, "
            "conservative, MUSCL, dt at the CFL limit\n\n"
            + _markdown(eps_rows, ["knudsen", "dt_over_eps", "energy_drift", "mass_drift",
                                   "min_f", "negative", "exact_rho", "exact_u", "exact_T",
                                   "limit_rho", "limit_u", "limit_T", "seconds"])
            + "\n\n" + _markdown(scheme_rows, ["integrator", "dt", "exact_rho", "exact_u",
                                               "exact_T", "limit_rho", "limit_u",
                                               "limit_T", "energy_drift"]) + "\n")
    (out / "euler_limit.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
