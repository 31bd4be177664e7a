r"""A granular shock: gas driven into a wall at rest (the piston problem in the wall's frame),
elastic and inelastic, against Rankine-Hugoniot and granular Euler hydrodynamics.

The gas (rho_1 = 1, T_1 = 1, u = -U) fills [0, ell] between two specular walls; a shock
leaves the wall at x = 0 and the gas behind it is at rest (a rarefaction leaves the far
wall, and the runs stop before it reaches the shock). 2D velocities with the Maxwell
kernel B = 1/(2 pi): Rankine-Hugoniot does not depend on the kernel (only on
gamma = (d+2)/d = 2), and for this kernel the energy the collisions take out of any f is
exact in rho and T (module notes of :func:`cooling_rate`), so that the granular Euler
equations

    d_t rho + d_x (rho u) = 0,   d_t (rho u) + d_x (rho u^2 + p) = 0,
    d_t E + d_x (u (E + p)) = -(1 - e^2) rho^2 T d / (8 eps),   p = rho T,
    E = rho u^2/2 + d rho T/2,

are the limit eps -> 0 at fixed (1 - e^2)/eps of the kinetic run. They are solved here by
an independent finite-volume scheme (:func:`granular_euler`); for e = 1 the post-shock
state and the shock speed are exact (:func:`rankine_hugoniot`).

Run: ``python studies/granular_shock.py --out DIR [--restitution 1] [--knudsen 1e-3]``.
"""

from __future__ import annotations

import math
import pathlib
import sys
import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space import exact
from granframe.tools.studykit import finish, json_text, number, save_figure

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from granular_hcs import output_folder, study_arguments  # noqa: E402
from space import cfl_time_step  # noqa: E402

DIMENSION = 2
GAMMA = (DIMENSION + 2) / DIMENSION


def rankine_hugoniot(speed: float, density: float = 1.0, temperature: float = 1.0) -> dict:
    """The exact elastic piston problem: gas (rho_1, T_1) moving at -U into a wall at rest.

    The reflected problem is the Riemann problem (rho_1, +U, p_1) | (rho_1, -U, p_1), whose
    star state (:func:`granframe.space.exact.euler_riemann_star`, Toro ch. 4) is the gas at
    rest behind the shock: rho_2, p_2, T_2 = p_2 / rho_2. Mass conservation across the shock
    gives its speed in the wall's frame, s = rho_1 U / (rho_2 - rho_1), and its Mach number
    against the incoming gas, M = (s + U) / c_1, c_1 = sqrt(gamma T_1)."""
    pressure = density * temperature
    star = exact.euler_riemann_star((density, speed, pressure), (density, -speed, pressure),
                                    GAMMA)
    rho2 = star["rho_left"]
    shock = density * speed / (rho2 - density)
    return {"rho_2": rho2, "T_2": star["p"] / rho2, "p_2": star["p"], "shock_speed": shock,
            "mach": (shock + speed) / math.sqrt(GAMMA * temperature)}


def piston_speed(mach: float, temperature: float = 1.0) -> float:
    """U = 2 c_1 (M - 1/M) / (gamma + 1): the wall speed that drives a shock of Mach M
    (Landau & Lifshitz, Fluid Mechanics, section 89; c_1 = sqrt(gamma T_1))."""
    return 2.0 * math.sqrt(GAMMA * temperature) * (mach - 1.0 / mach) / (GAMMA + 1.0)


def cooling_rate(e: float, knudsen: float) -> float:
    r"""c in dT/dt = -c rho T, the exact cooling of any f under the Maxwell kernel.

    With B = 1/|S^{d-1}| (1/(2 pi) in 2D) and g' = (1-e)/2 g + (1+e)/2 |g| sigma, the mean
    over sigma of |g'|^2 is (1 + e^2)/2 |g|^2, so the collisions change the energy density
    by -(1 - e^2)/(16 eps) int int f f_* |g|^2 = -(1 - e^2) d rho^2 T / (8 eps), and with
    E = d rho T/2 the temperature by -(1 - e^2) rho T / (4 eps)."""
    return (1.0 - e * e) / (4.0 * knudsen)


def _primitive(q):
    rho = q[0]
    u = q[1] / rho
    temperature = (q[2] - 0.5 * rho * u * u) / (0.5 * DIMENSION * rho)
    return rho, u, temperature


def _minmod(a, b):
    return numpy.where(a * b > 0.0, numpy.sign(a) * numpy.minimum(abs(a), abs(b)), 0.0)


