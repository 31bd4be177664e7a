"""Default quadratures of the fast operator: the error of Q against the rules, per grid.

    python studies/default_quadrature.py --out docs/figures/default_quadrature   # ~40 min, 2 cores
    python studies/default_quadrature.py --out DIR --only 3d        # one part: 2d, 3d, defaults
    python studies/default_quadrature.py --out /tmp/dq --quick                   # seconds

The parts ``2d`` and ``3d`` measure everything for their grids; ``defaults`` measures again
only the rows of the presets and of the refinement (after a change of
:func:`granframe_spectral.fast.default_quadratures`), keeping the sweeps.

For each grid (2D N = 16 ... 128, 3D N = 12 ... 32, S = 5, the default L and R) the study
measures how far the fast operator's Q is from a reference with far more quadrature points,
on the same grid and the same data:

- sphere rules (circle M, or Lebedev order) at the reference radial rule;
- radial rules N_rho at the reference sphere rule;
- the rule ``quadrature = "auto"`` chooses for the grid (the default), and the review's;
- the reference against a finer one (the ``refinement`` rows): what is left of the
  reference's own error.

Errors are max |Q - Q_ref| / max |Q_ref| and |D - D_ref| / |D_ref| for the energy-dissipation
rate D = int Q |v|^2, the worst over three data sets: a non-Maxwellian two-Gaussian mixture,
an anisotropic Gaussian (temperatures in the ratio 1.25 : 0.75 in 2D, 1.3 : 1 : 0.7 in 3D)
and two beams, Gaussians centred at +-S/2 along an oblique direction (relative velocity S:
the data that ask most of the sphere rule, whose angular width sqrt(T)/S shrinks as the grid
resolves colder beams), Maxwell molecules with e = 0.5. The data are scaled to the coldest
temperature that the grid resolves to TAIL_ERROR_FACTOR x spectral tail <= 1e-7 (the data N
is meant for: colder data have an N error above that; warmer data need fewer quadrature
points), or, on grids too coarse for that, to the temperature N resolves best; the
``resolution`` column gives that estimate of N's own error
(:mod:`granframe.velocity.estimators`). A rule is converged when its error is below
:func:`target`: 1e-7, or a tenth of N's error where that is larger. The printed table is the
one of docs/accuracy-vs-cost.md, "Default quadratures".
"""

from __future__ import annotations

import math
import pathlib
import time

import numpy

import granframe as gf
from granframe.backends import preferred_backend
from granframe.tools.studykit import command, finish, read_summary, write_csv, write_summary
from granframe.velocity.estimators import TAIL_ERROR_FACTOR, spectral_tail
from granframe.velocity.quadratures import CircleTrapezoid, Lebedev

SUPPORT = 5.0
#: the resolution the data are scaled to (TAIL_ERROR_FACTOR x spectral tail)
LEVEL = 1e-7
#: grids measured, and the largest N swept (2D N = 128: only the presets; its sweeps would take
#: longer than all the others)
SIZES = {2: (16, 24, 32, 48, 64, 96, 128), 3: (12, 16, 24, 32)}
SWEPT = {2: 96, 3: 32}
QUICK_SIZES = {2: (16,), 3: ()}
SPHERES = {2: (8, 12, 16, 20, 24, 32, 40, 48, 64, 80, 96, 128),
           3: (11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31, 35)}
RADIAL = (8, 12, 16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96, 112, 128)
#: a sweep stops at a rule this close to the reference (round-off, or the reference's error)
CONVERGED = 1e-11


def reference(d: int, n: int) -> tuple:
    """(N_rho, sphere size) of the reference and of its refinement."""
    if d == 2:
        return (max(64, 2 * n), max(64, 2 * n)), (max(80, 2 * n + 32), max(96, 3 * n))
    return (n + 32, 41), (n + 48, 47)


def rule(d: int, size: int):
    return CircleTrapezoid(size) if d == 2 else Lebedev(size)


