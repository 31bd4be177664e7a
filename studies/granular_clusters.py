r"""Clusters growing out of the homogeneous cooling state, past the linear regime, with the
velocity grid's monitors watched until they say it no longer holds the cold dense gas.

A periodic box of length ell, the gas at rho = 1, T = 1 with the transverse mode
u_2 = A sin(2 pi x / ell) (k below the shear mode's critical k_c), in the rescaled
formulation (docs/space.md: the cooling state is steady, the velocity grid follows the
mean temperature). The shear mode grows; once u_2 is of the thermal speed its viscous
heating, largest where du_2/dx is, drives gas out of the shear zones into the extrema of
u_2, where it cools faster than the mean (the sink goes as rho^2 T^{3/2}): two dense, cold
bands per wavelength. The run records at every step the total mass (its drift), the
smallest value of f and the share of negative mass, and the grid's resolution monitors
(spectral tail, support, heat flux of the outermost shell, edge mass and energy); it
stops on its own when f becomes too negative (the positivity guard: the study then reports
the stop and the monitors up to it) or at the final s.

2D velocities with the kernel B = |g|/(2 pi) (kappa = 1, so the rescaled transport is that
of f); the point is what the monitors report as the clusters sharpen, not a number for
hard disks.

Run: ``python studies/granular_clusters.py --out DIR [--restitution 0.8] [--final 40]``.
"""

from __future__ import annotations

import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.tools.analysis import cluster_monitors
from granframe.tools.studykit import (draw, finish, json_text, number, output_folder,
                                      parse_study, print_table, run_to_stop, save_figure,
                                      study_arguments)

DT = 0.05


def description(e: float, length: float, cells: int, n_modes: int, support: float,
                final: float, amplitude: float) -> RunDescription:
    """The rescaled 2D gas (B = |g|/(2 pi), eps = 1) with the shear mode, WENO5, RK4 with
    the conservative correction, ds = :data:`DT`, f stored every 2 s (or at the end)."""
    return RunDescription(
        title=f"clusters, e = {e:g}, length {length:g}, {cells} cells, N = {n_modes}",
        grid={"dimension": 2, "n_modes": n_modes, "support_radius": support},
        kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial={"name": "sinusoidal_mode", "field": "velocity", "component": 2,
                 "amplitude": amplitude},
        operator={"name": "fast_spectral"}, integrator="rk4", time_step=DT,
        final_time=final, rescaled=True, conservative=True, knudsen=1.0,
        output={"snapshot_interval": min(2.0, final)},
        space={"cells": cells, "length": length, "reconstruction": "weno5"})


def figure(stores, path) -> None:
    """The x-s map of rho of each run, with the density contrast, the smallest T/<T> and
    the negative mass share against s below; a red dashed line where the accuracy monitor
    first flagged."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(2, len(stores), figsize=(5 * len(stores), 7), squeeze=False,
                             layout="tight")
    for column, store in enumerate(stores):
        ds = granframe.open_run(store, time_axis="steps")
        s, x = ds.time.values, ds.x.values
        density, temperature = ds.density.values, ds.temperature.values
        top = axes[0, column].pcolormesh(x, s, density, shading="nearest", cmap="viridis")
        fig.colorbar(top, ax=axes[0, column], label="density")
        axes[0, column].set_xlabel("x")
        axes[0, column].set_ylabel("rescaled time s")
        axes[0, column].set_title(ds.attrs["title"], fontsize=8)
        low = axes[1, column]
        low.semilogy(s, density.max(axis=1) / density.min(axis=1), label="rho max / rho min")
        low.semilogy(s, temperature.min(axis=1) / temperature.mean(axis=1),
                     label="T min / <T>")
        low.semilogy(s, numpy.maximum(ds.negative_mass_fraction.values, 1e-16),
                     label="negative mass share")
        low.axhline(1e-3, color="k", lw=0.6, ls=":")
        flagged = ds.attrs.get("progress_accuracy_flagged_time")
        if flagged is not None:
            for ax in (axes[0, column], low):
                horizontal = ax is axes[0, column]
                (ax.axhline if horizontal else ax.axvline)(flagged, color="r", lw=0.8,
                                                           ls="--")
            monitor = ds.attrs.get("progress_accuracy_flagged_monitor")
            low.text(flagged, 1e-6, f" accuracy monitor flags\n ({monitor}) at s = {flagged:g}",
                     color="r", fontsize=7)
        low.set_xlabel("rescaled time s")
        low.legend(fontsize=7, loc="upper left")
    save_figure(fig, path, dpi=120)


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=32, cells=32, final=30.0,
                             quick={"n_modes": 24, "cells": 16, "final": 2.0})
    parser.set_defaults(restitution=0.8, support=4.0)
    parser.add_argument("--length", type=number(0.0), default=40.0, help="the box length")
    parser.add_argument("--amplitude", type=number(0.0, low_open=False), default=0.3,
                        help="the initial shear amplitude")
    args = parse_study(parser, argv)
    out = output_folder(args, figure, "clusters.png")
    if out is None:
        return
    began = time.perf_counter()
    run = Simulation(description(args.restitution, args.length, args.cells, args.n_modes,
                                 args.support, args.final, args.amplitude))
    store = out / f"clusters_e{args.restitution:g}_c{args.cells}_n{args.n_modes}.zarr"
    warnings = run_to_stop(run, store, args)
    ds = granframe.open_run(store, time_axis="steps")
    row = {"e": args.restitution, "length": args.length, "cells": args.cells,
           "N": args.n_modes, "S": args.support, "seconds": time.perf_counter() - began,
           **cluster_monitors(ds), "warnings": warnings}
    print_table([row], {key: ".5g" for key, value in row.items() if isinstance(value, float)})
    store.with_suffix(".json").write_text(json_text(row, indent=1))
    print(f"table: {store.with_suffix('.json')}")
    draw(figure, [store], out / "clusters.png")


if __name__ == "__main__":
    raise SystemExit(finish(main))
