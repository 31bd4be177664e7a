"""A model of the step of a run on a rectangle over P_x x P_y processes, and its prediction
at 8, 64 and 512 processes and GPUs (docs/scaling.md, "Two space dimensions").

A process owns a block of n_x x n_y cells (:func:`granframe.parallel.process_grid`: the
factorisation of P whose cuts cross the fewest cell faces, whole store chunks of one
cell here) and exchanges, in each of the six transport stages of a step (two half steps
of three SSP RK3 stages), one strip of ``ghost`` cells with each neighbour along each
axis that is cut: the message along x holds ghost x n_y distributions of N^d float64,
along y ghost x n_x. The time per step

    T(P) = t_cell n_x n_y + 6 sum_{a cut} (alpha + b_a / beta) + alpha_c ceil(log2 P)
           + T_commit / K,

the halo surface (b_a, proportional to the block's side) against the block's volume
(n_x n_y), with the network of ``studies/scaling.py`` (InfiniBand HDR, assumed: alpha =
2 us, beta = 12 GB/s, 3 us per collective stage, a commit every K = 100 steps of
T_commit = 0.24 s measured on the line) and t_cell measured here: the step of a rectangle
of 8 x 8 cells on one process (one thread, the median of ``--steps`` steps after one) per
cell, for 2D velocities N = 32 and 3D N = 16 (MUSCL, the fast operator, SSP RK2 at
Knudsen number 1). A GPU's t_cell is the review's time per 3D N = 16 evaluation on one
GPU (GTX 2080 Ti: 5.97 ms) times the step's 4 evaluations, an upper bound (a device
batching a block of cells takes less per cell); its ghost strips cross PCIe twice when the
MPI is not CUDA-aware. No GPU figure is published for 2D N = 32; that case is predicted
for CPU cores only.

    python studies/scaling_2d.py --out DIR [--steps 3]

writes ``scaling_2d.json`` and ``scaling_2d.md``. Run it on a quiet machine.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import statistics
import time

from granframe.parallel import process_grid
from granframe.tools.studykit import finish, number

#: assumed network and store (``studies/scaling.py``)
CLUSTER = {"latency": 2e-6, "bandwidth": 12e9, "collective": 3e-6, "steps_per_commit": 100}
PCIE = {"bandwidth": 25e9, "latency": 10e-6}
COMMIT = 0.24
#: the review's time per 3D N = 16 evaluation on one GPU, and the evaluations per step
GPU_EVALUATION_3D16 = 5.97e-3
EVALUATIONS = 4
GHOST = 2
#: the predicted runs: (name, velocity dimension, N, cells along x and y)
PREDICTED = (("256 x 256 cells, 2D N = 32", 2, 32, (256, 256)),
             ("64 x 64 cells, 3D N = 16", 3, 16, (64, 64)),
             ("512 x 128 cells, 3D N = 16", 3, 16, (512, 128)))


def measure(dimension: int, n_modes: int, steps: int) -> float:
    """Seconds per cell and step on one process and thread: a sine mode on a periodic
    8 x 8 rectangle, the median of ``steps`` steps after one."""
    from granframe.run.description import RunDescription
    from granframe.run.runner import Simulation
    from granframe.space.transport import box_step_limit
    from granframe.velocity.grid import VelocityGrid

    grid = {"dimension": dimension, "n_modes": n_modes, "support_radius": 3.5}
    dt = 0.9 * box_step_limit(VelocityGrid(**grid), (1 / 8, 1 / 8), 0.5)
    d = RunDescription.from_dict({
        "title": "t_cell", "grid": grid, "kernel": "maxwell",
        "restitution": {"name": "constant", "value": 0.9},
        "initial": {"name": "sinusoidal_mode", "mode": [1, 1], "amplitude": 0.2},
        "operator": {"name": "fast_spectral"}, "backend": {"name": "pyfftw", "threads": 1},
        "integrator": "ssp_rk2", "knudsen": 1.0, "time_step": dt, "final_time": dt,
        "space": {"cells": [8, 8]}})
    problem = Simulation(d).problem
    state = problem.state(problem.f0)
    state = problem.step(0.0, state, dt)
    times = []
    for k in range(steps):
        began = time.perf_counter()
        state = problem.step((k + 1) * dt, state, dt)
        problem.record(state)
        times.append(time.perf_counter() - began)
    return statistics.median(times) / 64


def model(t_cell: float, processes: int, cells, n_modes: int, dimension: int,
          staged: bool = False) -> dict:
    """T(P) of the module notes and its parts: the block, the compute, the messages."""
    counts = process_grid(processes, cells, (1, 1), GHOST)
    block = [math.ceil(c / p) for c, p in zip(cells, counts)]
    distribution = n_modes ** dimension * 8
    messages = 0.0
    for axis, cut in enumerate(counts):
        if cut == 1:
            continue
        size = GHOST * block[1 - axis] * distribution
        message = CLUSTER["latency"] + size / CLUSTER["bandwidth"]
        if staged:
            message += 2.0 * (PCIE["latency"] + size / PCIE["bandwidth"])
        messages += 6.0 * message
    reduction = CLUSTER["collective"] * math.ceil(math.log2(processes)) if processes > 1 \
        else 0.0
    compute = t_cell * block[0] * block[1]
    step = compute + messages + reduction + COMMIT / CLUSTER["steps_per_commit"]
    return {"grid": list(counts), "block": block, "compute": compute,
            "communication": messages + reduction, "step": step}


def predictions(t_cell: dict) -> list[dict]:
    rows = []
    for name, dimension, n_modes, cells in PREDICTED:
        devices = [("CPU core", t_cell[(dimension, n_modes)], False)]
        if (dimension, n_modes) == (3, 16):
            cost = EVALUATIONS * GPU_EVALUATION_3D16
            devices += [("GPU, staged", cost, True), ("GPU, CUDA-aware", cost, False)]
        for device, cost, staged in devices:
            one = model(cost, 1, cells, n_modes, dimension, staged)["step"]
            row = {"case": name, "device": device, "t_cell": cost}
            for processes in (8, 64, 512):
                part = model(cost, processes, cells, n_modes, dimension, staged)
                row[processes] = {**part, "efficiency": one / (processes * part["step"]),
                                  "share": part["communication"] / part["step"]}
            rows.append(row)
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--steps", type=number(1, kind=int, low_open=False), default=3)
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    t_cell = {(2, 32): measure(2, 32, args.steps), (3, 16): measure(3, 16, args.steps)}
    print({f"{d}D N = {n}": v for (d, n), v in t_cell.items()}, flush=True)
    rows = predictions(t_cell)
    lines = ["| case | per process | t_cell (s) | P = 8 | P = 64 | P = 512 |",
             "|---|---|---|---|---|---|"]
    for row in rows:
        cells = []
        for processes in (8, 64, 512):
            p = row[processes]
            cells.append(f"{p['efficiency']:.3f} ({p['grid'][0]}x{p['grid'][1]}, blocks "
                         f"{p['block'][0]}x{p['block'][1]}, {p['step']:.3g} s, "
                         f"{p['share']:.1%})")
        lines.append(f"| {row['case']} | {row['device']} | {row['t_cell']:.3g} | "
                     + " | ".join(cells) + " |")
    text = ("t_cell measured here (one process, one thread): "
            + ", ".join(f"{d}D N = {n}: {v:.3g} s" for (d, n), v in t_cell.items())
            + "\n\n" + "\n".join(lines) + "\n")
    (args.out / "scaling_2d.md").write_text(text)
    (args.out / "scaling_2d.json").write_text(json.dumps(
        {"t_cell": {f"{d}_{n}": v for (d, n), v in t_cell.items()}, "rows": rows},
        indent=1))
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(finish(main))
