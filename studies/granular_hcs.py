r"""Instabilities of the homogeneous cooling state: the shear mode against linear granular
hydrodynamics (3D inelastic hard spheres, the rescaled formulation).

In the rescaled variables of a hard-sphere gas (kappa = 1) the transport of g is that of
f, and linear Navier-Stokes hydrodynamics gives the amplitude A of the transverse velocity
mode u_2 / sqrt(T) = A sin(k x) (the same for g and f) the rate in s

    Gamma(k) = zeta_g / 2 - (eta(T_g) / rho) k^2,

with zeta_g the collisional cooling rate of g in its cooling state and eta the shear
viscosity. The rescaling rate a_0 is that of the Maxwellian f0; the cooling state's
zeta_g differs from 2 a_0 by its a_2 correction (3 a_2 / 16), so T_g drifts slowly and
zeta_g is measured from it (:func:`cooling_rate`). The first Sonine approximation
(Brey, Dufty, Kim & Santos, Phys. Rev. E 58 (1998) 4638; Garzo & Dufty, Phys. Rev. E 59
(1999) 5895) gives zeta and eta (:func:`granframe.theory.modes.shear_mode`), so the shear
mode grows for k < k_c = sqrt(rho zeta / (2 eta)); the longitudinal modes, the heat mode and
its critical k_h are :mod:`granframe.theory.modes`, the coefficients
:mod:`granframe.theory.sonine`.

Run: ``python studies/granular_hcs.py --out DIR [--restitution 0.9] [--n-modes 24]``.
"""

from __future__ import annotations

import math
import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.theory.modes import (density_response, heat_critical_wavenumber, heat_mode,
                                    heat_mode_index, longitudinal_matrix, shear_mode)
from granframe.theory.sonine import reference_frequency
from granframe.tools.analysis import (cooling_state_rate, heat_mode_rates, last_quarter,
                                      relaxed_rate)
from granframe.tools.studykit import (draw, finish, json_text, number, numbers,
                                      output_folder, parse_study, print_table, run_study,
                                      save_figure, study_arguments)


def description(e: float, length: float, cells: int, n_modes: int, support: float,
                final: float, amplitude: float = 0.02, knudsen: float = 1.0,
                field: str = "velocity", quadrature: str = "auto") -> RunDescription:
    """A rescaled 3D hard-sphere gas in a periodic box of ``length`` with the shear mode
    u_2 = amplitude sin(2 pi x / length), or (``field`` 'density') the density mode
    rho = 1 + amplitude sin(2 pi x / length) at uniform T, or (``field`` 'heat') the
    Navier-Stokes heat mode (:func:`~granframe.theory.modes.heat_mode`, first Sonine) of
    that wavenumber as a local Maxwellian
    (:func:`~granframe.theory.modes.longitudinal_maxwellian`); ``quadrature`` the fast
    operator's rules ('auto', the default's, or 'review': a quarter of the cost at N = 24,
    but 3.7 % of max |Q| from the default's on a near-Maxwellian there)."""
    grid = {"dimension": 3, "n_modes": n_modes, "support_radius": support}
    k = 2 * math.pi / length
    if field == "heat":
        _, (r, w, theta) = heat_mode(e, k / reference_frequency(knudsen, 1.0, 1.0))
        initial = {"name": "space_function",
                   "function": "granframe.theory.modes:longitudinal_maxwellian",
                   "params": {"k": k, "amplitude": amplitude, "density": float(r),
                              "velocity": float(w), "temperature": float(theta)}}
    else:
        initial = {"name": "sinusoidal_mode", "amplitude": amplitude,
                   **({"field": "velocity", "component": 2} if field == "velocity"
                      else {"field": "density"})}
    return RunDescription(
        title=f"HCS {field} mode, e = {e:g}, length {length:g}, {cells} cells, N = {n_modes}",
        grid=grid, kernel="hard_spheres", restitution={"name": "constant", "value": e},
        initial=initial,
        operator={"name": "fast_spectral", "quadrature": quadrature},
        integrator="rk4", time_step=DT, final_time=final, rescaled=True, conservative=True,
        knudsen=knudsen, output={"snapshot_interval": final},
        space={"cells": cells, "length": length, "reconstruction": "weno5"})


DT = 0.05


def amplitude_history(ds, length: float, field: str = "velocity"):
    """s and the sine amplitude of u_2/sqrt(T) (``velocity``) or of rho - <rho> (any other
    ``field``: the density and the heat mode)."""
    x = ds.x.values
    if field == "velocity":
        wave = ds.velocity.values[:, :, 1] / numpy.sqrt(ds.temperature.values)
    else:
        wave = ds.density.values - ds.density.values.mean(axis=1, keepdims=True)
    return ds.time.values, 2 * numpy.mean(wave * numpy.sin(2 * math.pi * x / length)[None],
                                          axis=1)


