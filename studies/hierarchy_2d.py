"""The hierarchy of collision models on a rectangle: what it saves on a two-dimensional
Riemann problem near the Euler limit, against what it changes.

The data are Liska & Wendroff's configuration 4 (SIAM J. Sci. Comput. 25 (2003) 995; four
shocks) on [0, 1]^2, as in ``studies/riemann_2d.py``, here with 3D velocities (the Euler
equations of gamma = 5/3), (rho, u_1, u_2, p) = (1.1, 0, 0, 1.1) upper right, (0.5065,
0.8939, 0, 0.35) upper left, (1.1, 0.8939, 0.8939, 1.1) lower left, (0.5065, 0, 0.8939,
0.35) lower right, as Maxwellians of T = p / rho, specular walls, to t = 0.25. Elastic
Maxwell molecules at eps = 1e-3, penalised ARS(2,2,2) with the conservative correction, the
fast spectral operator on 3D N = 24, S = 3.75 (the lower left Maxwellian, |u| = 1.26, needs
it), MUSCL, dt the transport's CFL limit on both axes.

On C x C cells (``--cells``) each hybrid run (the levels euler / esbgk / boltzmann chosen
cell by cell every step, with the ``[space.hierarchy]`` settings of a ``--hierarchy``
option, the defaults without one) goes to t = 0.25, timed over its whole run (set-up
included: the distance of the uniform state and the relaxation rates). Without
``--compare`` the all-kinetic run (the full operator in every cell) is timed over
``--kinetic-steps`` steps after one. With ``--compare`` it goes to t = 0.25 too, timed
over its whole run (its finished store in DIR is taken instead when it holds the same
description and the seconds written beside it), and each hybrid run's row gives the mean
L1 difference (over the cells) of rho, u_1, u_2, T from it, the all-kinetic run's own
distance from the Euler equations (gamma = 5/3, reflecting walls) solved by
:func:`granframe.theory.euler.euler_quadrants` on 8C x 8C cells averaged onto the C x C
cells, and their ratios: at eps = 1e-3 the shock
layers (a few mean free paths, ~1e-2) are far thinner than a cell, so that distance is the
kinetic scheme's discretisation error on C x C cells, up to O(eps). The figure charts
each setting's speed-up against its largest ratio.

    python studies/hierarchy_2d.py --out DIR [--cells 16] [--kinetic-steps 3] [--compare]
        [--hierarchy '{"buffer": 1, "realizability": [0.002, 0.05]}' ...]
    python studies/hierarchy_2d.py --out DIR --cells 16 --first-steps 6

The second times the first K steps of both runs one by one with the levels' shares
(``hierarchy_2d_first_<C>.md``; about 12 minutes for K = 6 on 16^2 cells).

Writes ``hierarchy_2d_<C>.csv``, ``hierarchy_2d_<C>.md``, with ``--compare``
``hierarchy_2d_<C>.png``, and ``levels_<C>_<k>.png`` (the maps of the k-th hybrid run at
t = 0.25, its levels among them) there. On 12^2 cells (50 steps, two cores): the
all-kinetic run 36 minutes (43 s a step), a hybrid run 17 s a step with the full level in
38 % of the cells.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import time

import numpy

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space.transport import box_step_limit
from granframe.theory.cells import conserved_block_average
from granframe.theory.euler import LISKA_WENDROFF_4, euler_quadrants
from granframe.tools import plotting
from granframe.tools.studykit import (
    finish,
    mean_distances,
    number,
    save_figure,
    write_csv,
)
from granframe.velocity.grid import VelocityGrid

GRID = {"dimension": 3, "n_modes": 24, "support_radius": 3.75}
KNUDSEN = 1e-3
#: Lax & Liu's configuration 12 (SIAM J. Sci. Comput. 19 (1998) 319; two shocks and two
#: contacts): (rho, u_1, u_2, p) of each quadrant, as LISKA_WENDROFF_4
LAX_LIU_12 = {"upper_right": (0.5313, 0.0, 0.0, 0.4), "upper_left": (1.0, 0.7276, 0.0, 1.0),
              "lower_left": (0.8, 0.0, 0.0, 1.0), "lower_right": (1.0, 0.0, 0.7276, 1.0)}
#: --configuration -> (its name, its quadrants, the suffix of its files)
CONFIGURATIONS = {"lw4": ("Liska-Wendroff 4", LISKA_WENDROFF_4, ""),
                  "lax_liu_12": ("Lax-Liu 12", LAX_LIU_12, "_ll12")}
FINAL = 0.25
FIELDS = ("rho", "u1", "u2", "T")


def description(cells: int, hierarchy: dict | None, configuration: str = "lw4"
                ) -> RunDescription:
    """The run of the quadrants ``configuration`` (a key of CONFIGURATIONS) on ``cells`` x
    ``cells`` cells, with the hierarchy of the settings ``hierarchy`` (the
    ``[space.hierarchy]`` table; {} its defaults) or all-kinetic (None)."""
    name, states, _ = CONFIGURATIONS[configuration]
    grid = VelocityGrid(**GRID)
    limit = box_step_limit(grid, (1.0 / cells, 1.0 / cells), 0.5)
    steps = 5 * math.ceil(FINAL / limit / 5 * (1 - 1e-12))      # five snapshots
    space = {"cells": [cells, cells], "reconstruction": "muscl", "left": "specular",
             "right": "specular", "bottom": "specular", "top": "specular"}
    if hierarchy is not None:
        space["hierarchy"] = dict(hierarchy)
    return RunDescription.from_dict({
        "title": (f"{name}, 3D velocities, eps = {KNUDSEN:g}, {cells}^2 cells, "
                  + ("all-kinetic" if hierarchy is None else f"hybrid {label(hierarchy)}")),
        "grid": GRID, "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "quadrants", **{
            name: {"density": r, "velocity": [u1, u2, 0.0], "temperature": p / r}
            for name, (r, u1, u2, p) in states.items()}},
        "operator": {"name": "fast_spectral"}, "integrator": "penalised_ars222",
        "conservative": True, "knudsen": KNUDSEN, "time_step": FINAL / steps,
        "final_time": FINAL, "output": {"snapshot_interval": FINAL / 5},
        "space": space})


def label(hierarchy: dict) -> str:
    """The settings ``hierarchy`` in a few characters: "default", or key=value pairs."""
    return ("default" if not hierarchy else
            " ".join(f"{k}={v}" for k, v in sorted(hierarchy.items())))


def settings(text: str) -> dict:
    """An argparse type: a ``[space.hierarchy]`` table as JSON (``{}``: the defaults); its
    keys and values are checked when the run is described, by name."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as error:
        raise argparse.ArgumentTypeError(f"{text!r} is not JSON: {error}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be a JSON object "
                                         "of [space.hierarchy] settings, e.g. "
                                         '\'{"buffer": 1}\'')
    return value


