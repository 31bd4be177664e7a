"""Review, section 3, Test 2: tails of the heated equilibrium in 2D.

Maxwell molecules (B = 1/(2 pi)) and hard spheres (B = |g|/(2 pi)), e = 0.3, 0.5, 0.7,
heat bath tau = 0.1, flat initial data (w0 = 2 sqrt 6), N = 128, N_rho = 32, M = 16,
R = 20, L = 5(3 + sqrt 2), RK4 with dt = 0.01 to t = 55, f_inf = f(55): all as in the review.

    granframe run studies/review_test2.py --out runs/test2          # about 20 min on 2 cores
    granframe run studies/review_test2.py --out runs/test2 --quick

The report plots f_inf(v1, 0.17) on a log scale, evaluated exactly from the Fourier series
(v2 = 0.17 is not a grid point). It fits the tail exponent alpha in f ~ exp(-c |v|^alpha)
(theory: 1 for Maxwell molecules, 3/2 for hard spheres) over the trustworthy range of |v|:
- from beyond the thermal core, |v| >= 3 sqrt(T_inf), where the asymptotic form applies;
- to where f_inf is still 100 times the noise floor, and at most S = R/2: beyond it
  collisions are cut and periodic images come near. The floor is the largest |f| at
  negative values of f_inf.
The uncertainty is the spread of alpha over sub-windows, with the fit's standard error.
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
import xarray  # noqa: E402

from granframe.tools.analysis import tail_exponent  # noqa: E402
from granframe.run.description import RunDescription  # noqa: E402
from granframe.run.storage import RunStore  # noqa: E402

W0 = 2 * math.sqrt(6)
KERNELS = {"maxwell": 1.0, "hard_spheres": 1.5}   # kernel: theoretical tail exponent
RESTITUTION = (0.3, 0.5, 0.7)
SLICE = 0.17


def runs(quick: bool = False) -> dict:
    made = {}
    for kernel in KERNELS:
        for e in RESTITUTION:
            n_modes, radial, circle, dt, final = ((64, 16, 8, 0.02, 2.0) if quick
                                                  else (128, 32, 16, 0.01, 55.0))
            made[f"{kernel}_e{e}"] = RunDescription(
                title=f"Test 2: {kernel.replace('_', ' ')}, e = {e}, tau = 0.1, N = {n_modes}"
                      + (" (quick)" if quick else ""),
                grid={"dimension": 2, "n_modes": n_modes, "support_radius": 10.0},
                kernel=kernel, restitution={"name": "constant", "value": e},
                initial={"name": "box", "half_width": W0},
                operator={"name": "fast_spectral", "radial_points": radial,
                          "sphere": {"name": "circle_trapezoid", "n_points": circle}},
                integrator="rk4", heat_bath=0.1, time_step=dt, final_time=final,
                output={"snapshot_interval": 0.4 if quick else 5.0},
                health={"positivity_tolerance": 0.1})   # flat data rings (review_test1.py)
    return made


def slice_at(f, v2, half_width):
    """f(v1_j, v2) for every grid v1_j, from the Fourier series of f (exact for f_N)."""
    n = f.shape[1]
    k = numpy.fft.fftfreq(n, 1.0 / n)
    k[n // 2] = 0.0       # the Nyquist mode is not real-representable: dropped
    points = -half_width + 2 * half_width / n * numpy.arange(n)
    column = numpy.argmin(numpy.abs(points))               # the grid line v2 = 0
    spectrum = numpy.fft.fft(f, axis=1) * numpy.exp(1j * math.pi * k * v2 / half_width)
    return numpy.fft.ifft(spectrum, axis=1)[:, column].real


def _tail(name, store):
    ds = xarray.open_zarr(store)
    f_inf = ds.f.isel(time=-1).values
    grid = RunStore.open(store).metadata["description"]["grid"]
    L, S = grid["half_width"], grid["support_radius"]
    v1 = ds.v1.values
    line = slice_at(f_inf, SLICE, L)
    T_inf = float(ds.temperature.values[-1])
    floor = float(max(-line.min(), -f_inf.min(), 1e-16 * f_inf.max()))
    trusted = line > 100 * floor
    v_min = 3 * math.sqrt(T_inf)
    outer = numpy.abs(v1)[trusted & (numpy.abs(v1) >= v_min) & (numpy.abs(v1) <= S)]
    v_max = float(outer.max()) if outer.size else v_min
    result = {"T_inf": T_inf, "noise_floor": floor, "fit_range": [v_min, v_max],
              "last_snapshot_change": float(numpy.abs(f_inf - ds.f.isel(time=-2).values).max()
                                            / f_inf.max()),
              "wall_seconds": RunStore.open(store).progress.get("wall_seconds")}
    speed, values = numpy.abs(v1), line
    if v_max - v_min < 6 * (v1[1] - v1[0]):
        result["alpha"] = None
        result["why_no_fit"] = "trustworthy range shorter than 6 grid cells"
        return result, (v1, line)
    alpha, stderr = tail_exponent(speed, values, (v_min, v_max))
    # spread over sub-windows: the outer two thirds and the inner two thirds of the range
    third = (v_max - v_min) / 3
    spread = [tail_exponent(speed, values, w)[0] for w in ((v_min + third, v_max),
                                                            (v_min, v_max - third))]
    result.update(alpha=alpha, alpha_stderr=stderr, alpha_subwindows=spread,
                  alpha_uncertainty=float(max(stderr, *(abs(a - alpha) for a in spread))),
                  theory=KERNELS[name.split("_e")[0]])
    return result, (v1, line)


def report(stores: dict, out) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = {}
    fig, axes = plt.subplots(1, 2, figsize=(14, 6), constrained_layout=True)
    names = {"maxwell": "Maxwell molecules (kernel exponent λ = 0)",
             "hard_spheres": "hard spheres (kernel exponent λ = 1)"}
    for column, kernel in enumerate(KERNELS):
        ax = axes[column]
        for e in RESTITUTION:
            name = f"{kernel}_e{e}"
            summary[name], (v1, line) = _tail(name, stores[name])
            s = summary[name]
            shown = numpy.where(line > 0, line, numpy.nan)
            label = f"e = {e}"
            if s.get("alpha") is not None:
                label += f": fitted α = {s['alpha']:.2f} ± {s['alpha_uncertainty']:.2f}"
            else:
                label += f": no fit ({s.get('why_no_fit', 'none')})"
            ax.semilogy(v1, shown, "o-", ms=2, lw=0.8, label=label)
            if e == RESTITUTION[0]:
                for sign in (1, -1):
                    ax.axvspan(*(sign * x for x in s["fit_range"]), color="0.9", zorder=0,
                               label=f"fit range of e = {e} (each e has its own, see "
                                     "summary.json)" if sign == 1 else None)
            numpy.savetxt(out / f"test2_{name}_slice.csv", numpy.c_[v1, line], delimiter=",",
                          header=f"v1,f_inf(v1;v2={SLICE})", comments="")
        final = xarray.open_zarr(stores[f"{kernel}_e{RESTITUTION[0]}"]).step_time.values[-1]
        ax.set(xlabel="velocity v1 (dimensionless)",
               ylabel=rf"$f_\infty(v_1, {SLICE})$ (dimensionless)",
               title=f"{names[kernel]}: f_inf = f(t = {final:g})\ntail exp(-c|v|^α), theory "
                     f"α = {KERNELS[kernel]:g}; a marker at each grid v1; f ≤ 0 left out")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    first = RunStore.open(stores[next(iter(stores))]).metadata["description"]
    grid, operator = first["grid"], first["operator"]
    fig.suptitle(f"Test 2: tails of the heated equilibrium, 2D, constant e, heat bath τ = "
                 f"{first['heat_bath']:g}, flat initial data (w0 = 2√6)\nN = {grid['n_modes']}, "
                 f"S = {grid['support_radius']:g}, fast_spectral, N_ρ = "
                 f"{operator['radial_points']}, circle M = {operator['sphere']['n_points']}; "
                 f"{first.get('integrator', {}).get('name', 'rk4')}, Δt = "
                 f"{first['time_step']:g}; slice at v2 = {SLICE} (from the Fourier series); "
                 "all quantities dimensionless", fontsize=10)
    fig.savefig(out / "test2_tails.png", dpi=100)
    plt.close(fig)
    return summary