def measured_rate(ds, length: float, skip: float) -> dict:
    """The rate Gamma of the sine amplitude A of u_2 / sqrt(T) (= that of g) in the
    hydrodynamic regime, after the kinetic relaxation of the Maxwellian f0
    (:func:`granframe.tools.analysis.relaxed_rate`)."""
    return relaxed_rate(*amplitude_history(ds, length), skip)


def cooling_rate(ds, skip: float) -> float:
    """zeta_g / 2 of the cooling state the run reaches
    (:func:`granframe.tools.analysis.cooling_state_rate`)."""
    return cooling_state_rate(ds.time.values, ds.density.values, ds.temperature.values,
                              ds.attrs["rescaling_rate"], skip)


def density_comparison(ds, e: float, length: float, knudsen: float = 1.0) -> dict:
    """The density mode's amplitude A(s)/A(0) (the sine coefficient of rho) against
    Navier-Stokes (:func:`~granframe.theory.modes.density_response` at the run's mean
    T_g): at the end, and the largest difference over the run."""
    s, amplitude = amplitude_history(ds, length, "density")
    measured = amplitude / amplitude[0]
    temperature = float(ds.temperature.values.mean())
    predicted = density_response(e, knudsen, temperature, 2 * math.pi / length, s)
    return {"A(end)/A(0)": float(measured[-1]), "NS A(end)/A(0)": float(predicted[-1]),
            "max difference": float(numpy.abs(measured - predicted).max())}


def heat_projection(ds, e: float, length: float, k_star: float, zeta: float):
    r"""The heat mode's amplitude of a longitudinal run at each s, projected on the
    Navier-Stokes heat mode: with the sine amplitudes of rho/<rho> - 1 and T/<T> - 1 and
    the cosine amplitude of u_1/sqrt(<T>) (the variables (rho', w, theta) of
    :func:`~granframe.theory.modes.longitudinal_matrix`, <.> the mean over the cells at each s),

        c_h(s) = l . (rho', w, theta)(s),   l M = lambda_h l,

    l the left eigenvector of M(k*) (``zeta`` = zeta*) of the heat mode's eigenvalue
    lambda_h. It has no sound in it as far as the kinetic modes are those of
    Navier-Stokes, so its slope is a check on :func:`heat_and_sound` that assumes nothing
    about the sound pair's frequency and damping."""
    phase = 2 * math.pi * ds.x.values[None] / length
    density, temperature = ds.density.values, ds.temperature.values
    mean_t = temperature.mean(axis=1, keepdims=True)
    amplitudes = [2 * numpy.mean(field * wave, axis=1) for field, wave in (
        (density / density.mean(axis=1, keepdims=True) - 1.0, numpy.sin(phase)),
        (ds.velocity.values[:, :, 0] / numpy.sqrt(mean_t), numpy.cos(phase)),
        (temperature / mean_t - 1.0, numpy.sin(phase)))]
    values, vectors = numpy.linalg.eig(longitudinal_matrix(e, k_star, zeta).T)
    left = vectors[:, heat_mode_index(values, k_star)].real
    return sum(weight * amplitude for weight, amplitude in zip(left, amplitudes))


def heat_comparison(ds, e: float, length: float, skip: float, knudsen: float = 1.0) -> dict:
    """The heat mode's rate in s, measured (:func:`heat_and_sound` on the density's sine
    amplitude; ``late``: the straight slope of ln A over the last quarter; ``projected
    late``: that of :func:`heat_projection`) against Navier-Stokes, lambda_h nu_0(T_g)
    (:func:`~granframe.theory.modes.heat_mode` at k* = k sqrt(T_g)/nu_0(T_g)), with the
    first Sonine zeta* and with the run's own zeta_g/nu_0(T_g) (:func:`cooling_rate`), T_g
    the run's mean temperature at the end, and with the linear Burnett terms as well
    (``Burnett rate with zeta_g``, :func:`~granframe.theory.modes.longitudinal_matrix`
    with ``burnett=True``); and ``conduction``, the factor f on
    kappa* - mu* (both scaled) that makes the Navier-Stokes rate with zeta_g the measured
    one, whence the kinetic k_h / k_h(first Sonine) = 1/sqrt(f) (k_h^2 = zeta*/(5 f
    (kappa* - mu*)), :func:`~granframe.theory.modes.heat_critical_wavenumber`); f is NaN
    where no f in [1/4, 4] gives the measured rate (a run too short or too coarse to
    measure it)."""
    import scipy.optimize

    s, amplitude = amplitude_history(ds, length, "heat")
    rates, scales = heat_mode_rates(s, amplitude, e, 2 * math.pi / length,
                                    float(ds.temperature.values[-1].mean()),
                                    cooling_rate(ds, skip), skip, knudsen)
    nu0, k_star, zeta_g = scales["nu0"], scales["k*"], scales["zeta*"]
    late = last_quarter(s, skip)
    projected = heat_projection(ds, e, length, k_star, zeta_g)

    def excess(factor):
        return heat_mode(e, k_star, zeta_g, factor)[0] * nu0 - rates["measured rate"]

    factor = (scipy.optimize.brentq(excess, 0.25, 4.0) if excess(0.25) * excess(4.0) < 0
              else math.nan)
    return {"measured rate": rates["measured rate"], "measured late": rates["measured late"],
            "projected late": float(numpy.polyfit(s[late], numpy.log(numpy.abs(
                projected[late])), 1)[0]),
            "sound/heat": rates["sound/heat"], "fit rms": rates["fit rms"],
            "Navier-Stokes rate": rates["Navier-Stokes rate (Sonine zeta)"],
            "Navier-Stokes rate with zeta_g": rates["Navier-Stokes rate with zeta_g"],
            "Burnett rate with zeta_g": heat_mode(e, k_star, zeta_g, burnett=True)[0] * nu0,
            "conduction": factor, "k_h/k_h Sonine": 1.0 / math.sqrt(factor)}


