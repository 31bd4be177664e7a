"""Aliasing: the error of the fast operator against the box size L/S and the truncation R/S.

    python studies/aliasing.py --out docs/figures/aliasing        # about a minute, 2 cores

Elastic 2D Maxwell molecules, the BKW solution at t = 6.5 (exact df/dt), whose profile is
below 1e-5 of its peak beyond S = 5. The spacing is fixed at h = 0.35 (N = 2L/h rounded to
an even number) so that only the periodic images move: L/S from 1 to 3 and R/S from 1 to
2.5, with the quadratures resolved (N_rho = 40, M = 32). [FPT05] proves the spectral
method free of aliasing for L >= (3 + sqrt 2) S / 2 ~ 2.21 S with R = 2S: the convolution
of two functions supported in B_S, with relative velocities cut at R, then does not wrap
around the periodic box onto B_S. granframe's grid refuses smaller L or R unless
``allow_aliasing=True``, and then warns (:class:`granframe.AliasingWarning`).
"""

from __future__ import annotations

import pathlib
import warnings

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402

import granframe as gf  # noqa: E402
from granframe.backends import preferred_backend  # noqa: E402
from granframe.model.exact import bkw  # noqa: E402
from granframe.velocity.grid import ANTI_ALIASING_FACTOR  # noqa: E402
from granframe.tools.studykit import command, finish, save_figure, write_csv, write_summary  # noqa: E402

SUPPORT = 5.0
SPACING = 0.35


def error(box_ratio: float, truncation_ratio: float) -> dict:
    """max |Q(f) - df/dt| / max |df/dt| on the grid with L = box_ratio S, R = truncation_ratio S."""
    n_modes = 2 * max(2, round(box_ratio * SUPPORT / SPACING))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gf.AliasingWarning)
        grid = gf.VelocityGrid(2, n_modes, SUPPORT, half_width=box_ratio * SUPPORT,
                               truncation_radius=truncation_ratio * SUPPORT,
                               allow_aliasing=True)
    f, dfdt = bkw(grid, 6.5)
    operator = gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel("maxwell"),
        gf.restitution_law("constant", value=1.0), backend=gf.array_backend(preferred_backend()),
        radial_points=40, sphere=gf.CircleTrapezoid(32))
    q = operator(f)
    return {"L_over_S": box_ratio, "R_over_S": truncation_ratio, "N": n_modes,
            "error": float(numpy.abs(q - dfdt).max() / numpy.abs(dfdt).max())}


def run(out: pathlib.Path, quick: bool = False) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    boxes = (1.5, 2.21) if quick else (1.0, 1.25, 1.5, 1.75, 2.0, 2.21, 2.5, 3.0)
    truncations = (2.0,) if quick else (1.0, 1.5, 2.0, 2.5)
    rows = [error(b, r) for r in truncations for b in boxes]
    write_csv(out / "aliasing.csv", rows)
    fig, ax = plt.subplots(figsize=(7.5, 5.5), constrained_layout=True)
    for r in truncations:
        chosen = [row for row in rows if row["R_over_S"] == r]
        ax.semilogy([row["L_over_S"] for row in chosen], [row["error"] for row in chosen],
                    "o-", label=f"truncation radius R = {r:g} S")
    ax.axvline(ANTI_ALIASING_FACTOR, color="k", ls="--", lw=1,
               label=r"L = $(3 + \sqrt{2})\,S/2$ (the grid's default; free of aliasing "
                     "for R = 2S)")
    sizes = sorted({row["N"] for row in rows})
    ax.set(xlabel="box half-width over support, L / S (dimensionless)",
           ylabel=r"relative error of Q, $\max|Q - \partial_t f|\,/\,\max|\partial_t f|$"
                  " (dimensionless)",
           title=f"aliasing: 2D elastic Maxwell molecules (e = 1, kernel exponent λ = 0),\n"
                 f"BKW solution at t = 6.5 (exact ∂f/∂t); fast_spectral, N_ρ = 40, M = 32;\n"
                 f"S = {SUPPORT:g}, spacing h = {SPACING:g}, N = 2L/h from {sizes[0]} to "
                 f"{sizes[-1]}; one marker per grid")
    ax.title.set_fontsize(9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, out / "aliasing.png")
    summary = {"rows": rows}
    write_summary(out, summary)
    return summary


def _show(summary):
    for row in summary["rows"]:
        print(f"L/S = {row['L_over_S']:<5g} R/S = {row['R_over_S']:<4g} N = {row['N']:<4d} "
              f"error {row['error']:.2e}")


main = command(run, __doc__, "two points (smoke test)", show=_show)


if __name__ == "__main__":
    raise SystemExit(finish(main))
