r"""The homogeneous cooling state on a periodic square: its shear (vortex) and heat
(cluster) modes on a wave vector off the axes against linear granular hydrodynamics, then
vortices and clusters past the linear regime, watched by the grid's monitors.

``--part modes`` (the default). 3D inelastic hard spheres (eps = 1), the rescaled
formulation, on a periodic square of side L = sqrt(2) 2 pi / k with the mode on the wave
vector [1, 1] (|K| = k, along the diagonal): the shear mode u = A sin(K . x) K_perp/k,
A = 0.02, or the Navier-Stokes heat mode (:func:`granframe.theory.modes.heat_mode`, first
Sonine) of that k as a local Maxwellian
(:func:`granframe.theory.modes.plane_modes_maxwellian`). Everything else is the 1D study's
(``studies/granular_hcs.py``): the fast operator, RK4 with the conservative correction,
ds = 0.05, WENO5 on both axes, and its fits (:mod:`granframe.tools.analysis`): the shear
rate Gamma of the sine amplitude of u . K_perp / (k sqrt(T)) past the relaxation, against
Navier-Stokes zeta_g/2 - eta k^2 (zeta_g the run's own cooling rate); the heat mode's rate
of the density's sine amplitude, its sound pair fitted out, against
:func:`~granframe.theory.modes.heat_mode` with zeta_g. On C x C cells the mode has C cells
per period along each axis, as the 1D run on C cells; each C of ``--cells`` is a column of
the refinement.

``--part clusters``. 2D velocities, B = |g| / (2 pi) (kappa = 1, as the 1D clusters study;
no number is compared with a hard-disk theory), e = 0.8, rescaled, on a periodic square of
side ``--length``: a lattice of vortices, the transverse modes on [1, 0] and [0, 1] of
amplitude A, and A/10 on [1, 1] to break the lattice's symmetry. Recorded every step: the
mass, min f, the negative mass share and the grid's resolution and accuracy monitors
(docs/runner.md); from the records the density contrast, T_min/<T>, max |u|/sqrt(<T>) and
the structure factor S(k, s) = |rho_hat(k)|^2 / C^2 (rho_hat the discrete Fourier transform
of rho - <rho> on the cells) averaged over shells n - 1/2 < |k| L / 2 pi <= n + 1/2; the
run stops itself on its positivity check or at the final s.

    python studies/granular_hcs_2d.py --out DIR [--field shear|heat] [--cells 8,12]
        [--n-modes 16] [--final 4] [--restitution 0.9] [--k-over-kc 0.5]
    python studies/granular_hcs_2d.py --out DIR --part clusters [--cells 24] [--n-modes 32]
        [--support 4] [--final 30] [--length 40] [--amplitude 0.3]

write ``modes_<field>.json`` and ``modes_<field>.png`` (ln A against s with Navier-Stokes),
or ``clusters.json``, ``clusters.png`` (maps of rho, T and the vorticity at four records)
and ``clusters_monitors.png`` (contrast, S(k, s) and the monitors against s) in DIR.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.theory.modes import heat_mode, shear_mode
from granframe.theory.sonine import reference_frequency
from granframe.tools.analysis import (cluster_monitors, cooling_state_rate, heat_mode_rates,
                                      relaxed_rate)
from granframe.tools.studykit import (finish, json_text, number, numbers, print_table,
                                      run_study, run_to_stop, save_figure)

DT = 0.05
MODES = "granframe.theory.modes:plane_modes_maxwellian"


def mode_description(field: str, e: float, k: float, cells: int, n_modes: int,
                     support: float, final: float, amplitude: float = 0.02) -> RunDescription:
    """The rescaled 3D hard-sphere gas on the square of side sqrt(2) 2 pi / k with the
    ``field`` ('shear' or 'heat') mode on the wave vector [1, 1]."""
    length = math.sqrt(2.0) * 2.0 * math.pi / k
    if field == "shear":
        modes = [{"field": "transverse", "wave": [1, 1], "amplitude": amplitude}]
    else:
        _, (r, w, theta) = heat_mode(e, k / reference_frequency(1.0, 1.0, 1.0))
        modes = [{"field": "density", "wave": [1, 1], "amplitude": amplitude * float(r)},
                 {"field": "longitudinal", "wave": [1, 1], "amplitude": amplitude * float(w),
                  "phase": math.pi / 2},
                 {"field": "temperature", "wave": [1, 1],
                  "amplitude": amplitude * float(theta)}]
    return _square_run(f"HCS {field} mode on [1, 1], e = {e:g}, k = {k:.4g}, {cells}^2 "
                       f"cells, N = {n_modes}", 3, n_modes, support, e, modes, length, cells,
                       final, final)


def plane_amplitude(ds, field: str):
    """s and the sine amplitude on K = 2 pi [1, 1] / L of u . K_perp / (|K| sqrt(T))
    (``shear``) or of rho - <rho> (``heat``), 2 <w sin(K . x)> over the cells."""
    x, y = numpy.meshgrid(ds.x.values, ds.y.values, indexing="ij")
    length = float(ds.x.values[0] * 2 * len(ds.x))
    wave = numpy.sin(2 * math.pi * (x + y) / length)
    if field == "shear":
        u = ds.velocity.values
        values = (u[..., 1] - u[..., 0]) / math.sqrt(2.0) / numpy.sqrt(ds.temperature.values)
    else:
        rho = ds.density.values
        values = rho - rho.mean(axis=(1, 2), keepdims=True)
    return ds.time.values, 2 * (values * wave[None]).mean(axis=(1, 2))


def compare_mode(ds, field: str, e: float, k: float, skip: float) -> dict:
    """The measured rate against Navier-Stokes (shear: zeta_g/2 - eta k^2 at the final
    T_g; heat: lambda_h nu_0(T_g) at k* = k sqrt(T_g)/nu_0(T_g) with the run's zeta_g)."""
    s, amplitude = plane_amplitude(ds, field)
    temperature = float(ds.temperature.values[-1].mean())
    half_zeta = cooling_state_rate(s, ds.density.values, ds.temperature.values,
                                   ds.attrs["rescaling_rate"], skip)
    row = {"T_g": temperature, "zeta_g/2": half_zeta}
    if field == "shear":
        predicted = shear_mode(e, 1.0, 1.0, temperature, k)
        fit = relaxed_rate(s, amplitude, skip)
        row.update({"measured rate": fit["rate"], "measured late": fit["late"],
                    "relaxation": fit["relaxation"],
                    "Navier-Stokes rate with zeta_g": half_zeta - predicted["eta"] * k * k,
                    "Navier-Stokes rate (Sonine zeta)": predicted["rate"]})
    else:
        row.update(heat_mode_rates(s, amplitude, e, k, temperature, half_zeta, skip)[0])
    row["measured - NS(zeta_g)"] = row["measured rate"] - row["Navier-Stokes rate with zeta_g"]
    return row


def modes_figure(stores, field: str, path) -> None:
    """ln A(s)/A(0) of each run, and the Navier-Stokes rate with the run's zeta_g from
    s = 1 (dashed)."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, ax = plt.subplots(figsize=(7, 4.5), layout="tight")
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        d = RunDescription.from_toml(ds.attrs["description_toml"])
        e = d.restitution.params["value"]
        k = 2 * math.pi * math.sqrt(2.0) / d.space.lengths[0]
        s, amplitude = plane_amplitude(ds, field)
        row = compare_mode(ds, field, e, k, 1.0)
        line, = ax.plot(s, numpy.log(amplitude / amplitude[0]),
                        label=f"{field}, e = {e:g}, k = {k:.3f}, N = {d.grid.n_modes}, "
                              f"{d.space.counts[0]}^2 cells")
        start = numpy.argmax(s >= 1.0)
        ax.plot(s[start:], numpy.log(amplitude[start] / amplitude[0])
                + row["Navier-Stokes rate with zeta_g"] * (s[start:] - s[start]), "--",
                color=line.get_color(), lw=1)
    ax.set_xlabel("rescaled time s")
    ax.set_ylabel("ln A(s)/A(0)")
    ax.set_title("a mode of the cooling state on the wave vector [1, 1] (3D hard spheres): "
                 "granframe (solid), Navier-Stokes (dashed)", fontsize=8)
    ax.legend(fontsize=7)
    save_figure(fig, path, dpi=120)


def run_modes(args, out: pathlib.Path) -> None:
    e = args.restitution
    k = args.k_over_kc * shear_mode(e, 1.0, 1.0, 1.0, 1.0)["k_c"]
    rows, stores = [], []
    for cells in args.cells:
        began = time.perf_counter()
        run = Simulation(mode_description(args.field, e, k, cells, args.n_modes,
                                          args.support, args.final))
        store = out / f"{args.field}_e{e:g}_c{cells}_n{args.n_modes}.zarr"
        result = run_study(run, store, args, overwrite=True)
        ds = granframe.open_run(store, time_axis="steps")
        rows.append({"field": args.field, "e": e, "k/k_c": args.k_over_kc, "k": k,
                     "cells": cells, "N": args.n_modes, "S": args.support,
                     "a_0": ds.attrs["rescaling_rate"],
                     **compare_mode(ds, args.field, e, k, args.skip),
                     "seconds": time.perf_counter() - began,
                     "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]})
        stores.append(store)
    print_table(rows, {"cells": "d", "N": "d", "zeta_g/2": ".5g", "measured rate": ".5g",
                       "measured late": ".5g", "Navier-Stokes rate with zeta_g": ".5g",
                       "measured - NS(zeta_g)": ".2e", "seconds": ".0f"})
    (out / f"modes_{args.field}.json").write_text(json_text(rows, indent=1))
    modes_figure(stores, args.field, out / f"modes_{args.field}.png")


def cluster_description(e: float, length: float, cells: int, n_modes: int, support: float,
                        final: float, amplitude: float) -> RunDescription:
    """The rescaled 2D gas with the lattice of vortices (module notes)."""
    modes = [{"field": "transverse", "wave": [1, 0], "amplitude": amplitude},
             {"field": "transverse", "wave": [0, 1], "amplitude": amplitude},
             {"field": "transverse", "wave": [1, 1], "amplitude": amplitude / 10}]
    return _square_run(f"vortices and clusters, e = {e:g}, square {length:g}, {cells}^2 "
                       f"cells, N = {n_modes}", 2, n_modes, support, e, modes, length, cells,
                       final, min(2.0, final))


def _square_run(title: str, dimension: int, n_modes: int, support: float, e: float,
                modes: list, length: float, cells: int, final: float,
                snapshot: float) -> RunDescription:
    """The rescaled hard-sphere gas (eps = 1) on the periodic square of side ``length`` with
    the plane ``modes``: the fast operator, RK4 with the conservative correction,
    ds = :data:`DT`, WENO5 on ``cells``^2 cells, f stored every ``snapshot``."""
    return RunDescription(
        title=title, grid={"dimension": dimension, "n_modes": n_modes,
                           "support_radius": support},
        kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial={"name": "space_function", "function": MODES,
                 "params": {"lengths": [length, length], "modes": modes}},
        operator={"name": "fast_spectral"}, integrator="rk4", time_step=DT,
        final_time=final, rescaled=True, conservative=True, knudsen=1.0,
        output={"snapshot_interval": snapshot},
        space={"cells": [cells, cells], "length": [length, length],
               "reconstruction": "weno5", "bottom": "periodic", "top": "periodic"})


def structure_factor(density) -> numpy.ndarray:
    """S(n, record) for the shells n = 1 .. C/2 of |k| L / (2 pi): the mean over each shell
    of |rho_hat|^2 / C^2, rho_hat the 2D DFT of rho - <rho> over the C x C cells."""
    density = numpy.asarray(density)
    cells = density.shape[-1]
    spectrum = numpy.abs(numpy.fft.fft2(density - density.mean(axis=(-2, -1), keepdims=True)))
    power = spectrum ** 2 / cells ** 2
    n = numpy.fft.fftfreq(cells, 1.0 / cells)
    radius = numpy.rint(numpy.hypot(n[:, None], n[None, :])).astype(int)
    shells = numpy.arange(1, cells // 2 + 1)
    return numpy.stack([power[:, radius == shell].mean(axis=1) for shell in shells], axis=1)


def vorticity(ds, record: int):
    """d u_2/dx - d u_1/dy of a record by central differences on the periodic cells."""
    u = ds.velocity.values[record]
    dx = float(ds.x.values[1] - ds.x.values[0])
    dy = float(ds.y.values[1] - ds.y.values[0])
    return ((numpy.roll(u[..., 1], -1, 0) - numpy.roll(u[..., 1], 1, 0)) / (2 * dx)
            - (numpy.roll(u[..., 0], -1, 1) - numpy.roll(u[..., 0], 1, 1)) / (2 * dy))


def cluster_history(ds) -> dict:
    """Per record: s, rho_max/rho_min, T_min/<T>, max |u| / sqrt(<T>), <T>, the structure
    factor's shells and the negative mass share."""
    density, temperature = ds.density.values, ds.temperature.values
    mean_t = temperature.mean(axis=(1, 2))
    speed = numpy.sqrt((ds.velocity.values ** 2).sum(axis=-1)).max(axis=(1, 2))
    return {"s": ds.time.values,
            "contrast": density.max(axis=(1, 2)) / density.min(axis=(1, 2)),
            "T min/mean": temperature.min(axis=(1, 2)) / mean_t,
            "max |u|/sqrt<T>": speed / numpy.sqrt(mean_t), "<T>": mean_t,
            "S": structure_factor(density),
            "negative": ds.negative_mass_fraction.values}


def cluster_figures(ds, out: pathlib.Path) -> None:
    """Maps of rho, T/<T> and the vorticity at four records; the history below."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    history = cluster_history(ds)
    s = history["s"]
    records = sorted({int(i) for i in numpy.linspace(0, len(s) - 1, 4)})
    fig, axes = plt.subplots(3, len(records), figsize=(3.6 * len(records), 9.6),
                             squeeze=False, layout="constrained")
    x, y = ds.x.values, ds.y.values
    for column, record in enumerate(records):
        temperature = ds.temperature.values[record]
        for row, (values, label, cmap) in enumerate((
                (ds.density.values[record], "density", "viridis"),
                (temperature / temperature.mean(), "T / <T>", "inferno"),
                (vorticity(ds, record), "vorticity", "RdBu_r"))):
            ax = axes[row, column]
            limit = numpy.abs(values).max() if label == "vorticity" else None
            mesh = ax.pcolormesh(x, y, values.T, shading="nearest", cmap=cmap,
                                 vmin=-limit if limit else None, vmax=limit)
            fig.colorbar(mesh, ax=ax, label=label, shrink=0.8)
            ax.set_aspect("equal")
            if row == 0:
                ax.set_title(f"s = {s[record]:.2f}", fontsize=9)
    fig.suptitle(ds.attrs["title"], fontsize=9)
    save_figure(fig, out / "clusters.png", dpi=100)

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), layout="tight")
    left.semilogy(s, history["contrast"], label="rho max / rho min")
    left.semilogy(s, history["T min/mean"], label="T min / <T>")
    left.semilogy(s, history["max |u|/sqrt<T>"], label="max |u| / sqrt<T>")
    left.semilogy(s, numpy.maximum(history["negative"], 1e-16), label="negative mass share")
    left.axhline(1e-3, color="k", lw=0.6, ls=":")
    flagged = ds.attrs.get("progress_accuracy_flagged_time")
    if flagged is not None:
        left.axvline(flagged, color="r", lw=0.8, ls="--",
                     label=f"accuracy flagged ({ds.attrs.get('progress_accuracy_flagged_monitor')})")
    left.set_xlabel("rescaled time s")
    left.legend(fontsize=7)
    for shell in range(min(4, history["S"].shape[1])):
        right.semilogy(s, history["S"][:, shell], label=f"|k| L / 2 pi = {shell + 1}")
    right.set_xlabel("rescaled time s")
    right.set_ylabel("structure factor S(k, s)")
    right.legend(fontsize=7)
    save_figure(fig, out / "clusters_monitors.png", dpi=110)


def run_clusters(args, out: pathlib.Path) -> None:
    began = time.perf_counter()
    cells = args.cells[0]
    run = Simulation(cluster_description(args.restitution, args.length, cells,
                                         args.n_modes, args.support, args.final,
                                         args.amplitude))
    store = out / f"clusters_e{args.restitution:g}_c{cells}_n{args.n_modes}.zarr"
    warnings = run_to_stop(run, store, args)
    ds = granframe.open_run(store, time_axis="steps")
    history = cluster_history(ds)
    marks = sorted({int(i) for i in numpy.linspace(0, len(history["s"]) - 1, 9)})
    rows = [{"s": float(history["s"][i]), "rho max/min": float(history["contrast"][i]),
             "T min/<T>": float(history["T min/mean"][i]),
             "max |u|/sqrt<T>": float(history["max |u|/sqrt<T>"][i]),
             "<T>": float(history["<T>"][i]),
             **{f"S(n={n + 1})": float(history["S"][i, n]) for n in range(3)},
             "negative mass share": float(history["negative"][i])} for i in marks]
    print_table(rows, {key: ".4g" for key in rows[0]})
    summary = {"e": args.restitution, "length": args.length, "cells": cells,
               "N": args.n_modes, "S": args.support, "seconds": time.perf_counter() - began,
               **cluster_monitors(ds), "warnings": warnings, "history": rows}
    (out / "clusters.json").write_text(json_text(summary, indent=1))
    print(json_text({key: value for key, value in summary.items() if key != "history"},
                    indent=1))
    cluster_figures(ds, out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", required=True, help="folder for the stores, tables, figures")
    parser.add_argument("--part", choices=("modes", "clusters"), default="modes")
    parser.add_argument("--field", choices=("shear", "heat"), default="shear",
                        help="the mode of --part modes")
    parser.add_argument("--restitution", type=number(0.0, 1.0), default=None,
                        help="e (default 0.9 for the modes, 0.8 for the clusters)")
    parser.add_argument("--cells", type=numbers(4, kind=int), default=None,
                        help="cells per side, comma-separated (default 8,12 for the modes, "
                             "24 for the clusters)")
    parser.add_argument("--n-modes", type=number(4, kind=int, low_open=False), default=None,
                        help="velocity modes N per axis (default 16 modes, 32 clusters)")
    parser.add_argument("--support", type=number(0.0), default=None,
                        help="velocity support S (default 3.5 modes, 4 clusters)")
    parser.add_argument("--final", type=number(0.0), default=None,
                        help="final rescaled time s (default 4 modes, 30 clusters)")
    parser.add_argument("--skip", type=number(0.0, low_open=False), default=1.0,
                        help="the s left out of the modes' fits (the relaxation)")
    parser.add_argument("--k-over-kc", type=number(0.0), default=0.5,
                        help="the modes' |K| over the shear mode's k_c")
    parser.add_argument("--length", type=number(0.0), default=40.0,
                        help="the side of the clusters' square")
    parser.add_argument("--amplitude", type=number(0.0), default=0.3,
                        help="the clusters' vortex amplitude")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None)
    args = parser.parse_args(argv)
    modes = args.part == "modes"
    for name, value in (("restitution", (0.9, 0.8)), ("cells", ([8, 12], [24])),
                        ("n_modes", (16, 32)), ("support", (3.5, 4.0)),
                        ("final", (4.0, 30.0))):
        if getattr(args, name) is None:
            setattr(args, name, value[0] if modes else value[1])
    if min(args.cells) < 7:
        parser.error(f"--cells {args.cells}: WENO5 needs at least 7 cells per side")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (run_modes if modes else run_clusters)(args, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