def heat_critical_between(e: float, rows: list[dict], rate: str = "measured rate") -> float:
    """The kinetic k_h: the wavenumber where the measured heat-mode rate crosses zero,
    between two runs of :func:`heat_comparison` on either side (``rows``: their ``k``,
    ``rate``, ``T_g`` and ``zeta_g/2``). The measured rate is the Navier-Stokes one
    (with the first run's zeta_g, :func:`~granframe.theory.modes.heat_mode`) plus a
    difference interpolated linearly in k^2 between the two runs, so that the curvature of
    the rate in k is Navier-Stokes' and only the difference is interpolated; the root is
    found in [k_1, k_2]."""
    import scipy.optimize

    first, second = sorted(rows, key=lambda row: row["k"])
    temperature, half_zeta = first["T_g"], first["zeta_g/2"]
    nu0 = reference_frequency(1.0, 1.0, temperature)

    def navier_stokes(k):
        return heat_mode(e, k * math.sqrt(temperature) / nu0, 2 * half_zeta / nu0)[0] * nu0

    low, high = first["k"], second["k"]
    below, above = (row[rate] - navier_stokes(row["k"]) for row in (first, second))

    def kinetic(k):
        return navier_stokes(k) + below + (above - below) * (k * k - low * low) / (
            high * high - low * low)

    if kinetic(low) * kinetic(high) > 0:
        raise ValueError(f"heat_critical_between: the rates {first[rate]:.3g} at k = {low:.4g} "
                         f"and {second[rate]:.3g} at k = {high:.4g} do not change sign")
    return float(scipy.optimize.brentq(kinetic, low, high, xtol=1e-12))


