"""Free cooling: concentration on a fixed grid, the rescaled formulation, the cooling state.

    python studies/free_cooling.py --out docs/figures/cooling   # ~4 min, 2 cores

Without a heat bath the gas cools for ever (Haff's law T ~ t^-2 for hard spheres) and f
concentrates at its mean velocity. Three parts (``--only``):

- ``concentration``: 2D hard spheres, e = 0.5, T0 = 1, S = 4, N = 32 and 64 (h = 0.55, 0.28),
  RK4. The unscaled equation (dt = 0.05) is run to t = 100 next to the rescaled one
  (:mod:`granframe.equations.rescaled`, ds = 0.1) to the same t. Reference: the rescaled N = 64 run,
  checked against the unscaled N = 64 run while both are resolved. Reported: when the unscaled
  temperature leaves the reference by 1e-3 and when its negative-mass share passes the
  runner's 1 % limit, with T/T0 and the thermal speed sqrt(T) in grid spacings there.
- ``hcs``: the homogeneous cooling state of hard spheres: rescaled runs to s = 15 for e = 0.2
  ... 0.9 in 3D (N = 32, S = 3.5, N_rho = 16, Lebedev degree 11) and 2D (N = 64, N_rho = 32,
  M = 32). Its kurtosis and Sonine coefficient a2, against the first Sonine approximation of
  van Noije & Ernst (Granular Matter 1, 1998) for 3D hard spheres,
  a2 = 16 (1-e)(1-2e^2) / (9 + 24d - e(41 - 8d) + 30 e^2 (1-e)).
  (The 2D kernel with isotropic b is not the hard-disk one, so it has no such reference.)
- ``maxwell``: 2D Maxwell molecules, e = 0.5, N = 64, S = 3.5, 5, 7, rescaled to s = 40:
  the exact law T = T0 exp(-(1-e^2) t/4) and the kurtosis. Their cooling state has
  power-law tails, which a bounded box truncates; the error and the kurtosis depend on S.
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402

import granframe as gf  # noqa: E402
from granframe.backends import preferred_backend  # noqa: E402
from granframe.equations.homogeneous import HomogeneousBoltzmann  # noqa: E402
from granframe.equations.rescaled import RescaledBoltzmann  # noqa: E402
from granframe.errors import NonFiniteError  # noqa: E402
from granframe.run.runner import moments  # noqa: E402
from granframe.tools.studykit import (command, read_summary, save_figure, write_csv,  # noqa: E402
                                write_summary)

PARTS = ("concentration", "hcs", "maxwell")
E_CONCENTRATION, FINAL_T = 0.5, 100.0


def sonine_a2(e: float, d: int) -> float:
    """First Sonine approximation of the HCS of hard spheres (van Noije & Ernst 1998)."""
    return 16 * (1 - e) * (1 - 2 * e * e) / (9 + 24 * d - e * (41 - 8 * d) + 30 * e * e * (1 - e))


def _operator(kernel, d, n_modes, support, e):
    grid = gf.VelocityGrid(d, n_modes, support)
    sphere = gf.CircleTrapezoid(32) if d == 2 else gf.Lebedev(11)
    return gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel(kernel),
        gf.restitution_law("constant", value=e), backend=gf.array_backend(preferred_backend()),
        radial_points=n_modes // 2 if d == 2 else 16, sphere=sphere)


def _march(equation, f, dt, steps, every=1):
    """RK4 steps; the runner's moments after every ``every`` steps (until f is not finite)."""
    grid, rk4 = equation.operator.grid, gf.time_integrator("rk4")
    rows = [dict(moments(grid, f, numpy), step=0)]
    for i in range(1, steps + 1):
        with numpy.errstate(over="ignore", invalid="ignore"):   # the unscaled runs blow up
            try:
                f = rk4.step(equation, (i - 1) * dt, f, dt)
            except NonFiniteError:   # a stage overflowed: the operator refuses that stage
                rows.append(dict(moments(grid, numpy.full_like(f, numpy.nan), numpy), step=i))
                break
        if i % every == 0 or i == steps:
            state = moments(grid, f, numpy)
            rows.append(dict(state, step=i))
            if not numpy.isfinite(state["kinetic_energy"]):
                break
    return f, rows