def run(cells: int, hierarchy: dict | None, out: pathlib.Path, name: str,
        configuration: str = "lw4"):
    """The run's dataset and its wall seconds, set-up included: the run made in its store
    ``out/<name>.zarr`` now, its seconds written beside it (``<name>.seconds``); or, when
    that store holds the finished run of the same description and those seconds, the
    store and the seconds of that run (a study run again compares without running it
    again, and times the same thing)."""
    store, timing = out / f"{name}.zarr", out / f"{name}.seconds"
    wanted = description(cells, hierarchy, configuration)
    if store.exists() and timing.exists():
        try:
            ds = granframe.open_run(store)
        except (OSError, ValueError, KeyError):
            ds = None
        if (ds is not None and ds.attrs.get("progress_status") == "finished"
                and RunDescription.from_toml(ds.attrs["description_toml"]) == wanted):
            return ds, float(timing.read_text())
    timing.unlink(missing_ok=True)
    began = time.perf_counter()
    Simulation(wanted).run(store, progress=False, overwrite=True)
    seconds = time.perf_counter() - began
    timing.write_text(f"{seconds!r}\n")
    return granframe.open_run(store), seconds


def fields(ds) -> dict:
    """rho, u_1, u_2, T (C, C) at the last record."""
    velocity = ds.velocity.values[-1]
    return {"rho": ds.density.values[-1], "u1": velocity[..., 0], "u2": velocity[..., 1],
            "T": ds.temperature.values[-1]}


