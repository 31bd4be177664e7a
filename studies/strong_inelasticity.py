"""Positivity of the heated steady state as e -> 0 (sticky collisions), against N.

    python studies/strong_inelasticity.py --out docs/figures/inelasticity   # ~10 min, 2 cores

d_t f = Q(f, f) + 0.1 Delta f in 2D, Maxwell molecules and hard spheres, constant e from 0
(sticky) to 0.95, from a Maxwellian T0 = 1 to t = 10 (RK4, dt = 0.02) on S = 6 with
N = 32, 64, 128 (h = 0.83, 0.41, 0.21), N_rho = 32, M = 16. Stronger inelasticity cools the
gas (T_inf = 8 tau / (1 - e^2) = 0.8 at e = 0 for Maxwell molecules) and fattens the tails,
which a truncated Fourier series resolves less well: f dips below zero in the far field.
Reported at t = 10: the negative-mass share int max(-f, 0) / int |f| (what the runner's
positivity check watches, default limit 1 %), min f / max f, the kurtosis and, for Maxwell
molecules, the temperature against the exact law.
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402

import granframe as gf  # noqa: E402
from granframe.backends import preferred_backend  # noqa: E402
from granframe.equations.homogeneous import HomogeneousBoltzmann  # noqa: E402
from granframe.model.exact import heated_maxwell_temperature  # noqa: E402
from granframe.run.runner import moments  # noqa: E402
from granframe.tools.studykit import command, finish, save_figure, write_csv, write_summary  # noqa: E402

TAU, FINAL, DT = 0.1, 10.0, 0.02


def steady_state(kernel: str, restitution: float, n_modes: int, final=FINAL) -> dict:
    grid = gf.VelocityGrid(2, n_modes, 6.0)
    operator = gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel(kernel),
        gf.restitution_law("constant", value=restitution),
        backend=gf.array_backend(preferred_backend()), radial_points=32,
        sphere=gf.CircleTrapezoid(16))
    equation = HomogeneousBoltzmann(operator, TAU)
    rk4 = gf.time_integrator("rk4")
    f = grid.maxwellian(temperature=1.0)
    steps = round(final / DT)
    for i in range(steps):
        f = rk4.step(equation, i * DT, f, DT)
    state = moments(grid, f, numpy)      # the runner's moments, positivity check included
    row = {"kernel": kernel, "e": restitution, "N": n_modes, "h": grid.spacing,
           "negative_share": state["negative_mass_fraction"],
           "min_over_max": state["min_f"] / float(f.max()),
           "temperature": state["temperature"], "kurtosis": state["kurtosis"], "T_error": None}
    if kernel == "maxwell":
        exact = heated_maxwell_temperature(final, 1.0, restitution, TAU, state["mass"])
        row["T_error"] = abs(row["temperature"] / exact - 1)
    return row


def run(out: pathlib.Path, quick: bool = False) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    kernels = ("maxwell",) if quick else ("maxwell", "hard_spheres")
    restitutions = (0.0, 0.9) if quick else (0.0, 0.2, 0.4, 0.6, 0.8, 0.95)
    sizes = (32,) if quick else (32, 64, 128)
    final = 1.0 if quick else FINAL
    rows = [steady_state(k, e, n, final) for k in kernels for n in sizes for e in restitutions]
    write_csv(out / "inelasticity.csv", rows)
    fig, axes = plt.subplots(1, len(kernels), figsize=(7 * len(kernels), 5.2),
                             constrained_layout=True, squeeze=False)
    names = {"maxwell": "Maxwell molecules (kernel exponent λ = 0)",
             "hard_spheres": "hard spheres (kernel exponent λ = 1)"}
    floor = 1e-17
    for ax, kernel in zip(axes[0], kernels):
        zeros = False
        for colour, n in enumerate(sizes):
            chosen = [r for r in rows if r["kernel"] == kernel and r["N"] == n]
            share = numpy.array([r["negative_share"] for r in chosen])
            e = numpy.array([r["e"] for r in chosen])
            ax.semilogy(e, numpy.where(share > 0, share, numpy.nan), "o-", color=f"C{colour}",
                        label=f"N = {n} (h = {chosen[0]['h']:.2f})")
            if (share <= 0).any():
                zeros = True
                ax.semilogy(e[share <= 0], numpy.full((share <= 0).sum(), floor), "v",
                            mfc="none", ms=7, color=f"C{colour}")
        if zeros:
            ax.semilogy([], [], "v", mfc="none", ms=7, color="0.4",
                        label=f"share exactly 0 (f ≥ 0 on the grid), drawn at {floor:g}")
        ax.axhline(1e-2, color="k", ls=":", lw=1, label="runner's default limit (1 %)")
        ax.set(xlabel="restitution coefficient e (dimensionless)",
               ylabel=rf"negative mass share $\int f^- / \int |f|$ at t = {final:g} "
                      "(dimensionless)",
               title=f"{names[kernel]}: one run per (e, N)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"heated state, 2D: heat bath τ = {TAU}, constant e, Maxwellian T0 = 1, "
                 f"S = 6;\nfast_spectral, N_ρ = 32, circle M = 16; RK4, Δt = {DT}, to "
                 f"t = {final:g}; all quantities dimensionless", fontsize=10)
    save_figure(fig, out / "inelasticity.png")
    summary = {"rows": rows}
    write_summary(out, summary)
    return summary


def _show(summary):
    for r in summary["rows"]:
        error = "-" if r["T_error"] is None else f"{r['T_error']:.1e}"
        print(f"{r['kernel']:<12} e = {r['e']:<4g} N = {r['N']:<3d} negative share "
              f"{r['negative_share']:.1e}  min/max {r['min_over_max']:.1e}  "
              f"T {r['temperature']:.4f}  kurtosis {r['kurtosis']:.3f}  T error {error}")


main = command(run, __doc__, "two runs to t = 1 (smoke test)", show=_show)


if __name__ == "__main__":
    raise SystemExit(finish(main))