def rescaled_run(kernel, d, n_modes, support, e, ds, final_s=None, final_t=None, every=1):
    """A rescaled run from the Maxwellian T0 = 1 to s = ``final_s`` or to the s of the
    physical time ``final_t``; rows carry s, t, T_g and the physical T."""
    operator = _operator(kernel, d, n_modes, support, e)
    f0 = operator.grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    law = equation.rescaling
    if final_s is None:
        final_s = float(law.rescaled_time(final_t))
    g, rows = _march(equation, f0, ds, int(numpy.ceil(final_s / ds - 1e-9)), every)
    for row in rows:
        s = row["step"] * ds
        row.update(s=s, t=float(law.physical_time(s)), rescaled_temperature=row["temperature"],
                   temperature=float(law.temperature(s, row["temperature"])))
    return operator.grid, g, law, rows


def concentration(quick: bool) -> dict:
    sizes = (32,) if quick else (32, 64)
    final_t = 10.0 if quick else FINAL_T
    runs, rows = {}, []
    for n in sizes:
        grid, _, law, rescaled = rescaled_run("hard_spheres", 2, n, 4.0, E_CONCENTRATION, 0.1,
                                              final_t=final_t)
        operator = _operator("hard_spheres", 2, n, 4.0, E_CONCENTRATION)
        dt = 0.05
        _, direct = _march(HomogeneousBoltzmann(operator), grid.maxwellian(temperature=1.0), dt,
                           round(final_t / dt))
        for row in direct:
            row["t"] = row["step"] * dt
        runs[n] = {"grid": grid, "rescaled": rescaled, "direct": direct, "law": law}
    finest = runs[sizes[-1]]
    spline = CubicSpline([r["s"] for r in finest["rescaled"]],
                         numpy.log([r["rescaled_temperature"] for r in finest["rescaled"]]))

    def exact(t):   # T(t) = T_g(s(t)) / omega(s(t))^2, T_g (nearly constant) interpolated in s
        s = finest["law"].rescaled_time(t)
        return finest["law"].temperature(s, numpy.exp(spline(s)))

    for n, run in runs.items():
        h = run["grid"].spacing
        for kind in ("direct", "rescaled"):
            series = run[kind]
            t = numpy.array([r["t"] for r in series])
            T = numpy.array([r["temperature"] for r in series])
            negative = numpy.array([r["negative_mass_fraction"] for r in series])
            error = numpy.abs(T / exact(t) - 1)
            run[kind + "_error"] = error
            bad_T = numpy.flatnonzero(~(error <= 1e-3))
            bad_share = numpy.flatnonzero(~(negative <= 1e-2))
            row = {"N": n, "h": h, "formulation": kind, "final_t": float(t[-1]),
                   "final_T": float(T[-1]), "final_negative_share": float(negative[-1])}
            for label, bad in (("T_error_1e-3", bad_T), ("negative_share_1e-2", bad_share)):
                i = int(bad[0]) if bad.size else None
                row[f"t_{label}"] = None if i is None else float(t[i])
                row[f"T_over_T0_{label}"] = None if i is None else float(T[i])
                row[f"thermal_speed_over_h_{label}"] = (None if i is None
                                                         else float(numpy.sqrt(T[i]) / h))
            early = t <= 1.0
            row["max_error_t_le_1"] = float(error[early].max())
            rows.append(row)
    return {"rows": rows, "runs": runs, "exact": exact, "final_t": final_t}


def hcs(quick: bool) -> dict:
    restitutions = (0.5,) if quick else (0.2, 0.4, 0.5, 0.6, 0.8, 0.9)
    cases = [(2, 32)] if quick else [(3, 32), (2, 64)]
    rows, histories = [], {}
    final_s = 3.0 if quick else 15.0
    for d, n in cases:
        for e in restitutions:
            grid, g, law, series = rescaled_run("hard_spheres", d, n, 3.5, e, 0.1, final_s)
            last = series[-1]
            tail = [r["kurtosis"] for r in series if r["s"] >= final_s - 2.0]
            histories[(d, e)] = series
            rows.append({"d": d, "N": n, "e": e, "a0": law.rate,
                         "kurtosis": last["kurtosis"], "a2": last["sonine_a2"],
                         "a2_sonine": sonine_a2(e, d) if d == 3 else None,
                         "kurtosis_change_last_2": max(tail) - min(tail),
                         "rescaled_temperature": last["rescaled_temperature"],
                         "negative_share": last["negative_mass_fraction"],
                         "mass_error": abs(last["mass"] / series[0]["mass"] - 1)})
    return {"rows": rows, "histories": histories}