def kinetic_step_seconds(cells: int, steps: int, configuration: str = "lw4") -> float:
    """Seconds per step of the all-kinetic run: the mean of ``steps`` steps after one."""
    d = description(cells, None, configuration)
    problem = Simulation(d).problem
    state, dt = problem.state(problem.f0), d.time_step
    state = problem.step(0.0, state, dt)                         # warm-up: plans
    began = time.perf_counter()
    for k in range(steps):
        state = problem.step((k + 1) * dt, state, dt)
    return (time.perf_counter() - began) / steps


def first_steps(cells: int, hierarchy: dict | None, steps: int,
                configuration: str = "lw4") -> tuple:
    """The wall seconds of each of the first ``steps`` steps with its record, and (with a
    hierarchy, the settings of :func:`description`) the share of the cells at each level
    in each."""
    d = description(cells, hierarchy, configuration)
    problem = Simulation(d).problem
    state, dt = problem.state(problem.f0), d.time_step
    times, shares = [], []
    for k in range(steps):
        began = time.perf_counter()
        state = problem.step(k * dt, state, dt)
        problem.record(state)
        times.append(time.perf_counter() - began)
        if hierarchy is not None:
            levels = problem.hierarchy.levels
            shares.append(numpy.bincount(levels, minlength=3) / levels.size)
    return times, shares


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder of the tables and figures")
    parser.add_argument("--configuration", choices=sorted(CONFIGURATIONS), default="lw4",
                        help="the quadrants: Liska & Wendroff's configuration 4 (default) or "
                             "Lax & Liu's configuration 12")
    parser.add_argument("--cells", type=number(8, low_open=False, kind=int), default=16,
                        help="cells a side (default 16)")
    parser.add_argument("--kinetic-steps", type=number(1, low_open=False, kind=int),
                        default=3, help="all-kinetic steps timed after one (default 3)")
    parser.add_argument("--compare", action="store_true",
                        help="run the all-kinetic run to the end too (or take its finished "
                             "store in --out) and compare")
    parser.add_argument("--hierarchy", type=settings, action="append",
                        help="the [space.hierarchy] settings of a hybrid run as JSON, e.g. "
                             '\'{"buffer": 1, "realizability": [0.002, 0.05]}\'; repeat for '
                             "several runs (default: one run, {}, the defaults)")
    parser.add_argument("--first-steps", type=number(1, low_open=False, kind=int),
                        help="time only the first K steps of each run, one by one")
    args = parser.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    c, configuration = args.cells, args.configuration
    name, states, suffix = CONFIGURATIONS[configuration]
    chosen = args.hierarchy or [{}]
    for hierarchy in chosen:            # bad settings refused by name before any run
        description(c, hierarchy, configuration)
    if args.first_steps:
        hybrid, shares = first_steps(c, chosen[0], args.first_steps, configuration)
        kinetic, _ = first_steps(c, None, args.first_steps, configuration)
        lines = ["| step | all-kinetic (s) | hybrid (s) | shares euler / esbgk / boltzmann |",
                 "|---|---|---|---|"]
        lines += [f"| {k + 1} | {a:.1f} | {b:.1f} | {' / '.join(f'{x:.0%}' for x in share)} |"
                  for k, (a, b, share) in enumerate(zip(kinetic, hybrid, shares))]
        text = "\n".join(lines) + "\n"
        (out / f"hierarchy_2d_first_{c}{suffix}.md").write_text(text)
        print(text)
        return 0
    if args.compare:
        ds_k, seconds_k = run(c, None, out, f"kinetic_{c}{suffix}", configuration)
        steps = int(ds_k.sizes["step_time"] - 1)
        truth = conserved_block_average(euler_quadrants(states, 8 * c, FINAL, dimension=3),
                                        c, dimension=3)
        kinetic = {"step_s": seconds_k / steps, "fields": fields(ds_k)}
        kinetic["own"] = mean_distances(kinetic["fields"], truth)
        print(f"all-kinetic: {steps} steps in {seconds_k:.1f} s; its own L1 error "
              f"{kinetic['own']}", flush=True)
    else:
        kinetic = {"step_s": kinetic_step_seconds(c, args.kinetic_steps, configuration)}
    rows = [compare(c, hierarchy, k, out, kinetic, configuration)
            for k, hierarchy in enumerate(chosen)]
    write_csv(out / f"hierarchy_2d_{c}{suffix}.csv", rows, list(rows[0]))
    if args.compare:
        save_figure(cost_and_accuracy(rows, name), out / f"hierarchy_2d_{c}{suffix}.png")
    columns = [k for k in rows[0] if k not in ("cells",)]
    lines = [(f"{name}, 3D velocities N = {GRID['n_modes']}, eps = {KNUDSEN:g}, "
              f"t = {FINAL}, {c}^2 cells; all-kinetic {kinetic['step_s']:.4g} s a step "
              + ("over its whole run" if args.compare else
                 f"(the mean of {args.kinetic_steps} steps after one)")), "",
             "| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(f"{row[k]:.4g}" if isinstance(row[k], float) else str(row[k])
                                for k in columns) + " |" for row in rows]
    text = "\n".join(lines) + "\n"
    (out / f"hierarchy_2d_{c}{suffix}.md").write_text(text)
    print(text)
    return 0


