"""Space-inhomogeneous runs (docs/space.md): the Euler limit and the energy balance with walls.

d_t f + v_1 d_x f = Q(f, f)/eps on x in [0, 1], 2D velocities (gamma = (d+2)/d = 2),
Maxwell molecules (B = 1/(2 pi)), the fast spectral operator with S = 3.5 (L = 7.72) and
N = 32 (h = 0.483) for the Sod tube, N = 24 (h = 0.644) for the wall runs, MUSCL with
SSP RK3 and Strang splitting, dt at the transport's CFL limit dx / (L - h) (the largest
dt <= it that divides the final time):

- ``sod_eps*``: the elastic Sod tube, (rho, u, T) = (1, 0, 1) left of x = 0.5 and
  (0.125, 0, 0.8) right of it, specular walls, eps = 1e-2, 1e-3, 1e-4, penalised ARS(2,2,2)
  with the conservative correction (dt/eps = 28 at 50 cells and eps = 1e-4: without it the
  energy of the elastic gas drifts by -1.3e-3 by t = 0.1, with it by -2.3e-7), to t = 0.2,
  against the exact Euler Riemann solution (cell averages, gamma = 2): L1 errors of rho,
  u, T;
- ``walls_heat``: elastic gas between diffuse walls at T1 = 0.8 (x = 0) and T2 = 1.2
  (x = 1), eps = 0.1, from the Maxwellian of T = 1, conservative correction (without it
  the operator's energy defect shows as a net heat of 0.2 % of the flux): at the steady
  state the energy flux h^d sum_j c_j |v_j|^2/2 f_j is uniform in x and equals what the
  left wall takes out and the right one puts in;
- ``walls_balance``: inelastic gas (e = 0.9) between two diffuse walls at T_w = 1,
  eps = 0.2, from the Maxwellian of T = 0.84 (near the steady state): at the steady state
  the heat the walls put in per unit time equals the collisional dissipation
  -sum_cells dx h^d sum_j Q_j |v_j|^2/2 / eps of the final snapshot.

    granframe run studies/space.py --out runs/space            # 200 cells, 32 cells
    granframe run studies/space.py --quick --out runs/space    # 50 cells, 8 cells
    python studies/space.py --convergence --out DIR            # the refinement tables

The report draws the Sod profiles at t = 0.2 with the exact Euler solution and its cell
averages (``report/space_sod_profiles.png``), the wall runs' profiles and heat rates, and
writes ``space_sod_l1.csv`` and ``space_walls.csv``.
``--convergence`` runs the Sod tube at 25, 50, 100, 200 cells for eps = 1e-2, 1e-3, 1e-4
(L1 errors and observed orders log2(E_n / E_2n)) and the energy-balance case to t = 10 at
8 cells (dt at the CFL limit, 1/2 and 1/4 of it), 16 and 32 cells (at the limit); it
writes ``space_sod_convergence.csv``, ``space_balance_refinement.csv`` and
``space_convergence.md`` (``--parts sod`` or ``balance`` for one of them).
"""

from __future__ import annotations

import argparse
import math
import pathlib
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
import xarray  # noqa: E402

from granframe.run.description import RunDescription  # noqa: E402
from granframe.run.runner import Simulation  # noqa: E402
from granframe.space.transport import transport_speeds  # noqa: E402
from granframe.theory.euler import euler_riemann, euler_riemann_cell_averages  # noqa: E402
from granframe.tools.analysis import energy_balance  # noqa: E402
from granframe.tools.space_cases import (GAMMA, SOD_LEFT, SOD_RIGHT, euler_state,  # noqa: E402
                                         sod_description, sod_errors, walls_description)
from granframe.tools.studykit import finish, write_csv, write_summary  # noqa: E402

SOD_KNUDSEN = (1e-2, 1e-3, 1e-4)
SOD_CELLS = (25, 50, 100, 200)
#: the energy-balance case: e, eps, wall temperature, initial temperature, final time
BALANCE = {"restitution": 0.9, "knudsen": 0.2, "wall": 1.0, "initial": 0.84, "final": 10.0}
#: the energy-balance refinement: (cells, fraction of the CFL limit)
BALANCE_STEPS = ((8, 1.0), (8, 0.5), (8, 0.25), (16, 1.0), (32, 1.0))
#: the heat-transfer case: eps, the two wall temperatures, final time
HEAT = {"knudsen": 0.1, "T1": 0.8, "T2": 1.2, "final": 4.0}