def maxwell(quick: bool) -> dict:
    supports = (3.5,) if quick else (3.5, 5.0, 7.0)
    final_s = 5.0 if quick else 40.0
    rows, histories = [], {}
    e = 0.5
    for support in supports:
        grid, g, law, series = rescaled_run("maxwell", 2, 64, support, e, 0.1, final_s, every=10)
        T0 = series[0]["temperature"]
        for r in series:
            r["T_error"] = abs(r["temperature"] / (T0 * numpy.exp(-(1 - e * e) * r["t"] / 4)) - 1)
        histories[support] = series
        rows.append({"S": support, "h": grid.spacing, "final_t": series[-1]["t"],
                     "T_over_T0": series[-1]["temperature"] / T0,
                     "max_T_error": max(r["T_error"] for r in series),
                     "kurtosis": series[-1]["kurtosis"], "a0": law.rate})
    return {"rows": rows, "histories": histories}


_TIME = "time t (dimensionless)"


def _numerics(d, n_modes) -> str:
    """N, N_rho and the sphere rule of :func:`_operator` for a ``d``-dimensional grid."""
    rule = "circle M = 32" if d == 2 else "Lebedev 11"
    return f"N = {n_modes}, N_ρ = {n_modes // 2 if d == 2 else 16}, {rule}"


def _positive(values):
    """``values`` with zeros and negative entries left out (for a logarithmic axis)."""
    values = numpy.asarray(values, dtype=float)
    return numpy.where(values > 0, values, numpy.nan)


def _figure_concentration(result, out):
    fig, axes = plt.subplots(1, 3, figsize=(16, 5), constrained_layout=True)
    styles = {"direct": "-", "rescaled": "--"}
    reference = max(result["runs"])
    for n, run in result["runs"].items():
        for kind in ("direct", "rescaled"):
            series = run[kind]
            t = numpy.array([r["t"] for r in series])
            label = f"{'unscaled' if kind == 'direct' else 'rescaled'}, N = {n}"
            keep = t > 0
            axes[0].loglog(t[keep], _positive([r["temperature"] for r, k in zip(series, keep)
                                               if k]), styles[kind], label=label)
            error_label = label + (" (the reference itself: round-off)"
                                   if kind == "rescaled" and n == reference else "")
            axes[1].loglog(t[keep], _positive(run[kind + "_error"][keep]), styles[kind],
                           label=error_label)
            axes[2].loglog(t[keep], _positive([r["negative_mass_fraction"]
                                               for r, k in zip(series, keep) if k]),
                           styles[kind], label=label)
    axes[1].axhline(1e-3, color="k", ls=":", lw=1, label="1e-3 (the report's threshold)")
    axes[2].axhline(1e-2, color="k", ls=":", lw=1, label="runner's positivity limit (1 %)")
    axes[0].set(xlabel=_TIME, ylabel="temperature T (dimensionless)",
                title="temperature (T ≤ 0 and non-finite values left out)", ylim=(1e-4, 2.0))
    axes[1].set(xlabel=_TIME, ylabel=r"temperature error $|T/T_{ref} - 1|$ (dimensionless)",
                ylim=(1e-17, 10.0),
                title=f"error against the reference (rescaled, N = {reference}; zeros left out)")
    axes[2].set(xlabel=_TIME,
                ylabel=r"negative mass share $\int f^- / \int |f|$ (dimensionless)",
                title="positivity (zeros left out)", ylim=(1e-18, 1.0))
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    sizes = ", ".join(str(n) for n in result["runs"])
    fig.suptitle(f"free cooling of 2D hard spheres (kernel exponent λ = 1), constant e = "
                 f"{E_CONCENTRATION}, Maxwellian T0 = 1, S = 4, N = {sizes}, N_ρ = N/2, circle "
                 f"M = 32\nRK4: unscaled Δt = 0.05, rescaled Δs = 0.1, to t = "
                 f"{result['final_t']:g}; all quantities dimensionless", fontsize=10)
    save_figure(fig, out / "concentration.png")