def figure(stores, path) -> None:
    """ln(A(s)/A(0)) of each run against s, with the Navier-Stokes prediction (dashed):
    the shear mode's rate zeta_g/2 - eta k^2/rho (zeta_g the run's :func:`cooling_rate`)
    and the heat mode's (:func:`heat_comparison`, with zeta_g) from s = 1 on, the density
    mode's :func:`~granframe.theory.modes.density_response`."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, ax = plt.subplots(figsize=(7, 4.5), layout="tight")
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        description = RunDescription.from_toml(ds.attrs["description_toml"])
        length, e = description.space.length, description.restitution.params["value"]
        field = ("heat" if description.initial.name == "space_function"
                 else description.initial.params.get("field", "velocity"))
        s, amplitude = amplitude_history(ds, length, field)
        label = (f"{ {'velocity': 'shear'}.get(field, field)}, e = {e:g}, "
                 f"k = {2 * math.pi / length:.3f}, N = {description.grid.n_modes}, "
                 f"{description.space.cells} cells")
        line, = ax.plot(s, numpy.log(amplitude / amplitude[0]), label=label)
        k = 2 * math.pi / length
        temperature = float(ds.temperature.values.mean())
        if field == "density":
            reference = numpy.log(density_response(e, description.knudsen, temperature, k, s))
        else:
            if field == "heat":
                rate = heat_comparison(ds, e, length, 1.0,
                                       description.knudsen)["Navier-Stokes rate with zeta_g"]
            else:
                eta = shear_mode(e, description.knudsen, 1.0, temperature, k)["eta"]
                rate = cooling_rate(ds, 1.0) - eta * k * k
            reference = numpy.log(amplitude[s >= 1.0][0] / amplitude[0]) + rate * (s - 1.0)
        ax.plot(s, reference, "--", color=line.get_color(), lw=1)
    ax.set_xlabel("rescaled time s")
    ax.set_ylabel("ln A(s)/A(0)")
    ax.set_title("modes of the cooling state (3D hard spheres): granframe (solid), "
                 "Navier-Stokes (dashed)", fontsize=9)
    ax.legend(fontsize=7)
    save_figure(fig, path, dpi=120)


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=24, cells=12, final=6.0,
                             quick={"n_modes": 16, "cells": 8, "final": 1.5,
                                    "skip": 0.5})
    parser.add_argument("--skip", type=number(0.0, low_open=False), default=1.0,
                        help="the rescaled time s left out of the fits (the relaxation)")
    parser.add_argument("--k-over-kc", type=numbers(0.0), default=[0.5, 1.0, 1.5],
                        help="wavenumbers over the shear mode's k_c, comma-separated")
    parser.add_argument("--k-over-kh", type=numbers(0.0), default=None,
                        help="wavenumbers over the heat mode's k_h instead")
    parser.add_argument("--field", choices=("velocity", "density", "heat"),
                        default="velocity", help="the shear mode (velocity, u_2), the "
                        "density mode or the heat mode (its Navier-Stokes eigenvector)")
    args = parse_study(parser, argv)
    out = output_folder(args, figure, "modes.png")
    if out is None:
        return
    e = args.restitution
    if args.k_over_kh:
        unit, ratio_name = "kh", "k/k_h"
        scale = heat_critical_wavenumber(e) * reference_frequency(1.0, 1.0, 1.0)
    else:
        unit, ratio_name, scale = "k", "k/k_c", shear_mode(e, 1.0, 1.0, 1.0, 1.0)["k_c"]
    name = {"velocity": "shear"}.get(args.field, args.field)
    rows, stores = [], []
    for ratio in args.k_over_kh or args.k_over_kc:
        k = ratio * scale
        length = 2 * math.pi / k
        began = time.perf_counter()
        run = Simulation(description(e, length, args.cells, args.n_modes, args.support,
                                     args.final, field=args.field,
                                     quadrature=args.quadrature))
        store = out / f"{name}_e{e:g}_{unit}{ratio:g}.zarr"
        result = run_study(run, store, args, overwrite=True)
        ds = granframe.open_run(store, time_axis="steps")
        seconds = time.perf_counter() - began
        temperature = float(ds.temperature.values[-1].mean())
        predicted = shear_mode(e, 1.0, 1.0, temperature, k)
        half_zeta = cooling_rate(ds, args.skip)
        if args.field == "velocity":
            compared = {"Navier-Stokes rate": predicted["rate"],
                        "Navier-Stokes rate with zeta_g": half_zeta - predicted["eta"] * k * k,
                        **{f"measured {key}": value
                           for key, value in measured_rate(ds, length, args.skip).items()}}
        elif args.field == "density":
            compared = density_comparison(ds, e, length)
        else:
            compared = heat_comparison(ds, e, length, args.skip)
        row = {"e": e, ratio_name: ratio, "k": k, "length": length, "cells": args.cells,
               "N": args.n_modes, "S": args.support, "quadrature": args.quadrature,
               "a_0": ds.attrs["rescaling_rate"],
               "zeta/2 Sonine": predicted["zeta"] / 2, "T_g": temperature,
               "zeta_g/2": half_zeta, **compared,
               "seconds": seconds,
               "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]}
        rows.append(row)
        stores.append(store)
    print_table(rows, {"e": "g", ratio_name: "g", "k": ".4g", "N": "d", "cells": "d",
                       "zeta/2 Sonine": ".5g", "zeta_g/2": ".5g", "seconds": ".0f",
                       **{key: ".5g" for key in rows[0] if key.startswith(("measured rate",
                                                                           "Navier-Stokes rate",
                                                                           "rate"))}})
    (out / f"{name}_e{e:g}.json").write_text(json_text(rows, indent=1))
    print(f"table: {out / f'{name}_e{e:g}.json'}")
    draw(figure, stores, out / "modes.png")
    rates = [row["measured rate"] for row in rows] if args.field == "heat" else []
    if len(rates) == 2 and rates[0] * rates[1] < 0:
        sonine_k = heat_critical_wavenumber(e) * reference_frequency(1.0, 1.0, 1.0)
        found = {"e": e, "k_h": heat_critical_between(e, rows), "k_h Sonine": sonine_k,
                 "k_h from the projected late slopes":
                     heat_critical_between(e, rows, "projected late")}
        found["k_h/k_h Sonine"] = found["k_h"] / sonine_k
        print(json_text(found))
        (out / f"{name}_e{e:g}_critical.json").write_text(json_text(found, indent=1))


if __name__ == "__main__":
    raise SystemExit(finish(main))