def balance_description(cells: int, fraction: float = 1.0, final: float | None = None):
    b = BALANCE
    return walls_description(cells, b["knudsen"], b["restitution"], b["wall"], b["wall"],
                             b["initial"], final or b["final"], fraction)


def _description(ds) -> RunDescription:
    """The run's description: from a run in memory (``description_toml``) or a store opened
    with xarray.open_zarr (``granframe.description``)."""
    if "description_toml" in ds.attrs:
        return RunDescription.from_toml(ds.attrs["description_toml"])
    return RunDescription.from_dict(ds.attrs["granframe"]["description"])


def energy_flux(ds):
    """h^d sum_j c_j |v_j|^2/2 f_ij of the last snapshot, per cell (c_j the net transport
    speeds)."""
    grid = _description(ds).grid
    f = ds.f.values[-1]
    weight = transport_speeds(grid, numpy) * 0.5 * grid.speed_squared() * grid.cell_volume
    return numpy.sum(f * weight, axis=tuple(range(1, f.ndim)))


def heat_transfer(ds, window: float = 0.2) -> dict:
    r"""The heat-transfer run at its last step.

    ``energy_flux``: h^d sum_j c_j |v_j|^2/2 f_ij per cell with the net transport speeds
    c_j (:func:`~granframe.space.transport.transport_speeds`: v_1, and 0 at the node j = 0
    that the periodic grid shares between v_1 = -L and +L), its mean and relative spread
    (max - min)/|mean|; at the steady state of an elastic gas it is uniform in x and
    equals the heat rates of the walls, what the left wall puts in and the right one takes
    out per unit time (averaged over the last ``window`` of the steps). ``q1``: the recorded
    heat-flux field, which counts the node j = 0 as its two halves at +-L, as the transport
    moves it (:mod:`granframe.velocity.moments`); at the steady state (u = 0) it is the energy
    flux.
    """
    flux = energy_flux(ds)
    q1 = ds.heat_flux.values[-1][:, 0]
    dt = ds.dt.values[1:]
    rates = ds.wall_energy.values[1:] / dt[:, None]
    count = max(1, int(window * len(rates)))
    return {"energy_flux_mean": float(flux.mean()),
            "energy_flux_spread": float(numpy.ptp(flux) / abs(flux.mean())),
            "q1_mean": float(q1.mean()), "q1_spread": float(numpy.ptp(q1) / abs(q1.mean())),
            "left_heat_rate": float(rates[-count:, 0].mean()),
            "right_heat_rate": float(-rates[-count:, 1].mean()),
            "net_over_left": float(rates[-count:].sum(axis=1).mean() / rates[-count:, 0].mean()),
            "T_min": float(ds.temperature.values[-1].min()),
            "T_max": float(ds.temperature.values[-1].max())}


def runs(quick: bool = False) -> dict:
    sod_cells, wall_cells = (50, 8) if quick else (200, 32)
    made = {f"sod_eps{eps:g}": sod_description(sod_cells, eps) for eps in SOD_KNUDSEN}
    h = HEAT
    made["walls_heat"] = walls_description(wall_cells, h["knudsen"], 1.0, h["T1"], h["T2"],
                                           0.5 * (h["T1"] + h["T2"]),
                                           3.0 if quick else h["final"], conservative=True)
    made["walls_balance"] = balance_description(wall_cells, final=3.0 if quick else None)
    return made


def _operator(ds):
    """The run's collision operator, rebuilt from its stored description."""
    return Simulation(_description(ds)).problem.operator