def compare(cells: int, hierarchy: dict, index: int, out: pathlib.Path, kinetic: dict,
            configuration: str = "lw4") -> dict:
    """The row of the hybrid run of the settings ``hierarchy``: its seconds per step over
    its whole run against the all-kinetic run's (``kinetic["step_s"]``), the mean and final
    share of the cells at each level and, when ``kinetic`` holds the all-kinetic run's
    "fields" and its "own" mean L1 error against the reference, the mean L1 differences
    from the all-kinetic run, that own error, and their ratios; its levels mapped at the
    end (``levels_<C>_<index>.png``)."""
    suffix = CONFIGURATIONS[configuration][2]
    ds_h, seconds_h = run(cells, hierarchy, out, f"hybrid_{cells}_{index}{suffix}",
                          configuration)
    steps = int(ds_h.sizes["step_time"] - 1)
    levels = ds_h.level.values[1:]
    names = list(ds_h.level.attrs["levels"])
    row = {"cells": cells, "settings": label(hierarchy), "steps": steps,
           "kinetic_step_s": kinetic["step_s"], "hybrid_step_s": seconds_h / steps,
           "speedup": kinetic["step_s"] * steps / seconds_h,
           **{f"share_{n}": float((levels == k).mean()) for k, n in enumerate(names)},
           **{f"final_{n}": float((levels[-1] == k).mean()) for k, n in enumerate(names)}}
    save_figure(plotting.figures(ds_h)[f"plane_{ds_h.sizes['time'] - 1}"],
                out / f"levels_{cells}_{index}{suffix}.png")
    if "own" in kinetic:
        diff, own = mean_distances(fields(ds_h), kinetic["fields"]), kinetic["own"]
        row.update({f"diff_{k}": v for k, v in diff.items()})
        row.update({f"own_{k}": v for k, v in own.items()})
        row.update({f"ratio_{k}": diff[k] / own[k] for k in FIELDS})
        row["ratio_max"] = max(row[f"ratio_{k}"] for k in FIELDS)
    print(row, flush=True)
    return row


def cost_and_accuracy(rows: list[dict], name: str):
    """The speed-up of each hybrid run against the largest ratio of its L1 difference from
    the all-kinetic run to that run's own error (over rho, u_1, u_2, T), with the targets
    (5x, 0.1) drawn."""
    import matplotlib.pyplot as plt  # the Agg backend: studykit chose it on import

    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    for k, row in enumerate(rows):
        ax.plot(row["ratio_max"], row["speedup"], "o", color=f"C{k}",
                label=f"{k}: {row['settings']}")
    ax.axhline(5.0, color="0.5", ls="--", lw=0.8)
    ax.axvline(0.1, color="0.5", ls="--", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("max over rho, u, T of L1(hybrid - kinetic) / L1(kinetic - Euler ref.)")
    ax.set_ylabel("speed-up over the whole run")
    ax.set_title(f"{name}, eps = {KNUDSEN:g}, {rows[0]['cells']}^2 cells",
                 fontsize=10)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


if __name__ == "__main__":
    raise SystemExit(finish(main))
