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
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import pathlib
import time

import numpy

from granframe.testing.dsmc import (
    ShockSettings,
    default_length,
    rankine_hugoniot,
    run_shock,
)
from granframe.theory.shock import navier_stokes_shock
from granframe.tools.studykit import (finish, json_text, number, numbers, parse_study,
                                      print_table, quick_option, save_figure)

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


def gathered(out: pathlib.Path) -> list[dict]:
    """Every dsmc_M*.json in OUT: (row, profiles), by Mach number."""
    found = [json.loads(p.read_text()) for p in out.glob("dsmc_M*.json")]
    return sorted(found, key=lambda entry: entry["row"]["M"])


def figure(entries, path) -> None:
    """Normalised density and temperature against x/lambda_1: DSMC markers, NS lines."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    for k, entry in enumerate(entries):
        row, prof = entry["row"], entry["profiles"]
        colour = f"C{k}"
        n2, t2 = row["rho2/rho1"], row["T2/T1"]
        dsmc, ns = prof["dsmc"], prof["ns"]
        x = numpy.array(dsmc["x"])
        for ax, key, jump in ((axes[0], "density", n2), (axes[1], "temperature", t2)):
            values = (numpy.array(dsmc[key]) - 1.0) / (jump - 1.0)
            ax.plot(x, values, "o", ms=2.5, color=colour,
                    label=f"M = {row['M']:g} DSMC: λ₁/δ = {row['DSMC']:.3f} ± {row['+-']:.3f}")
            ax.plot(ns["x"], (numpy.array(ns[key]) - 1.0) / (jump - 1.0), "-", lw=1.2,
                    color=colour, label=f"M = {row['M']:g} Navier-Stokes: λ₁/δ = "
                                        f"{row['NS']:.3f}")
    axes[0].set(xlabel="x / λ₁ (from the density midpoint)",
                ylabel="(ρ − ρ₁)/(ρ₂ − ρ₁)", xlim=(-12, 12))
    axes[1].set(xlabel="x / λ₁ (from the density midpoint)",
                ylabel="(T − T₁)/(T₂ − T₁)", xlim=(-12, 12))
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("normal shock of elastic hard spheres: DSMC (markers) and Navier-Stokes with "
                 "first Chapman-Enskog μ, κ (lines); λ₁ = 1/(√2 n₁ π σ²)", fontsize=9)
    save_figure(fig, path, dpi=120)


def main(argv=None):
    args = parse_study(arguments(), argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for mach in args.mach:
        one_mach(mach, args, out)
    entries = gathered(out)
    rows = [entry["row"] for entry in entries]
    print(f"\nhard-sphere shock, lambda_1/delta (every dsmc_M*.json in {out}):")
    print_table(rows, COLUMNS)
    print("literature (hard spheres, lambda_1/delta at these M): none found by the library "
          "search; none quoted")
    summary = {"rows": rows, "literature": LITERATURE,
               "note": "change: refined (dx/2, dt/2, 2x particles per cell) minus the first "
                       "run; +-: batch-means standard errors"}
    (out / "hard_sphere_shock.json").write_text(json_text(summary, indent=1))
    print(f"table: {out / 'hard_sphere_shock.json'}")
    figure(entries, out / "hard_sphere_shock.png")
    print(f"figure: {out / 'hard_sphere_shock.png'}")


if __name__ == "__main__":
    raise SystemExit(finish(main))