def _figure_hcs(result, out):
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), constrained_layout=True)
    shown = 3 if any(d == 3 for d, _ in result["histories"]) else 2   # 2D in the quick variant
    for (d, e), series in result["histories"].items():
        if d == shown:
            axes[0].plot([r["s"] for r in series], [r["kurtosis"] for r in series],
                         label=f"e = {e}")
    axes[0].axhline((shown + 2) / shown, color="k", ls=":", lw=1,
                    label=f"Maxwellian, (d + 2)/d = {(shown + 2) / shown:.4g}")
    axes[0].set(xlabel="rescaled time s (dimensionless)",
                ylabel=r"kurtosis $\kappa$ (dimensionless)",
                title=f"{shown}D hard spheres, rescaled: kurtosis against s")
    for d, marker in ((3, "o"), (2, "s")):
        chosen = [r for r in result["rows"] if r["d"] == d]
        if chosen:
            axes[1].plot([r["e"] for r in chosen], [r["a2"] for r in chosen], marker,
                         label=f"granframe, {d}D ({_numerics(d, chosen[0]['N'])}), one run "
                               "per e")
    grid_e = numpy.linspace(0.0, 1.0, 101)
    axes[1].plot(grid_e, [sonine_a2(e, 3) for e in grid_e], "k-", lw=1,
                 label="first Sonine approximation, 3D hard spheres\n(van Noije & Ernst "
                       "1998; none for the 2D kernel)")
    axes[1].set(xlabel="restitution coefficient e (dimensionless)",
                ylabel=r"Sonine coefficient $a_2$ of the cooling state (dimensionless)",
                title="homogeneous cooling state: a2 at the last step")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    cases = sorted({(r["d"], r["N"]) for r in result["rows"]}, reverse=True)
    final_s = max(r["s"] for series in result["histories"].values() for r in series)
    fig.suptitle("homogeneous cooling state of hard spheres (kernel exponent λ = 1), constant "
                 "e, no heat bath, rescaled formulation, Maxwellian T0 = 1, S = 3.5\n"
                 + "; ".join(f"{d}D: {_numerics(d, n)}" for d, n in cases)
                 + f"; RK4, Δs = 0.1, to s = {final_s:g}; all quantities dimensionless",
                 fontsize=10)
    save_figure(fig, out / "hcs.png")


def _figure_maxwell(result, out):
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    for support, series in result["histories"].items():
        ax.semilogy([r["t"] for r in series], _positive([r["T_error"] for r in series]),
                    "o-", ms=2.5, lw=1, label=f"support S = {support}")
    final_s = max(r["s"] for series in result["histories"].values() for r in series)
    ax.set(xlabel=_TIME, ylabel=r"temperature error $|T/T_{exact} - 1|$ (dimensionless)",
           title="free cooling of 2D Maxwell molecules (kernel exponent λ = 0), e = 0.5, "
                 "Maxwellian T0 = 1\nrescaled, N = 64, N_ρ = 32, circle M = 32, RK4, "
                 f"Δs = 0.1 to s = {final_s:g}; exact law T0 exp(-(1 - e²) t/4)\n"
                 "a marker every 10 steps; zeros (t = 0) left out; all quantities "
                 "dimensionless")
    ax.title.set_fontsize(9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    save_figure(fig, out / "maxwell_tails.png")


def run(out: pathlib.Path, quick: bool = False, only=None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = read_summary(out, only)
    parts = {"concentration": (concentration, _figure_concentration),
             "hcs": (hcs, _figure_hcs), "maxwell": (maxwell, _figure_maxwell)}
    for name in PARTS if only is None else [p for p in PARTS if p in only]:
        measure, draw = parts[name]
        result = measure(quick)
        write_csv(out / f"{name}.csv", result["rows"])
        draw(result, out)
        summary[name] = result["rows"]
    write_summary(out, summary)
    return summary


def _show(summary):
    for name, rows in summary.items():
        print(name)
        for row in rows:
            print("  " + ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                                   for k, v in row.items()))


main = command(run, __doc__, "short runs at small N (smoke test)", parts="part", show=_show)


if __name__ == "__main__":
    raise SystemExit(main())