def _hll(left, right):
    """HLL flux (Harten, Lax & van Leer 1983) with Davis's wave speeds, from primitive
    (rho, u, T) states either side of each face."""
    fluxes, states, speeds = [], [], []
    for rho, u, temperature in (left, right):
        p = rho * temperature
        energy = 0.5 * rho * u * u + 0.5 * DIMENSION * p
        states.append(numpy.array([rho, rho * u, energy]))
        fluxes.append(numpy.array([rho * u, rho * u * u + p, u * (energy + p)]))
        speeds.append((u, numpy.sqrt(GAMMA * temperature)))
    (ul, cl), (ur, cr) = speeds
    slow = numpy.minimum(ul - cl, ur - cr)
    fast = numpy.maximum(ul + cl, ur + cr)
    lo, hi = numpy.minimum(slow, 0.0), numpy.maximum(fast, 0.0)
    return (hi * fluxes[0] - lo * fluxes[1] + hi * lo * (states[1] - states[0])) / (hi - lo)


def granular_euler(speed: float, e: float, knudsen: float, length: float, times,
                   cells: int = 4000, cfl: float = 0.4) -> dict:
    """The granular Euler equations (module notes) for the same piston problem: MUSCL
    (minmod on rho, u, T), HLL fluxes, SSP RK2 (Shu & Osher 1988), reflecting walls at both
    ends, and the cooling each step by its exact solution at fixed rho,
    T <- T exp(-c rho dt) (:func:`cooling_rate`), Strang-split around the transport.
    Returns the cell centres and rho, u, T at each of ``times``."""
    dx = length / cells
    x = (numpy.arange(cells) + 0.5) * dx
    rho = numpy.ones(cells)
    q = numpy.array([rho, -speed * rho, 0.5 * speed * speed * rho + 0.5 * DIMENSION * rho])
    c = cooling_rate(e, knudsen)

    def cool(q, dt):
        rho, u, temperature = _primitive(q)
        temperature = temperature * numpy.exp(-c * rho * dt)
        return numpy.array([rho, rho * u, 0.5 * rho * u * u + 0.5 * DIMENSION * rho * temperature])

    def rate(q):
        prim = numpy.array(_primitive(q))
        mirror = prim[:, [1, 0]] * numpy.array([[1.0], [-1.0], [1.0]])
        far = prim[:, [-1, -2]] * numpy.array([[1.0], [-1.0], [1.0]])
        padded = numpy.concatenate([mirror[:, ::-1], prim, far], axis=1)
        slope = _minmod(padded[:, 1:-1] - padded[:, :-2], padded[:, 2:] - padded[:, 1:-1])
        centre = padded[:, 1:-1]
        left = (centre + 0.5 * slope)[:, :-1]
        right = (centre - 0.5 * slope)[:, 1:]
        flux = _hll(tuple(left), tuple(right))
        return -(flux[:, 1:] - flux[:, :-1]) / dx

    out, t = {"x": x, "time": [], "density": [], "velocity": [], "temperature": []}, 0.0
    for target in sorted(times):
        while t < target - 1e-14:
            rho, u, temperature = _primitive(q)
            dt = min(cfl * dx / float(numpy.max(abs(u) + numpy.sqrt(GAMMA * temperature))),
                     target - t)
            q = cool(q, 0.5 * dt)
            stage = q + dt * rate(q)
            q = 0.5 * (q + stage + dt * rate(stage))
            q = cool(q, 0.5 * dt)
            t += dt
        rho, u, temperature = _primitive(q)
        for name, value in (("time", t), ("density", rho), ("velocity", u),
                            ("temperature", temperature)):
            out[name].append(value)
    return {k: numpy.asarray(v) for k, v in out.items()}


def description(speed: float, e: float, knudsen: float, cells: int, length: float,
                final: float, n_modes: int, support: float, time_step: float) -> RunDescription:
    """The kinetic piston problem: 2D Maxwell kernel, MUSCL, penalised ARS(2,2,2) (the
    Euler limit at small eps), the conservative correction, moments every step."""
    state = {"density": 1.0, "temperature": 1.0, "velocity": -speed}
    return RunDescription(
        title=f"granular shock, U = {speed:g}, e = {e:g}, eps = {knudsen:g}, {cells} cells",
        grid={"dimension": DIMENSION, "n_modes": n_modes, "support_radius": support},
        kernel="maxwell", restitution={"name": "constant", "value": e},
        initial={"name": "riemann", "left": state, "right": state},
        operator={"name": "fast_spectral"}, integrator="penalised_ars222", knudsen=knudsen,
        conservative=True, time_step=time_step, final_time=final,
        output={"snapshot_interval": final},
        space={"cells": cells, "length": length, "left": "specular", "right": "specular"})


