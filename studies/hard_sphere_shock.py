r"""The normal shock of elastic hard spheres: the inverse density thickness lambda_1/delta
from an independent DSMC (granframe.testing.dsmc, NumPy only) at M = 1.5, 2, 3, with
its batch-means error and a refinement check, next to the Navier-Stokes profile.

Upstream n_1 = T_1 = 1, gamma = 5/3, u_1 = M sqrt(5/3); the downstream state from
Rankine-Hugoniot; lengths in the upstream hard-sphere mean free path
lambda_1 = 1/(sqrt 2 n_1 pi sigma_d^2); delta = (rho_2 - rho_1)/max |d rho/dx|.
For each Mach number: the DSMC run (cells of lambda_2/3, dt = 0.2/nu_2, 60 particles per
upstream cell, sampling ``--sampling`` x L/u_2 in 16 batches), then the refined run
(cells and time step halved, particles per cell doubled: four times the particles per
unit length) started from the first run's profile and sampled ``--refine-fraction`` as
long; the change between the two against the combined error bars; the Navier-Stokes
(Gilbarg-Paolucci) lambda_1/delta with the first Chapman-Enskog mu and kappa
(granframe.theory.shock).

With ``--spectral N[,N...]``: granframe's own run of the shock (:func:`spectral_description`:
in the frame of the gas behind it, from the Navier-Stokes profile, the gas ahead entering
from a reservoir; 3D hard spheres, e = 1, the default hierarchy of collision models,
cells of ``--spectral-cells-per-path`` per lambda_1), its lambda_1/delta
read off the cell averages by :func:`spline_inverse_thickness` at nine times over the
second half of the run, its shock speed and plateau against Rankine-Hugoniot, and the
velocity-resolution indicator in the shock; each run writes
OUT/spectral_M<M>_N<N>_c<cells per lambda_1>.json, and the table and figure gather them.
``--no-dsmc`` runs granframe's runs only.

Each Mach number writes OUT/dsmc_M<M>.json (its rows and profiles); the table, OUT/
hard_sphere_shock.json and the figure OUT/hard_sphere_shock.png gather every
dsmc_M*.json in OUT, so the Mach numbers can be run one command at a time.

Run: ``python studies/hard_sphere_shock.py --out DIR [--mach 1.5,2,3] [--quick]``
(``--quick``: about 40 s for the three, a smoke test). The table of the study was made one
Mach number at a time on one core (first run + refined run):

    python studies/hard_sphere_shock.py --out runs/hard_sphere_shock --mach 1.5 --sampling 160
    python studies/hard_sphere_shock.py --out runs/hard_sphere_shock --mach 2 --sampling 120
    python studies/hard_sphere_shock.py --out runs/hard_sphere_shock --mach 3 --sampling 60

(4.3, 6.1 and 6.4 minutes), giving lambda_1/delta = 0.1514 +- 0.0014, 0.2551 +- 0.0009,
0.3533 +- 0.0018, refined minus first run +0.0025 +- 0.0022, -0.0006 +- 0.0015,
+0.0018 +- 0.0024; Navier-Stokes 0.1752, 0.3325, 0.5533.

granframe's own runs at M = 1.5 (docs/granular.md, section 3):

    python studies/hard_sphere_shock.py --out runs/shock --no-dsmc --spectral 20,24,28
    python studies/hard_sphere_shock.py --out runs/shock --no-dsmc --spectral 24 \
        --spectral-cells-per-path 0.5 --spectral-cfl-fraction 0.8

(630, 1344 and 3152 s, and 690 s, beside other runs), giving the steady lambda_1/delta
0.1468 (N = 24) and 0.1496 (N = 28) on cells of lambda_1, 0.129 on cells of 2 lambda_1.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import pathlib
import time

import numpy

import granframe
from granframe.backends import NumpyBackend
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.testing.dsmc import (
    ShockSettings,
    default_length,
    rankine_hugoniot,
    run_shock,
)
from granframe.theory.euler import piston_speed
from granframe.theory.shock import navier_stokes_shock
from granframe.tools.studykit import (
    cfl_time_step,
    finish,
    json_text,
    number,
    numbers,
    parse_study,
    print_table,
    quick_option,
    relaxation_fit,
    run_study,
    save_figure,
)
from granframe.velocity.grid import VelocityGrid
from granframe.velocity.moments import FieldMoments

GAMMA = 5.0 / 3.0

#: published hard-sphere lambda_1/delta at these Mach numbers: none was found by the
#: library search (Bird 1994 ch. 12, Ohwada 1993, Erwin et al. 1991 were not readable
#: there), so none is quoted
LITERATURE: dict = {}

COLUMNS = {"M": "g", "rho2/rho1": ".4f", "T2/T1": ".4f", "DSMC": ".4f", "+-": ".4f",
           "refined": ".4f", "refined +-": ".4f", "change": "+.4f", "change +-": ".4f",
           "NS": ".4f", "particles": ".0f", "samples": "d", "seconds": ".0f"}


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", required=True, help="folder for the JSON files and figure")
    parser.add_argument("--mach", type=numbers(1.0), default=[1.5, 2.0, 3.0],
                        help="the upstream Mach numbers, comma-separated")
    parser.add_argument("--particles-per-cell", type=number(2.0), default=60.0,
                        help="simulated particles per cell at the upstream density")
    parser.add_argument("--cells-per-path", type=number(0.0), default=3.0,
                        help="cells per downstream mean free path lambda_2")
    parser.add_argument("--dt-fraction", type=number(0.0, 1.0), default=0.2,
                        help="dt times the downstream collision frequency")
    parser.add_argument("--length", type=number(0.0), default=None,
                        help="domain length in lambda_1 (default: 30 - 7 (M - 1.5), at "
                             "least 24)")
    parser.add_argument("--sampling", type=number(0.0), default=80.0,
                        help="sampling time in units of L/u_2")
    parser.add_argument("--transient", type=number(0.0), default=3.0,
                        help="transient time in units of L/u_2")
    parser.add_argument("--refine-fraction", type=number(0.0, low_open=False), default=0.25,
                        help="sampling of the refined run over the first run's (0: none)")
    parser.add_argument("--batches", type=number(4, kind=int, low_open=False), default=16,
                        help="batches of the sampling period (batch means)")
    parser.add_argument("--seed", type=number(0, kind=int, low_open=False), default=1,
                        help="random seed")
    parser.add_argument("--dsmc", action=argparse.BooleanOptionalAction, default=True,
                        help="run the DSMC at every --mach (--no-dsmc: only granframe's runs)")
    parser.add_argument("--spectral", type=numbers(4, kind=int), default=[],
                        help="granframe's own 3D runs at --spectral-mach on these velocity "
                             "grids N, comma-separated (default: none)")
    parser.add_argument("--spectral-mach", type=numbers(1.0), default=[1.5],
                        help="the Mach numbers of granframe's runs")
    parser.add_argument("--spectral-support", type=number(0.0), default=4.5,
                        help="their velocity grid's support radius S")
    parser.add_argument("--spectral-cells-per-path", type=number(0.0), default=1.0,
                        help="their cells per upstream mean free path lambda_1")
    parser.add_argument("--spectral-length", type=number(0.0), default=44.0,
                        help="their tube length in lambda_1")
    parser.add_argument("--spectral-position", type=number(0.0), default=15.0,
                        help="where their Navier-Stokes shock starts, in lambda_1")
    parser.add_argument("--spectral-final", type=number(0.0), default=12.0,
                        help="their final time in lambda_1/sqrt(T_1)")
    parser.add_argument("--spectral-cfl-fraction", type=number(0.0, 1.0), default=1.0,
                        help="their time step over half the transport's CFL limit")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=True,
                        help="a progress bar for granframe's runs")
    return quick_option(parser, {"particles_per_cell": 20.0, "sampling": 8.0,
                                 "transient": 2.0, "refine_fraction": 0.25, "batches": 8})


def result_row(result) -> dict:
    """What the table and the JSON keep of a DSMC run."""
    return {"inverse_thickness": result.inverse_thickness,
            "error": result.inverse_thickness_error,
            "jackknife_error": result.jackknife_error, "jackknife_bias": result.jackknife_bias,
            "batches": result.batch_inverse_thickness.tolist(),
            "dx": result.dx, "dt": result.dt, "particles": result.particles,
            "steps": result.steps, "samples": result.samples, "collisions": result.collisions,
            "seconds": result.seconds, "cell_over_local_path": result.cell_over_local_path,
            "dt_times_local_rate": result.dt_times_local_rate, "shift_rms": result.shift_rms,
            "checks": result.checks, "settings": result.settings}


def profile(result) -> dict:
    return {"x": result.x.tolist(), "density": result.density.tolist(),
            "velocity": result.velocity.tolist(), "temperature": result.temperature.tolist(),
            "temperature_xx": result.temperature_xx.tolist()}


def one_mach(mach: float, args, out: pathlib.Path) -> dict:
    """The DSMC run, its refinement and Navier-Stokes at ``mach``; writes OUT/dsmc_M.json."""
    state = rankine_hugoniot(mach)
    length = args.length or default_length(mach)
    flow = length / state["u2"]
    settings = ShockSettings(mach=mach, length=length, cells_per_path=args.cells_per_path,
                             particles_per_cell=args.particles_per_cell,
                             dt_fraction=args.dt_fraction, transient=args.transient * flow,
                             sampling=args.sampling * flow, batches=args.batches,
                             seed=args.seed)
    began = time.perf_counter()
    base = run_shock(settings, progress=lambda text: print("  " + text, flush=True))
    print(f"M = {mach:g}: lambda_1/delta = {base.inverse_thickness:.4f} +- "
          f"{base.inverse_thickness_error:.4f} ({base.seconds:.0f} s, "
          f"dx = {base.dx:.4f} = {base.cell_over_local_path:.3f} of the shortest local mean "
          f"free path, dt = {base.dt:.4f} = {base.dt_times_local_rate:.3f} of the shortest "
          f"local collision time)", flush=True)
    ns = navier_stokes_shock(mach)
    row = {"M": mach, "rho2/rho1": state["n2"], "T2/T1": state["T2"],
           "DSMC": base.inverse_thickness, "+-": base.inverse_thickness_error,
           "NS": ns["inverse_thickness"], "particles": base.particles,
           "samples": base.samples, "literature": LITERATURE.get(mach), "base": result_row(base)}
    profiles = {"dsmc": profile(base)}
    if args.refine_fraction > 0:
        finer = dataclasses.replace(settings, cells_per_path=2 * settings.cells_per_path,
                                    dt_fraction=0.5 * settings.dt_fraction,
                                    particles_per_cell=2 * settings.particles_per_cell,
                                    transient=1.0 * flow,
                                    sampling=args.refine_fraction * settings.sampling,
                                    seed=settings.seed + 1000)
        refined = run_shock(finer, initial=(base.x, base.density, base.velocity,
                                            base.temperature),
                            progress=lambda text: print("  refined " + text, flush=True))
        change = refined.inverse_thickness - base.inverse_thickness
        change_error = math.hypot(refined.inverse_thickness_error,
                                  base.inverse_thickness_error)
        print(f"M = {mach:g} refined (dx/2, dt/2, 2 x particles per cell): "
              f"{refined.inverse_thickness:.4f} +- {refined.inverse_thickness_error:.4f}, "
              f"change {change:+.4f} +- {change_error:.4f} ({refined.seconds:.0f} s)",
              flush=True)
        row.update({"refined": refined.inverse_thickness,
                    "refined +-": refined.inverse_thickness_error, "change": change,
                    "change +-": change_error, "refined run": result_row(refined)})
        profiles["refined"] = profile(refined)
    row["seconds"] = time.perf_counter() - began
    profiles["ns"] = {key: ns[key].tolist() for key in ("x", "density", "temperature")}
    path = out / f"dsmc_M{mach:g}.json"
    path.write_text(json_text({"row": row, "profiles": profiles}))
    print(f"written: {path}")
    return row


def spectral_description(mach: float, n_modes: int, support: float, cells_per_path: float,
                         length: float, final: float, position: float = 15.0,
                         fraction: float = 1.0) -> RunDescription:
    r"""granframe's own hard-sphere shock, in the frame of the gas behind it, with 3D
    velocities: a specular wall at x = 0, the gas at rest next to it, the Navier-Stokes
    shock at x = ``position`` (:func:`granframe.theory.shock.navier_stokes_maxwellian`,
    its local Maxwellians) moving with u_s = c_1 M - U into the gas ahead, which moves at
    -U (U = 2 c_1 (M - 1/M)/(gamma + 1), gamma = 5/3) and enters at x = ``length`` from a
    reservoir of the upstream state (:class:`granframe.space.boundaries.Reservoir`), so
    that nothing but the shock's own structure changes as it runs. eps = sqrt 2 makes
    lambda_1 = eps/sqrt 2 = 1 the unit of length; hard spheres B = |g|/(4 pi), e = 1,
    MUSCL, SSP-RK2 at ``fraction`` of half the transport's CFL limit (on cells of two mean
    free paths the collision term's limit is lower: 0.8), the conservative correction, and the
    default hierarchy: the uniform gas ahead of and behind the shock takes the fluid
    level, the shock and its reach of two mean free paths the full operator."""
    speed = piston_speed(mach, GAMMA)
    cells = max(1, round(length * cells_per_path))
    grid = {"dimension": 3, "n_modes": n_modes, "support_radius": support}
    return RunDescription(
        title=f"hard-sphere shock, M = {mach:g}, {cells} cells over {length:g} lambda_1, "
              f"N = {n_modes}, S = {support:g}",
        grid=grid, kernel="hard_spheres", restitution={"name": "constant", "value": 1.0},
        initial={"name": "space_function",
                 "function": "granframe.theory.shock:navier_stokes_maxwellian",
                 "params": {"mach": mach, "position": position}},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", knudsen=math.sqrt(2.0),
        conservative=True, final_time=final,
        time_step=cfl_time_step(cells, final, grid, length=length, fraction=fraction),
        output={"snapshot_interval": final},
        space={"cells": cells, "length": length, "reconstruction": "muscl",
               "left": "specular",
               "right": {"name": "reservoir", "density": 1.0, "velocity": -speed,
                         "temperature": 1.0},
               "hierarchy": {}})


def spline_inverse_thickness(x, density, n1: float, n2: float) -> tuple[float, float]:
    r"""lambda_1/delta of cell averages without noise, rising from n_1 at small x to n_2.

    The cell averages r_j of the normalised profile r = (n - n_1)/(n_2 - n_1) on cells of
    width h centred at ``x`` give its primitive exactly at the faces,
    P(x_{j+1/2}) = h sum_{i <= j} r_i; a quintic interpolating spline of P over the faces
    within three first-estimate thicknesses of the midpoint
    (:func:`~granframe.testing.dsmc.estimated_thickness`) has P'' = dr/dx, maximised
    within one thickness of the midpoint. Unlike a spline through the averages taken as
    point values (whose slope is low by h^2/24 times the third derivative, 1 % at
    h = lambda_1 for M = 1.5), it reads the Navier-Stokes profile of M = 1.5 to 6e-4 at
    h = lambda_1 and 2e-7 at h = lambda_1/2. Returns the inverse thickness and the
    midpoint (the 0.5 crossing of the averages)."""
    import scipy.interpolate

    from granframe.testing.dsmc import estimated_thickness

    x = numpy.asarray(x, dtype=float)
    r = (numpy.asarray(density, dtype=float) - n1) / (n2 - n1)
    h = float(x[1] - x[0])
    delta = estimated_thickness(x, r)
    crossing = numpy.nonzero(r >= 0.5)[0]
    if crossing.size == 0 or crossing[0] == 0:
        raise ValueError("spline_inverse_thickness: the profile never crosses its midpoint")
    i = int(crossing[0])
    middle = x[i - 1] + (x[i] - x[i - 1]) * (0.5 - r[i - 1]) / (r[i] - r[i - 1])
    window = numpy.nonzero(numpy.abs(x - middle) <= 3.0 * delta)[0]
    faces = numpy.append(x[window] - 0.5 * h, x[window[-1]] + 0.5 * h)
    primitive = numpy.concatenate(([0.0], numpy.cumsum(r[window]) * h))
    spline = scipy.interpolate.make_interp_spline(faces, primitive, k=5)
    fine = numpy.linspace(middle - delta, middle + delta, 2001)
    return float(spline(fine, 2).max()), float(middle)


def steady_thickness(times, values) -> dict:
    """The steady value of lambda_1/delta that still relaxes when the run ends:
    a + b exp(-k t) fitted by least squares over the second half of the record and over
    its last two thirds; ``steady`` = a of the first, ``spread`` = |a_1 - a_2| (the
    extrapolation's uncertainty), ``rate`` = k of the first. NaN where a fit fails or
    finds no decay (k outside (0.02, 20))."""
    fit = relaxation_fit(times, values,
                         (times[0], times[-1] - (times[-1] - times[0]) * 2.0 / 3.0), 0.3,
                         ([0, -1, 0.02], [1, 1, 20.0]))
    return fit or {"steady": math.nan, "spread": math.nan, "rate": math.nan}


def spectral_analysis(store, mach: float) -> dict:
    """The shock of a :func:`spectral_description` store: lambda_1/delta after every step
    of the second half of the run, and its steady value by :func:`steady_thickness` (the
    profile relaxes from the Navier-Stokes start over a few mean free times), the shock's
    position and speed (fitted over that half) against u_s, the plateau behind it against
    Rankine-Hugoniot, the velocity-resolution indicator of the final f
    (:meth:`~granframe.velocity.moments.FieldMoments.resolution`: the change of a cell's
    fields without the outermost shell of modes) in the cells within two thicknesses of
    the shock and, apart, in the others, and the final profile seen from the shock's
    midpoint (upstream at x < 0)."""
    ds = granframe.open_run(store, time_axis="steps")
    t, x = ds.time.values, ds.x.values
    density, temperature = ds.density.values, ds.temperature.values
    state = rankine_hugoniot(mach)
    shock_speed = math.sqrt(GAMMA) * mach - piston_speed(mach, GAMMA)
    xs = -x[::-1]  # seen from the shock: upstream (far from the wall) on the left
    history = []
    for k in numpy.nonzero(t >= 0.5 * t[-1])[0]:
        inverse, middle = spline_inverse_thickness(xs, density[k][::-1], 1.0, state["n2"])
        history.append({"t": float(t[k]), "inverse_thickness": inverse,
                        "position": float(-middle)})
    times = numpy.array([h["t"] for h in history])
    positions = numpy.array([h["position"] for h in history])
    steady = steady_thickness(times, numpy.array([h["inverse_thickness"] for h in history]))
    final = history[-1]
    behind = (x > 0.15 * final["position"]) & (x < 0.45 * final["position"])
    description = RunDescription.from_toml(ds.attrs["description_toml"])
    grid = VelocityGrid(dimension=3, n_modes=description.grid.n_modes,
                        support_radius=description.grid.support_radius)
    fields = FieldMoments(grid, float(x[1] - x[0])).resolution(ds.f.values[-1],
                                                              NumpyBackend())[:, 4]
    inside = numpy.abs(x - final["position"]) <= 2.0 / final["inverse_thickness"]
    quarter = int(numpy.argmin(abs(times - 0.75 * t[-1])))
    change = final["inverse_thickness"] - history[quarter]["inverse_thickness"]
    return {"M": mach, "N": int(ds.sizes["v1"]), "cells": len(x),
            "dx": float(x[1] - x[0]), "final": float(t[-1]), "steps": int(len(t) - 1),
            "granframe": final["inverse_thickness"], "change": change,
            "steady": steady["steady"], "steady spread": steady["spread"],
            "relaxation rate": steady["rate"],
            "shock speed": float(numpy.polyfit(times, positions, 1)[0]),
            "RH shock speed": shock_speed,
            "rho2": float(density[-1][behind].mean()) if behind.any() else math.nan,
            "RH rho2": state["n2"],
            "T2": float(temperature[-1][behind].mean()) if behind.any() else math.nan,
            "RH T2": state["T2"],
            "fields in the shock": float(fields[inside].max()),
            "fields elsewhere": float(fields[~inside].max()),
            "history": history,
            "profile": {"x": (final["position"] - x).tolist(),
                        "density": density[-1].tolist(),
                        "temperature": temperature[-1].tolist()}}


def one_spectral(mach: float, n_modes: int, args, out: pathlib.Path) -> dict:
    """granframe's run at ``mach`` on N = ``n_modes``; writes OUT/spectral_M_N_c.json."""
    name = f"spectral_M{mach:g}_N{n_modes}_c{args.spectral_cells_per_path:g}"
    description = spectral_description(mach, n_modes, args.spectral_support,
                                       args.spectral_cells_per_path, args.spectral_length,
                                       args.spectral_final, args.spectral_position,
                                       args.spectral_cfl_fraction)
    began = time.perf_counter()
    result = run_study(Simulation(description), out / f"{name}.zarr", args, overwrite=True)
    row = {**spectral_analysis(out / f"{name}.zarr", mach),
           "S": args.spectral_support, "seconds": time.perf_counter() - began,
           "warnings": [str(w) for w in (*result.warnings, *result.accuracy_warnings)]}
    (out / f"{name}.json").write_text(json_text(row))
    print(f"M = {mach:g}, N = {n_modes}, dx = {row['dx']:g} lambda_1: lambda_1/delta = "
          f"{row['granframe']:.4f} (change over the last quarter {row['change']:+.4f}); "
          f"shock speed {row['shock speed']:.4f} (Rankine-Hugoniot "
          f"{row['RH shock speed']:.4f}); written: {out / (name + '.json')}", flush=True)
    return row


def gathered(out: pathlib.Path) -> tuple[list[dict], list[dict]]:
    """Every dsmc_M*.json in OUT (row and profiles), by Mach number, and every
    spectral_*.json (granframe's runs), by Mach number, cell width and N."""
    found = [json.loads(p.read_text()) for p in out.glob("dsmc_M*.json")]
    spectral = [json.loads(p.read_text()) for p in out.glob("spectral_M*.json")]
    return (sorted(found, key=lambda entry: entry["row"]["M"]),
            sorted(spectral, key=lambda row: (row["M"], -row["dx"], row["N"])))


def figure(entries, spectral, path) -> None:
    """Normalised density and temperature against x/lambda_1: DSMC markers, Navier-Stokes
    lines, granframe's runs dashed with open markers, one shape per run (one colour per Mach
    number)."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 2, figsize=(12, 5.6), layout="constrained")
    colours = {entry["row"]["M"]: f"C{k}" for k, entry in enumerate(entries)}
    for row in spectral:
        colours.setdefault(row["M"], f"C{len(colours)}")
    for entry in entries:
        row, prof = entry["row"], entry["profiles"]
        colour = colours[row["M"]]
        n2, t2 = row["rho2/rho1"], row["T2/T1"]
        dsmc, ns = prof["dsmc"], prof["ns"]
        x = numpy.array(dsmc["x"])
        for ax, key, jump in ((axes[0], "density", n2), (axes[1], "temperature", t2)):
            values = (numpy.array(dsmc[key]) - 1.0) / (jump - 1.0)
            ax.plot(x, values, "o", ms=2.5, color=colour, zorder=3,
                    label=f"M = {row['M']:g} DSMC: λ₁/δ = {row['DSMC']:.3f} ± {row['+-']:.3f}")
            ax.plot(ns["x"], (numpy.array(ns[key]) - 1.0) / (jump - 1.0), "-", lw=1.2,
                    color=colour, label=f"M = {row['M']:g} Navier-Stokes: λ₁/δ = "
                                        f"{row['NS']:.3f}")
    for k, row in enumerate(spectral):
        prof = row["profile"]
        for ax, key, jump in ((axes[0], "density", row["RH rho2"]),
                              (axes[1], "temperature", row["RH T2"])):
            values = (numpy.array(prof[key]) - 1.0) / (jump - 1.0)
            ax.plot(prof["x"], values, "--", marker="s^Dvp"[k % 5], ms=3.5, lw=0.8,
                    color=colours[row["M"]], markerfacecolor="none", alpha=0.8,
                    label=f"M = {row['M']:g} granframe N = {row['N']}, dx = {row['dx']:g} λ₁: "
                          f"λ₁/δ = {row['granframe']:.3f} at t = {row['final']:g}")
    axes[0].set(xlabel="x / λ₁ (from the density midpoint)",
                ylabel="(ρ − ρ₁)/(ρ₂ − ρ₁)", xlim=(-12, 12))
    axes[1].set(xlabel="x / λ₁ (from the density midpoint)",
                ylabel="(T − T₁)/(T₂ − T₁)", xlim=(-12, 12))
    for ax in axes:
        ax.grid(True, alpha=0.3)
    # below the panels: inside, it covered a rise
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=3,
               fontsize=7)
    fig.suptitle("normal shock of elastic hard spheres: DSMC (markers), Navier-Stokes with "
                 "first Chapman-Enskog μ, κ (lines), granframe (open markers, dashed); "
                 "λ₁ = 1/(√2 n₁ π σ²)", fontsize=9)
    save_figure(fig, path, dpi=120)


SPECTRAL_COLUMNS = {"M": "g", "N": "d", "dx": "g", "steps": "d", "granframe": ".4f",
                    "change": "+.4f", "steady": ".4f", "steady spread": ".1e", "shock speed": ".4f", "RH shock speed": ".4f",
                    "rho2": ".4f", "RH rho2": ".4f", "fields in the shock": ".3g",
                    "fields elsewhere": ".3g", "seconds": ".0f"}


def main(argv=None):
    args = parse_study(arguments(), argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for mach in args.mach if args.dsmc else []:
        one_mach(mach, args, out)
    for mach in args.spectral_mach if args.spectral else []:
        for n_modes in args.spectral:
            one_spectral(mach, n_modes, args, out)
    entries, spectral = gathered(out)
    rows = [entry["row"] for entry in entries]
    print(f"\nhard-sphere shock, lambda_1/delta (every dsmc_M*.json in {out}):")
    print_table(rows, COLUMNS)
    if spectral:
        print(f"\ngranframe's runs (every spectral_M*.json in {out}; change: lambda_1/delta "
              "at the end minus at three quarters of the run):")
        print_table(spectral, SPECTRAL_COLUMNS)
    print("literature (hard spheres, lambda_1/delta at these M): none found by the library "
          "search; none quoted")
    summary = {"rows": rows, "literature": LITERATURE,
               "spectral": [{key: row.get(key) for key in SPECTRAL_COLUMNS} for row in spectral],
               "note": "change: refined (dx/2, dt/2, 2x particles per cell) minus the first "
                       "run; +-: batch-means standard errors"}
    (out / "hard_sphere_shock.json").write_text(json_text(summary, indent=1))
    print(f"table: {out / 'hard_sphere_shock.json'}")
    figure(entries, spectral, out / "hard_sphere_shock.png")
    print(f"figure: {out / 'hard_sphere_shock.png'}")


if __name__ == "__main__":
    raise SystemExit(finish(main))