def report(stores: dict, out) -> dict:
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    summary, rows = {}, []
    sod = sorted((name for name in stores if name.startswith("sod_")),
                 key=lambda n: -float(n[len("sod_eps"):]))
    if sod:
        fig, axes = plt.subplots(1, 3, figsize=(16, 5.2), layout="constrained")
        x = numpy.linspace(0.0, 1.0, 2001)
        for name in sod:
            ds = xarray.open_zarr(stores[name])
            eps = float(ds.attrs["granframe"]["description"]["knudsen"])
            errors = sod_errors(ds)
            summary[name] = {"knudsen": eps, "cells": int(ds.sizes["x"]),
                             "dt": float(ds.dt.values[-1]),
                             "final_time": float(ds.step_time.values[-1]),
                             "l1": errors, "mass_drift": float(ds.mass.values[-1]
                                                               / ds.mass.values[0] - 1),
                             "energy_drift": float(ds.kinetic_energy.values[-1]
                                                   / ds.kinetic_energy.values[0] - 1)}
            rows.append({"knudsen": eps, "cells": int(ds.sizes["x"]), **errors})
            fields = (ds.density.values[-1], ds.velocity.values[-1][:, 0],
                      ds.temperature.values[-1])
            for axis, values in zip(axes, fields):
                axis.plot(ds.x.values, values, "o-", ms=2.5, lw=0.8, label=f"eps = {eps:g}")
        t, cells = summary[sod[0]]["final_time"], summary[sod[0]]["cells"]
        grid = ds.attrs["granframe"]["description"]["grid"]
        left, right = euler_state(SOD_LEFT), euler_state(SOD_RIGHT)
        exact = euler_riemann(left, right, GAMMA, x, t)
        averages = euler_riemann_cell_averages(left, right, GAMMA,
                                               numpy.linspace(0.0, 1.0, cells + 1), t)
        for axis, key, label in zip(axes, ("rho", "u", "T"),
                                    ("density ρ", "velocity u₁", "temperature T")):
            axis.plot(x, exact[key], "k-", lw=1.2, label="exact Euler, γ = 2")
            axis.plot(ds.x.values, averages[key], "k+", ms=5,
                      label="its cell averages (the L1 errors' reference)")
            axis.set(xlabel="position x (dimensionless)", ylabel=f"{label} (dimensionless)",
                     title=f"{label} at t = {t:g}")
        # one legend below the panels: inside, it covered the velocity plateau
        fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center",
                   ncol=5, fontsize=8)
        fig.suptitle(f"Sod tube, 2D Maxwell molecules, elastic, {cells} cells, MUSCL + SSP "
                     f"RK3, penalised ARS(2,2,2), N = {grid['n_modes']}, "
                     f"S = {grid['support_radius']:g}", fontsize=9)
        fig.savefig(out / "space_sod_profiles.png", dpi=100)
        plt.close(fig)
        write_csv(out / "space_sod_l1.csv", rows, ["knudsen", "cells", "rho", "u", "T"])
    wall_rows = []
    for name in ("walls_heat", "walls_balance"):
        if name not in stores:
            continue
        ds = xarray.open_zarr(stores[name])
        description = ds.attrs["granframe"]["description"]
        eps = float(description["knudsen"])
        if name == "walls_heat":
            summary[name] = heat_transfer(ds)
        else:
            summary[name] = energy_balance(ds, _operator(ds), eps)
        summary[name].update({"cells": int(ds.sizes["x"]), "dt": float(ds.dt.values[-1]),
                              "final_time": float(ds.step_time.values[-1]), "knudsen": eps})
        wall_rows.append({"run": name, **summary[name]})
        fig, axes = plt.subplots(1, 3, figsize=(16, 4.6), constrained_layout=True)
        axes[0].plot(ds.x.values, ds.temperature.values[-1], "o-", ms=3)
        axes[0].set(xlabel="position x (dimensionless)", ylabel="temperature T (dimensionless)",
                    title=f"T at t = {summary[name]['final_time']:g}")
        axes[1].plot(ds.x.values, energy_flux(ds), "o-", ms=3,
                     label="energy flux Σ c |v|²/2 f (net transport speeds c)")
        axes[1].plot(ds.x.values, ds.heat_flux.values[-1][:, 0], "s--", ms=3,
                     label="recorded q₁ (node v₁ = −L counted)")
        axes[1].set(xlabel="position x (dimensionless)",
                    ylabel="energy flux (dimensionless)", title="fluxes at the last step")
        axes[1].legend(fontsize=8)
        t, dt = ds.step_time.values[1:], ds.dt.values[1:]
        walls = ds.wall_energy.values[1:] / dt[:, None]
        axes[2].plot(t, walls[:, 0], label="left wall")
        axes[2].plot(t, walls[:, 1], label="right wall")
        axes[2].plot(t, walls.sum(axis=1), "k", label="both walls")
        if name == "walls_balance":
            axes[2].axhline(-summary[name]["dissipation"], color="C3", ls="--",
                            label="−dissipation of the final f")
        axes[2].set(xlabel="time t (dimensionless)",
                    ylabel="energy entering per unit time (dimensionless)",
                    title="heat put in by the walls")
        axes[2].legend(fontsize=8)
        fig.suptitle(description["title"], fontsize=9)
        fig.savefig(out / f"space_{name}.png", dpi=100)
        plt.close(fig)
    if wall_rows:
        fields = sorted({k for row in wall_rows for k in row} - {"run"})
        write_csv(out / "space_walls.csv", wall_rows, ["run"] + fields)
    write_summary(out, summary)
    return summary