def shock_position(x, density, upstream: float = 1.0) -> float:
    """Where the density, read from the far side, first climbs above halfway between the
    upstream density and the largest density ahead of the wall region: the last crossing
    of (rho_1 + rho_max)/2 from the wall, linearly interpolated between cell centres; 0
    while the density nowhere exceeds rho_1 by 1e-3 (no shock yet)."""
    if float(numpy.max(density)) < upstream + 1e-3:
        return 0.0
    level = 0.5 * (upstream + float(numpy.max(density)))
    above = numpy.nonzero(density >= level)[0]
    i = int(above[-1])
    if i + 1 >= len(x):
        return float(x[-1])
    a, b = density[i], density[i + 1]
    return float(x[i] + (x[i + 1] - x[i]) * (a - level) / (a - b))


def shock_track(times, x, density):
    """The shock position at each time and its speed: the slope of the least-squares line
    through the positions of the last two thirds of the run."""
    positions = numpy.array([shock_position(x, rho) for rho in density])
    late = times >= times[-1] / 3.0
    slope = numpy.polyfit(times[late], positions[late], 1)[0]
    return positions, float(slope)


def plateau(x, values, position: float) -> float:
    """The mean of ``values`` over the cells in [0.3, 0.7] x the shock position (away from
    the wall's layer and the shock)."""
    inside = (x >= 0.3 * position) & (x <= 0.7 * position)
    return float(numpy.mean(values[inside]))


def cell_averages(values, cells: int):
    """Averages of fine reference profiles (the last axis) over ``cells`` kinetic cells,
    each a whole number of fine ones."""
    return values.reshape(*values.shape[:-1], cells, -1).mean(axis=-1)


