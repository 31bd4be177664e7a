"""The hierarchy of collision models against the all-kinetic run, on five scenes.

For every scene three runs: the all-kinetic run (the full operator in every cell) on C
cells, the same on 2C cells (the reference of its discretisation error), and the hybrid
run on C cells with the default hierarchy (``space.hierarchy = {}``: euler, esbgk,
boltzmann; docs/space.md, "The hierarchy"). For rho, u and T at the final time:

- ``error`` the L1 distance sum dx |w_C - w_2C| of the all-kinetic run from the refined
  one averaged onto the C cells, its own discretisation error;
- ``difference`` the L1 distance of the hybrid run from the all-kinetic one, and the
  ratio difference / error, which must be at most 0.1;

with the wall time of each run, its time per step, the share of cells at each level
(mean over the steps and at the end) and the warnings of each run's monitors.

Scenes (2D velocities, Maxwell molecules, the fast operator, the conservative correction):

- ``sod_1e-3``, ``sod_1e-2``: the elastic Sod tube of studies/space.py (N = 32, S = 3.5,
  specular walls, MUSCL, penalised ARS(2,2,2)), 50 cells, t = 0.2;
- ``walls``: the granular gas between heated walls, e = 0.9, eps = 0.1, diffuse walls at
  T = 1, from the Maxwellian at T = 1, 40 cells, explicit SSP RK2, t = 2;
- ``shock``: a gas (rho = 1, T = 1, u = -1.5, Mach 1.06) driven into the specular wall at
  x = 0, e = 0.97, eps = 1e-2, N = 40, S = 5, 50 cells, t = 0.3: a reflected shock moving
  into the inflow (and a rarefaction at the far wall; with e = 0.9 the cooled, compressed
  gas at the wall was narrower than the grid resolves and the all-kinetic run lost
  positivity at t = 0.25);
- ``shear``: the homogeneous cooling state with a shear mode u_2 = 0.2 sin(2 pi x),
  periodic, e = 0.97, eps = 1e-2, 40 cells, t = 0.5;
- ``sod_1e-3_n48`` (only when named): ``sod_1e-3`` on the velocity grid N = 48, S = 4.5,
  on which the edge monitor of the N = 32 grid no longer warns;
- ``sod3d`` (only when named: about an hour here): the Sod tube at eps = 1e-3 with 3D
  velocities (N = 24, S = 3.5), 40 cells, t = 0.1.

``--timing3d`` adds the time per step of the Sod tube at eps = 1e-3 with 3D velocities
(N = 24, S = 3.5, 40 cells): the hybrid run to t = 0.1 and the mean of the all-kinetic
run's first steps (its cost per step does not depend on the solution), with the shares,
and the cost per cell of the transport and of each level. ``--refinement`` adds the mean
shares of the levels of the 2D Sod tube at eps = 1e-3 on 50, 100 and 200 cells and the 3D
speed-up they would give with those costs. ``--thresholds 0.05,0.03`` adds, for every
scene, hybrid runs with the middle level's realizability threshold set to each value
(``calibration.png``: the ratio against the share of the full level). ``--model-error``
runs the shear scene with every cell at the ES-BGK level, inelastic and elastic.

    python studies/hierarchy.py --out DIR [--scenes sod_1e-3,walls] [--timing3d]
        [--refinement] [--thresholds 0.05,0.03] [--model-error]

writes ``hierarchy.csv``, ``hierarchy.md``, ``levels_<scene>.png`` (the x-t map of the
levels and their shares over time) there and prints the tables.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import numpy

from granframe.tools.studykit import (cfl_time_step, finish, name_list, numbers, save_figure,
                                      write_csv)
import matplotlib.pyplot as plt  # noqa: E402  (after studykit chose the Agg backend)
from granframe.run.description import Hierarchy, RunDescription
from granframe.run.runner import Simulation
from granframe.tools import plotting
from granframe.tools.space_cases import SOD_FINAL, SOD_GRID, sod_description, walls_description

SHOCK_GRID = {"dimension": 2, "n_modes": 40, "support_radius": 5.0}
GRID_3D = {"dimension": 3, "n_modes": 24, "support_radius": 3.5}
FINE_GRID = {"dimension": 2, "n_modes": 48, "support_radius": 4.5}


def _with(description: RunDescription, hierarchy) -> RunDescription:
    """``description`` with ``space.hierarchy`` set (None: left without)."""
    if hierarchy is None:
        return description
    table = description.to_dict()
    table["space"]["hierarchy"] = dict(hierarchy)
    return RunDescription.from_dict(table)


def sod(knudsen):
    def build(cells, hierarchy=None, grid=SOD_GRID, final=SOD_FINAL):
        return _with(sod_description(cells, knudsen, final=final, grid=grid), hierarchy)
    return build


def walls(cells, hierarchy=None):
    d = walls_description(cells, 0.1, 0.9, 1.0, 1.0, 1.0, 2.0, conservative=True,
                                title=f"heated walls, e = 0.9, eps = 0.1, {cells} cells")
    return _with(d, hierarchy)


def shock(cells, hierarchy=None):
    final = 0.3
    state = {"density": 1.0, "temperature": 1.0, "velocity": -1.5}
    d = RunDescription(
        title=f"gas driven into a wall, e = 0.97, eps = 1e-2, {cells} cells",
        grid=SHOCK_GRID, kernel="maxwell", restitution={"name": "constant", "value": 0.97},
        initial={"name": "riemann", "left": state, "right": state},
        operator={"name": "fast_spectral"}, integrator="penalised_ars222", knudsen=1e-2,
        conservative=True, time_step=cfl_time_step(cells, final, SHOCK_GRID),
        final_time=final, output={"snapshot_interval": final},
        space={"cells": cells, "left": "specular", "right": "specular"})
    return _with(d, hierarchy)


def shear(cells, hierarchy=None):
    final = 0.5
    d = RunDescription(
        title=f"cooling state with a shear mode, e = 0.97, eps = 1e-2, {cells} cells",
        grid=SOD_GRID, kernel="maxwell", restitution={"name": "constant", "value": 0.97},
        initial={"name": "sinusoidal_mode", "field": "velocity", "component": 2,
                 "amplitude": 0.2},
        operator={"name": "fast_spectral"}, integrator="penalised_ars222", knudsen=1e-2,
        conservative=True, time_step=cfl_time_step(cells, final, SOD_GRID),
        final_time=final, output={"snapshot_interval": final},
        space={"cells": cells})
    return _with(d, hierarchy)


def sod3d(cells, hierarchy=None):
    return sod(1e-3)(cells, hierarchy, grid=GRID_3D, final=0.1)


def sod_fine(cells, hierarchy=None):
    return sod(1e-3)(cells, hierarchy, grid=FINE_GRID)


#: name -> (description builder, cells, the velocity component compared); ``sod3d`` (3D
#: velocities, about an hour on 2 cores) and ``sod_1e-3_n48`` (the finer velocity grid)
#: run only when named
SCENES = {"sod_1e-3": (sod(1e-3), 50, 0), "sod_1e-2": (sod(1e-2), 50, 0),
          "walls": (walls, 40, 0), "shock": (shock, 50, 0), "shear": (shear, 40, 1),
          "sod3d": (sod3d, 40, 0), "sod_1e-3_n48": (sod_fine, 50, 0)}
DEFAULT_SCENES = ("sod_1e-3", "sod_1e-2", "walls", "shock", "shear")
FIELDS = ("rho", "u", "T")


def run(description):
    """(dataset, seconds, warnings) of one run held in memory."""
    began = time.perf_counter()
    result = Simulation(description).run(None, progress=False)
    seconds = time.perf_counter() - began
    return result.dataset, seconds, tuple(result.warnings) + tuple(result.accuracy_warnings)


def final_fields(ds, component: int) -> numpy.ndarray:
    """rho, u (the compared component) and T of every cell at the final step."""
    return numpy.stack([ds.density.values[-1], ds.velocity.values[-1][:, component],
                        ds.temperature.values[-1]])


def coarsened(fields: numpy.ndarray) -> numpy.ndarray:
    """Fields of 2C cells averaged onto C cells."""
    return 0.5 * (fields[:, 0::2] + fields[:, 1::2])


def _shares(hybrid) -> tuple[list[str], numpy.ndarray, numpy.ndarray]:
    """(level names, mean share of each level over the steps, share at the last step)."""
    levels = hybrid.level.values[1:]
    names = list(hybrid.level.attrs["levels"])
    return (names, numpy.array([(levels == k).mean() for k in range(len(names))]),
            numpy.array([(levels[-1] == k).mean() for k in range(len(names))]))


def scene_row(name: str, out: pathlib.Path, middle=()) -> tuple[dict, list[dict]]:
    """The row of scene ``name`` with the default hierarchy, and (when ``middle`` is given)
    calibration rows: the default's, and one for each threshold of the middle level in
    ``middle`` (``realizability = [0.002, t]``, the rest default), all measured against the
    same all-kinetic and refined runs."""
    build, cells, component = SCENES[name]
    kinetic, t_kinetic, w_kinetic = run(build(cells))
    refined, t_refined, w_refined = run(build(2 * cells))
    hybrid, t_hybrid, w_hybrid = run(build(cells, {}))
    base = final_fields(kinetic, component)
    error = numpy.abs(base - coarsened(final_fields(refined, component))).mean(axis=1)
    difference = numpy.abs(final_fields(hybrid, component) - base).mean(axis=1)
    steps = int(hybrid.sizes["step_time"] - 1)
    names, shares, final = _shares(hybrid)
    figure = plotting.figures(hybrid).get("levels")
    if figure is not None:
        save_figure(figure, out / f"levels_{name}.png")
    row = {"scene": name, "cells": cells, "steps": steps,
           **{f"error_{k}": float(v) for k, v in zip(FIELDS, error)},
           **{f"difference_{k}": float(v) for k, v in zip(FIELDS, difference)},
           **{f"ratio_{k}": float(v) for k, v in zip(FIELDS, difference / error)},
           "kinetic_s": t_kinetic, "refined_s": t_refined, "hybrid_s": t_hybrid,
           "kinetic_step_s": t_kinetic / steps, "hybrid_step_s": t_hybrid / steps,
           "speedup": t_kinetic / t_hybrid,
           **{f"share_{n}": float(s) for n, s in zip(names, shares)},
           **{f"final_{n}": float(s) for n, s in zip(names, final)},
           "warnings": " | ".join(sorted(set(w_kinetic + w_refined + w_hybrid)))[:300]}
    _print(row)
    calibration = [{"scene": name, "realizability": Hierarchy().realizability[-1],
                    **{k: row[k] for k in row if k.startswith(("ratio_", "share_"))},
                    "hybrid_s": t_hybrid}] if middle else []
    for threshold in middle:
        other, seconds, _ = run(build(cells, {"realizability": [0.002, threshold]}))
        difference = numpy.abs(final_fields(other, component) - base).mean(axis=1)
        names, shares, _ = _shares(other)
        calibration.append({"scene": name, "realizability": threshold,
                            **{f"ratio_{k}": float(v) for k, v in zip(FIELDS, difference / error)},
                            **{f"share_{n}": float(s) for n, s in zip(names, shares)},
                            "hybrid_s": seconds})
        _print(calibration[-1])
    return row, calibration


#: every cell at the ES-BGK level after the first step (thresholds no cell exceeds)
ALL_ESBGK = {"levels": ["esbgk", "boltzmann"], "realizability": [1.0], "distance": [2.0]}


def model_error(cells: int = 40) -> list[dict]:
    """The ES-BGK model's own error on the shear scene: the L1 difference of rho, u_2, T
    between the all-kinetic run and the run with every cell at the ES-BGK level, for the
    inelastic gas of the scene (e = 0.97) and the elastic one (e = 1), the latter telling
    what is due to the model at this Knudsen number and not to the granular cooling."""
    rows = []
    for e in (0.97, 1.0):
        def build(hierarchy):
            table = shear(cells, hierarchy).to_dict()
            table["restitution"] = {"name": "constant", "value": e}
            return RunDescription.from_dict(table)
        kinetic = final_fields(run(build(None))[0], 1)
        relaxed = final_fields(run(build(ALL_ESBGK))[0], 1)
        difference = numpy.abs(relaxed - kinetic).mean(axis=1)
        amplitude = numpy.ptp(kinetic, axis=1)
        rows.append({"restitution": e,
                     **{f"difference_{k}": float(v) for k, v in zip(FIELDS, difference)},
                     **{f"range_{k}": float(v) for k, v in zip(FIELDS, amplitude)}})
        _print(rows[-1])
    return rows


def _print(row: dict) -> None:
    print(" ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                   for k, v in row.items()), flush=True)


def calibration_figure(rows: list[dict]):
    """The largest ratio over rho, u, T against the mean share of the full level, one line
    per scene through the thresholds of the middle level, and the tolerance 0.1."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
    for scene in dict.fromkeys(r["scene"] for r in rows):
        points = sorted((r["share_boltzmann"], max(r[f"ratio_{k}"] for k in FIELDS),
                         r["realizability"]) for r in rows if r["scene"] == scene)
        share, ratio, threshold = zip(*points)
        ratio = numpy.maximum(ratio, 1e-4)
        ax.plot(share, ratio, "o-", label=scene)
        for x, y, t in points:
            ax.annotate(f"{t:g}", (x, max(y, 1e-4)), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")
    ax.axhline(0.1, color="red", lw=0.8, ls="--", label="tolerance 0.1")
    ax.set_yscale("log")
    ax.set_xlabel("mean share of cells at the full level (the cost in 3D)")
    ax.set_ylabel("|hybrid - all-kinetic| / all-kinetic error\n"
                  "(max over rho, u, T; 0 drawn at 1e-4)")
    ax.set_title("accuracy against cost: the middle level's realizability threshold",
                 fontsize=9)
    ax.legend(fontsize=8)
    return fig


def level_costs(description, batch: int = 8, repeats: int = 3) -> dict:
    """Seconds per cell of the transport step (two half steps) and of each level's
    collision step, on a batch of ``batch`` cells of f0 (median of ``repeats`` after one
    warm-up)."""
    problem = Simulation(description).problem
    dt = description.time_step
    cells = problem.backend.asarray(problem.f0[:batch])
    costs = {}
    for model in problem.hierarchy.models:
        model.advance(cells.copy(), 0.0, dt)
        times = []
        for _ in range(repeats):
            began = time.perf_counter()
            model.advance(cells.copy(), 0.0, dt)
            times.append(time.perf_counter() - began)
        costs[type(model).name] = float(numpy.median(times)) / batch
    state = problem.state(problem.f0)
    times = []
    for _ in range(repeats + 1):
        began = time.perf_counter()
        problem.transport.advance(state, 0.5 * dt, 0.0)
        problem.transport.advance(state, 0.5 * dt, 0.5 * dt)
        times.append(time.perf_counter() - began)
    costs["transport"] = float(numpy.median(times[1:])) / description.space.cells
    return costs


def timing3d(out: pathlib.Path, cells: int = 40, final: float = 0.1,
             kinetic_steps: int = 3) -> tuple[dict, dict]:
    """The time per step of the 3D Sod tube at eps = 1e-3, all-kinetic (mean of its first
    steps after one) and hybrid (its whole run to ``final``), the shares of the levels, and
    the cost per cell of each level and of the transport (:func:`level_costs`)."""
    grid = {"dimension": 3, "n_modes": 24, "support_radius": 3.5}
    build = sod(1e-3)
    costs = level_costs(build(cells, {}, grid=grid, final=final))
    print("3D N = 24 seconds per cell:", costs, flush=True)
    hybrid, t_hybrid, warnings = run(build(cells, {}, grid=grid, final=final))
    steps = int(hybrid.sizes["step_time"] - 1)
    kinetic = build(cells, None, grid=grid, final=final)
    problem = Simulation(kinetic).problem
    state, dt = problem.state(problem.f0), kinetic.time_step
    problem.step(0.0, state, dt)                                  # warm-up
    began = time.perf_counter()
    for k in range(kinetic_steps):
        state = problem.step((k + 1) * dt, state, dt)
    t_kinetic = (time.perf_counter() - began) / kinetic_steps
    levels = hybrid.level.values[1:]
    names = list(hybrid.level.attrs["levels"])
    figure = plotting.figures(hybrid).get("levels")
    if figure is not None:
        save_figure(figure, out / "levels_sod3d.png")
    row = {"scene": "sod_1e-3_3d", "cells": cells, "steps": steps,
           "kinetic_step_s": t_kinetic, "hybrid_step_s": t_hybrid / steps,
           "speedup": t_kinetic * steps / t_hybrid,
           **{f"share_{n}": float((levels == k).mean()) for k, n in enumerate(names)},
           **{f"final_{n}": float((levels[-1] == k).mean()) for k, n in enumerate(names)},
           "warnings": " | ".join(sorted(set(warnings)))[:300]}
    print(" ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                   for k, v in row.items()), flush=True)
    return row, costs


def refinement(costs: dict | None, cell_counts=(50, 100, 200)) -> list[dict]:
    """The mean shares of the levels of the 2D Sod tube at eps = 1e-3 on finer meshes (the
    hybrid run only), and the speed-up they would give with the 3D per-cell ``costs``:
    (transport + boltzmann) / (transport + sum_l share_l cost_l)."""
    rows = []
    for cells in cell_counts:
        hybrid, seconds, _ = run(sod(1e-3)(cells, {}))
        names, mean, _ = _shares(hybrid)
        shares = dict(zip(names, mean.tolist()))
        row = {"cells": cells, "hybrid_s": seconds, **shares}
        if costs:
            row["projected_3d_speedup"] = (costs["transport"] + costs["boltzmann"]) / (
                costs["transport"] + sum(shares[n] * costs[n] for n in names))
        rows.append(row)
        print(" ".join(f"{k}={v:.3g}" for k, v in row.items()), flush=True)
    return rows


def markdown(rows) -> str:
    lines = ["| scene | cells | steps | error rho, u, T (C vs 2C) | hybrid - kinetic rho, u, T "
             "| ratio (max) | s/step kinetic | s/step hybrid | speed-up | mean shares | "
             "final shares |", "|" + "---|" * 11]
    for r in rows:
        names = [k[6:] for k in r if k.startswith("share_")]
        shares = ", ".join(f"{n} {r['share_' + n]:.0%}" for n in names)
        final = ", ".join(f"{n} {r['final_' + n]:.0%}" for n in names)
        if "error_rho" in r:
            error = ", ".join(f"{r['error_' + k]:.2e}" for k in FIELDS)
            difference = ", ".join(f"{r['difference_' + k]:.2e}" for k in FIELDS)
            ratio = f"{max(r['ratio_' + k] for k in FIELDS):.3f}"
        else:
            error = difference = ratio = "-"
        lines.append(f"| {r['scene']} | {r['cells']} | {r['steps']} | {error} | {difference} "
                     f"| {ratio} | {r['kinetic_step_s']:.3g} | {r['hybrid_step_s']:.3g} | "
                     f"{r['speedup']:.2f} | {shares} | {final} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, type=pathlib.Path)
    parser.add_argument("--scenes", type=name_list(tuple(SCENES)), default=list(DEFAULT_SCENES),
                        help="comma-separated: " + ", ".join(SCENES))
    parser.add_argument("--thresholds", type=numbers(0.0), default=[],
                        help="middle-level realizability thresholds to calibrate, e.g. "
                             "0.05,0.03,0.01")
    parser.add_argument("--timing3d", action="store_true")
    parser.add_argument("--refinement", action="store_true")
    parser.add_argument("--model-error", action="store_true",
                        help="the ES-BGK level everywhere on the shear scene, e = 0.97 and 1")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    began = time.perf_counter()
    rows, calibration = [], []
    for name in args.scenes:
        row, more = scene_row(name, args.out, args.thresholds)
        rows.append(row)
        calibration += more
    costs = None
    if args.timing3d:
        row, costs = timing3d(args.out)
        rows.append(row)
    if rows:
        write_csv(args.out / "hierarchy.csv", rows, fields=sorted({k for r in rows for k in r}))
    table = markdown(rows)
    if costs:
        table += ("\n3D N = 24, seconds per cell and step: "
                  + ", ".join(f"{k} {v:.3g}" for k, v in costs.items()) + "\n")
    if calibration:
        write_csv(args.out / "hierarchy_calibration.csv", calibration,
                  fields=sorted({k for r in calibration for k in r}))
        save_figure(calibration_figure(calibration), args.out / "calibration.png")
        table += ("\n| scene | realizability (middle) | ratio rho, u, T | mean share "
                  "boltzmann |\n|---|---|---|---|\n")
        for r in calibration:
            table += (f"| {r['scene']} | {r['realizability']:g} | "
                      + ", ".join(f"{r['ratio_' + k]:.3f}" for k in FIELDS)
                      + f" | {r['share_boltzmann']:.0%} |\n")
    if args.model_error:
        errors = model_error()
        write_csv(args.out / "hierarchy_model_error.csv", errors)
        table += ("\n| e | all-esbgk - all-kinetic rho, u_2, T | range of rho, u_2, T |\n"
                  "|---|---|---|\n")
        for r in errors:
            table += (f"| {r['restitution']:g} | "
                      + ", ".join(f"{r['difference_' + k]:.2e}" for k in FIELDS) + " | "
                      + ", ".join(f"{r['range_' + k]:.2e}" for k in FIELDS) + " |\n")
    if args.refinement:
        finer = refinement(costs)
        write_csv(args.out / "hierarchy_refinement.csv", finer)
        names = [k for k in finer[0] if k not in ("cells", "hybrid_s", "projected_3d_speedup")]
        table += ("\n| cells | " + " | ".join(f"mean share {n}" for n in names)
                  + " | projected 3D speed-up |\n|" + "---|" * (len(names) + 2) + "\n")
        for r in finer:
            table += (f"| {r['cells']} | " + " | ".join(f"{r[n]:.0%}" for n in names)
                      + f" | {r.get('projected_3d_speedup', float('nan')):.2f} |\n")
    (args.out / "hierarchy.md").write_text(table)
    print(table)
    print(f"wall time {time.perf_counter() - began:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