def data(grid, scale: float):
    """The three data sets at temperature scale ``scale``, stacked: a two-Gaussian mixture
    (densities 0.6 and 0.4, temperatures 0.7 and 1.1 times scale), an anisotropic
    Gaussian (temperatures (1.25, 0.75) or (1.3, 1, 0.7) times 0.8 scale) and two beams
    (densities 0.5, temperature 0.7 scale, centred at +-S/2 along (1, 0.4, 0.2)/|.|)."""
    d, root = grid.dimension, math.sqrt(scale)
    first, second = (0.8, 0.2, 0.0)[:d], (-1.2, -0.3, 0.4)[:d]
    mixture = (grid.maxwellian(0.6, [root * u for u in first], 0.7 * scale)
               + grid.maxwellian(0.4, [root * u for u in second], 1.1 * scale))
    factors = (1.25, 0.75) if d == 2 else (1.3, 1.0, 0.7)
    anisotropic = 1.0
    for c, u, factor in zip(grid.mesh(), (0.3, -0.2, 0.1), factors):
        t = 0.8 * factor * scale
        anisotropic = anisotropic * numpy.exp(-(c - root * u) ** 2 / (2 * t)) / math.sqrt(
            2 * math.pi * t)
    direction = numpy.array((1.0, 0.4, 0.2)[:d])
    centre = 0.5 * SUPPORT * direction / numpy.linalg.norm(direction)
    beams = (grid.maxwellian(0.5, list(centre), 0.7 * scale)
             + grid.maxwellian(0.5, list(-centre), 0.7 * scale))
    return numpy.stack([mixture, anisotropic, beams])


def resolved_scale(grid) -> tuple[float, float]:
    """(scale, resolution): the coldest scale whose data have TAIL_ERROR_FACTOR x spectral
    tail <= LEVEL, or the best-resolved scale; and that estimate of N's error."""
    scales = numpy.geomspace(0.01, 20.0, 80)
    tails = [TAIL_ERROR_FACTOR * max(spectral_tail(grid, f) for f in data(grid, s))
             for s in scales]
    good = [i for i, t in enumerate(tails) if t <= LEVEL]
    i = good[0] if good else int(numpy.argmin(tails))
    return float(scales[i]), float(tails[i])


def measure(d: int, n: int, quick: bool = False, sweeps: bool = True) -> list[dict]:
    """Rows of the table for grid (d, N): every rule's errors against the reference (without
    ``sweeps``: only the refinement and the presets)."""
    grid = gf.VelocityGrid(d, n, SUPPORT)
    kernel, law = gf.collision_kernel("maxwell"), gf.restitution_law("constant", value=0.5)
    backend = gf.array_backend(preferred_backend())
    scale, resolution = resolved_scale(grid)
    f = data(grid, scale)
    weight = grid.speed_squared() * grid.cell_volume

    def evaluate(**options):
        start = time.perf_counter()
        operator = gf.collision_operator("fast_spectral", grid, kernel, law, backend=backend,
                                         **options)
        q = operator(f)
        return q, operator, time.perf_counter() - start

    (radial_ref, sphere_ref), (radial_fine, sphere_fine) = reference(d, n)
    q_ref, _, _ = evaluate(radial_points=radial_ref, sphere=rule(d, sphere_ref))
    scale_q = [numpy.abs(q).max() for q in q_ref]
    rate_ref = [(q * weight).sum() for q in q_ref]
    rows = []

    def row(kind, operator, q, seconds):
        error = max(numpy.abs(q[i] - q_ref[i]).max() / scale_q[i] for i in range(len(f)))
        rate = max(abs((q[i] * weight).sum() / rate_ref[i] - 1) for i in range(len(f)))
        sphere = operator.sphere
        rows.append({"d": d, "N": n, "kind": kind, "N_rho": operator.radial_points,
                     "sphere": (sphere.n_points if d == 2 else
                                getattr(sphere, "order", None) or f"product{sphere.n_polar}"),
                     "pairs": operator.transform_pairs, "scale": scale,
                     "resolution": resolution, "error_Q": float(error),
                     "error_D": float(rate), "seconds": seconds})

    q, operator, seconds = evaluate(radial_points=radial_fine, sphere=rule(d, sphere_fine))
    row("refinement", operator, q, seconds)
    for kind in ("auto", "review"):
        q, operator, seconds = evaluate(quadrature=kind)
        row(kind, operator, q, seconds)
    spheres = [s for s in SPHERES[d] if s < sphere_ref] if sweeps else []
    radial = [r for r in RADIAL if r < radial_ref] if sweeps else []
    if quick:
        spheres, radial = spheres[:2], radial[:2]
    for size in spheres:
        q, operator, seconds = evaluate(radial_points=radial_ref, sphere=rule(d, size))
        row("sphere", operator, q, seconds)
        if rows[-1]["error_Q"] <= CONVERGED:
            break
    for points in radial:
        q, operator, seconds = evaluate(radial_points=points, sphere=rule(d, sphere_ref))
        row("radial", operator, q, seconds)
        if rows[-1]["error_Q"] <= CONVERGED:
            break
    return rows