def compare(store, speed: float, e: float, knudsen: float, length: float) -> dict:
    """The kinetic run against Rankine-Hugoniot (shock speed, rho_2, T_2: elastic) and
    against granular Euler (the L1 distance of rho and T behind the shock over the run's
    last state; ``bulk rho``, ``bulk T``: the largest relative difference over the cells in
    [0.15, 0.75] x Euler's shock position, away from the wall's layer and the shock; the
    wall cell's rho and T, the shock position; any e), with ``history``:
    the wall cell's rho and T and the shock position at a quarter, half, three quarters and
    the whole of the run, against granular Euler's (averaged over the same cells)."""
    ds = granframe.open_run(store, time_axis="steps")
    t = ds.time.values
    x = ds.x.values
    cells = len(x)
    density, temperature = ds.density.values, ds.temperature.values
    positions, shock = shock_track(t, x, density)
    quarters = [t[-1] * q for q in (0.25, 0.5, 0.75, 1.0)]
    reference = granular_euler(speed, e, knudsen, length, quarters,
                               cells=cells * max(1, 4000 // cells))
    rho_coarse = cell_averages(reference["density"], cells)
    t_coarse = cell_averages(reference["temperature"], cells)
    rho_ref, t_ref = rho_coarse[-1], t_coarse[-1]
    rows = [int(numpy.argmin(abs(t - q))) for q in quarters]
    history = {"times": quarters,
               "T wall": [float(temperature[i][0]) for i in rows],
               "Euler T wall": [float(v) for v in t_coarse[:, 0]],
               "rho wall": [float(density[i][0]) for i in rows],
               "Euler rho wall": [float(v) for v in rho_coarse[:, 0]],
               "shock position": [float(positions[i]) for i in rows],
               "Euler shock position": [shock_position(x, r) for r in rho_coarse]}
    ref_position = shock_position(x, rho_ref)
    behind = x <= 1.2 * max(ref_position, positions[-1])
    bulk = (x >= 0.15 * ref_position) & (x <= 0.75 * ref_position)
    dx = length / cells
    row = {"U": speed, "e": e, "eps": knudsen, "cells": cells,
           "N": int(ds.sizes["v1"]), "final": float(t[-1]), "steps": int(len(t) - 1),
           "shock speed": shock, "shock position": float(positions[-1]),
           "Euler shock position": ref_position,
           "rho wall": float(density[-1][0]), "Euler rho wall": float(rho_ref[0]),
           "T wall": float(temperature[-1][0]), "Euler T wall": float(t_ref[0]),
           "L1 rho": float(numpy.sum(abs(density[-1] - rho_ref)[behind]) * dx),
           "L1 T": float(numpy.sum(abs(temperature[-1] - t_ref)[behind]) * dx),
           "bulk rho": float(numpy.max(abs(density[-1] / rho_ref - 1.0)[bulk])),
           "bulk T": float(numpy.max(abs(temperature[-1] / t_ref - 1.0)[bulk])),
           "mass drift": float(abs(ds.mass.values[-1] / ds.mass.values[0] - 1.0)),
           "largest negative mass share": float(ds.negative_mass_fraction.values.max()),
           "history": history}
    if e == 1.0:
        exact_state = rankine_hugoniot(speed)
        row.update({"rho_2": plateau(x, density[-1], positions[-1]),
                    "T_2": plateau(x, temperature[-1], positions[-1]),
                    "RH rho_2": exact_state["rho_2"], "RH T_2": exact_state["T_2"],
                    "RH shock speed": exact_state["shock_speed"], "mach": exact_state["mach"]})
    return row


def figure(stores, path) -> None:
    """rho and T at the last time of each run (lines with markers) against granular Euler
    (black), and the wall cell's T over time."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), layout="tight")
    drawn = set()
    for store in stores:
        ds = granframe.open_run(store, time_axis="steps")
        d = RunDescription.from_toml(ds.attrs["description_toml"])
        e, eps = d.restitution.params["value"], d.knudsen
        speed = -d.initial.params["left"]["velocity"]
        length = d.space.length
        t = ds.time.values
        label = f"e = {e:g}, eps = {eps:g}, {ds.sizes['x']} cells"
        line, = axes[0].plot(ds.x.values, ds.density.values[-1], ".-", ms=3, lw=0.8,
                             label=label)
        axes[1].plot(ds.x.values, ds.temperature.values[-1], ".-", ms=3, lw=0.8,
                     color=line.get_color())
        axes[2].plot(t, ds.temperature.values[:, 0], "-", color=line.get_color(), lw=1)
        key = (speed, e, eps, length, float(t[-1]))
        if key in drawn:
            continue
        drawn.add(key)
        times = numpy.linspace(0.0, t[-1], 41)[1:]
        ref = granular_euler(speed, e, eps, length, times)
        axes[0].plot(ref["x"], ref["density"][-1], "k-", lw=0.8)
        axes[1].plot(ref["x"], ref["temperature"][-1], "k-", lw=0.8)
        axes[2].plot(ref["time"], ref["temperature"][:, :len(ref["x"]) // 100].mean(axis=1),
                     "k--", lw=0.8)
    axes[0].set_ylabel("density")
    axes[1].set_ylabel("temperature")
    axes[2].set_ylabel("T in the wall cell")
    for ax in axes[:2]:
        ax.set_xlabel("x")
    axes[2].set_xlabel("t")
    axes[0].legend(fontsize=7)
    fig.suptitle("gas driven into a wall: granframe (colours), granular Euler (black)",
                 fontsize=9)
    save_figure(fig, path, dpi=120)


def main(argv=None):
    parser = study_arguments(__doc__, n_modes=48, cells=100, final=0.2)
    parser.set_defaults(restitution=1.0, support=4.5)
    parser.add_argument("--knudsen", type=number(0.0), default=1e-3)
    parser.add_argument("--mach", type=number(1.0), default=1.5,
                        help="the elastic shock's Mach number, which fixes U")
    parser.add_argument("--length", type=number(0.0), default=1.0)
    args = parser.parse_args(argv)
    out = output_folder(args, figure, "shock.png")
    if out is None:
        return
    speed = piston_speed(args.mach)
    grid = {"n_modes": args.n_modes, "support_radius": args.support}
    time_step = cfl_time_step(args.cells, args.final, grid, length=args.length)
    began = time.perf_counter()
    run = Simulation(description(speed, args.restitution, args.knudsen, args.cells,
                                 args.length, args.final, args.n_modes, args.support,
                                 time_step))
    store = out / (f"shock_e{args.restitution:g}_eps{args.knudsen:g}_c{args.cells}"
                   f"_n{args.n_modes}.zarr")
    result = run.run(store, progress=False, overwrite=True)
    seconds = time.perf_counter() - began
    row = {**compare(store, speed, args.restitution, args.knudsen, args.length),
           "seconds": seconds, "dt": time_step,
           "warnings": [str(w) for w in result.warnings + result.accuracy_warnings]}
    print(json_text(row))
    store.with_suffix(".json").write_text(json_text(row, indent=1))


if __name__ == "__main__":
    raise SystemExit(finish(main))