def _orders(values):
    """log2(E_n / E_2n) between consecutive resolutions (None for the first)."""
    return [None] + [math.log2(a / b) for a, b in zip(values[:-1], values[1:])]


def convergence(out, cells=SOD_CELLS, knudsen=SOD_KNUDSEN, balance=BALANCE_STEPS,
                parts=("sod", "balance")) -> dict:
    """The Sod refinement (L1 errors, observed orders) and the energy-balance refinement
    (``balance``: (cells, fraction of the CFL limit) pairs), run in memory; writes the CSVs
    of the ``parts`` run and a markdown table into ``out``."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sod_rows, balance_rows = [], []
    for eps in knudsen if "sod" in parts else ():
        errors = []
        for n in cells:
            description = sod_description(n, eps)
            started = time.perf_counter()
            ds = Simulation(description).run(None, progress=False).dataset
            seconds = time.perf_counter() - started
            errors.append(sod_errors(ds))
            sod_rows.append({"knudsen": eps, "cells": n, "dt": description.time_step,
                             "seconds": round(seconds, 1), **errors[-1]})
            print(sod_rows[-1], flush=True)
        for key in ("rho", "u", "T"):
            for row, order in zip(sod_rows[-len(cells):], _orders([e[key] for e in errors])):
                row[f"order_{key}"] = order
    for n, fraction in balance if "balance" in parts else ():
        description = balance_description(n, fraction)
        started = time.perf_counter()
        simulation = Simulation(description)
        ds = simulation.run(None, progress=False).dataset
        seconds = time.perf_counter() - started
        balance_rows.append({"cells": n, "dt": description.time_step,
                             "seconds": round(seconds, 1),
                             **energy_balance(ds, simulation.problem.operator,
                                              BALANCE["knudsen"])})
        print(balance_rows[-1], flush=True)
    if sod_rows:
        write_csv(out / "space_sod_convergence.csv", sod_rows)
    if balance_rows:
        write_csv(out / "space_balance_refinement.csv", balance_rows)
    (out / "space_convergence.md").write_text(_tables(sod_rows, balance_rows))
    return {"sod": sod_rows, "balance": balance_rows}


def _tables(sod_rows, balance_rows) -> str:
    """The refinement tables in markdown (a table only for the rows given)."""
    def number(value, fmt):
        return "" if value is None else format(value, fmt)

    lines = []
    if sod_rows:
        lines += ["| eps | cells | dt | L1 rho | order | L1 u | order | L1 T | order | seconds |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        lines += [f"| {r['knudsen']:g} | {r['cells']} | {r['dt']:.4g} | {r['rho']:.3e} | "
                  f"{number(r['order_rho'], '.2f')} | {r['u']:.3e} | "
                  f"{number(r['order_u'], '.2f')} | {r['T']:.3e} | "
                  f"{number(r['order_T'], '.2f')} | {r['seconds']} |" for r in sod_rows]
        lines.append("")
    if balance_rows:
        lines += ["| cells | dt | heat in | dissipation | (heat + diss)/heat | dE/dt / heat "
                  "| residual | seconds |", "|---|---|---|---|---|---|---|---|"]
        lines += [f"| {r['cells']} | {r['dt']:.4g} | {r['heat']:.6f} | "
                  f"{r['dissipation']:.6f} | {r['mismatch']:.2e} | {r['unsteadiness']:.2e} "
                  f"| {r['residual']:.2e} | {r['seconds']} |" for r in balance_rows]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--convergence", action="store_true",
                        help="run the Sod and energy-balance refinements")
    parser.add_argument("--parts", default="sod,balance",
                        help="comma-separated refinements to run: sod, balance")
    args = parser.parse_args(argv)
    if not args.convergence:
        parser.error("--convergence is the only script mode; run the study itself with "
                     "'granframe run studies/space.py --out DIR'")
    convergence(args.out, parts=tuple(args.parts.split(",")))
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