PARTS = ("2d", "3d", "defaults")
PRESETS = ("refinement", "auto", "review")


def run(out: pathlib.Path, quick: bool = False, only=None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    unknown = set(only or ()) - set(PARTS)
    if unknown:
        raise SystemExit(f"default_quadrature: unknown parts {sorted(unknown)}; "
                         f"choose from {', '.join(PARTS)}")
    rows = read_summary(out, only).get("rows", [])
    sizes = QUICK_SIZES if quick else SIZES
    for d in (2, 3):
        if only and f"{d}d" not in only and "defaults" not in only:
            continue
        sweeps = not only or f"{d}d" in only
        for n in sizes[d]:
            new = measure(d, n, quick, sweeps and n <= SWEPT[d])
            kinds = {row["kind"] for row in new}
            rows = [row for row in rows if not (row["d"] == d and row["N"] == n
                                                and row["kind"] in kinds)] + new
            rows.sort(key=lambda row: (row["d"], row["N"], _ORDER[row["kind"]]))
            write_csv(out / "default_quadrature.csv", rows)
            write_summary(out, {"rows": rows})
    summary = {"rows": rows}
    write_summary(out, summary)
    return summary


_ORDER = {"refinement": 0, "auto": 1, "review": 2, "sphere": 3, "radial": 4}


def target(resolution: float) -> float:
    """The error a converged rule may leave: 1e-7, or a tenth of N's own error where N
    resolves the data less well than that."""
    return max(LEVEL, resolution / 10)


def table(rows) -> str:
    """The Markdown table of docs/accuracy-vs-cost.md: per grid, N's own error, the target,
    the cheapest sphere and radial rules that meet it (each with the other rule at the
    reference), the preset ``auto`` and the review's rules, and the reference's own error."""
    lines = ["| d | N | N's error (data) | target | cheapest sphere rule | cheapest N_ρ | "
             "auto: N_ρ, rule (pairs) | auto: error Q, D | review: error Q, D | "
             "reference − finer, Q |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for d, n in sorted({(r["d"], r["N"]) for r in rows}):
        of = [r for r in rows if (r["d"], r["N"]) == (d, n)]
        kind = {r["kind"]: r for r in of if r["kind"] in PRESETS}
        if set(kind) != set(PRESETS):
            continue
        goal = target(kind["auto"]["resolution"])

        def cheapest(name, column):
            swept = [r for r in of if r["kind"] == name]
            good = [r for r in swept if r["error_Q"] <= goal]
            prefix = "" if column == "N_rho" else ("M " if d == 2 else "Lebedev ")
            if not swept:
                return "not swept"
            return (prefix + str(min(good, key=lambda r: r["pairs"])[column]) if good
                    else "none")

        name = "M" if d == 2 else "Lebedev"
        auto, review = kind["auto"], kind["review"]
        lines.append(
            f"| {d} | {n} | {auto['resolution']:.1e} | {goal:.1e} | "
            f"{cheapest('sphere', 'sphere')} | {cheapest('radial', 'N_rho')} | "
            f"{auto['N_rho']}, {name} {auto['sphere']} ({auto['pairs']}) | "
            f"{auto['error_Q']:.1e}, {auto['error_D']:.1e} | "
            f"{review['error_Q']:.1e}, {review['error_D']:.1e} | "
            f"{kind['refinement']['error_Q']:.1e} |")
    return "\n".join(lines)


def _show(summary):
    for r in summary["rows"]:
        print(f"{r['d']}D N = {r['N']:<4d} {r['kind']:<10s} N_rho = {r['N_rho']:<4d} "
              f"sphere {r['sphere']!s:<10s} pairs {r['pairs']:<6d} error Q {r['error_Q']:.1e} "
              f"D {r['error_D']:.1e}  (resolution {r['resolution']:.1e}) {r['seconds']:.1f} s")
    print(table(summary["rows"]))


main = command(run, __doc__, "2D N = 16, two rules of each kind (smoke test)",
               parts=", ".join(PARTS), show=_show)


if __name__ == "__main__":
    raise SystemExit(finish(main))
