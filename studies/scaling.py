"""Strong and weak scaling of a space run over MPI processes, and a model of the step.

Each configuration is a periodic box of hard spheres (3D velocities, the fast spectral
operator with its default quadrature, a density wave so that the cells differ), MUSCL,
explicit SSP RK2 collisions at Knudsen number 1, one thread per process. For 1 and 2
processes (``mpiexec -n P``, the pip-installed MPICH) the study times:

- the step and its record (one Strang step, the reduction of the totals), the median of
  ``--steps`` steps after a warm-up step, on process 0 (the processes wait for each
  other at every halo and at the reduction, so it is the step of the slowest);
- the halo exchange per step (:class:`granframe.parallel.Halo`: posting and completing
  the six exchanges of ghost cells, the part not hidden behind the local ghost fills)
  and the reduction per step (``SpaceProblem.reduction_seconds``), each the largest over
  the processes;
- the commit of a snapshot into the one store (:meth:`RunStore.commit_together`), in a
  short run of the same description written to disk;
- the point-to-point latency and bandwidth between two processes (ping-pong of 8 bytes
  and of one ghost message).

Strong scaling: the same cells on 1 and 2 processes; weak: 32 cells on each. Each
process is bound to a core (Hydra's ``-bind-to core``). Runs alternate between 1 and 2
processes, ``--repeats`` times; the tables give the medians over the runs of each run's
median step, and the best (least disturbed) step. The model of the time per step on P processes,

    T(P) = t_cell * n(P) + 6 (alpha + b / beta) + alpha_c * ceil(log2 P) + T_commit / K,

with t_cell the measured time per cell and step, n(P) the most cells a process owns
(whole store chunks), b the bytes of one ghost message (ghost x N^d x 8), alpha and beta
the latency and bandwidth of the network, alpha_c that of a collective step and K the
steps between commits, predicts the efficiency T(1) / (P T(P)) at 8, 64 and 512
processes (docs/scaling.md).

    python studies/scaling.py --out DIR [--steps 5] [--repeats 3]

writes ``scaling.json`` and ``scaling.md`` to DIR and prints the tables. Run it on a
quiet machine: every process takes one core.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy

from granframe.tools.studykit import finish, number

#: the configurations: (name, dimension, n_modes, cells on one process)
STRONG = ("strong", 3, 16, 64)
#: the cells of each process in the weak scaling
WEAK_CELLS = 32
#: one thread per process: the BLAS and OpenMP pools too
SINGLE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                         "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}


def description(dimension: int, n_modes: int, cells: int, steps: int = 2,
                block_cells: int | None = None, backend: str = "numpy"):
    """The timed space run (see the module notes): ``steps`` steps of dt = 0.002, one
    snapshot per step, on ``backend`` (one thread on the CPU)."""
    from granframe.run.description import RunDescription

    dt = 0.002
    return RunDescription.from_dict({
        "final_time": steps * dt, "time_step": dt,
        "grid": {"dimension": dimension, "n_modes": n_modes, "support_radius": 3.2},
        "kernel": "hard_spheres", "restitution": {"name": "constant", "value": 0.9},
        "initial": {"name": "sinusoidal_mode", "field": "density", "amplitude": 0.2},
        "operator": "fast_spectral", "integrator": "ssp_rk2",
        "backend": {"name": backend, "threads": 1} if backend != "cupy" else "cupy",
        "space": {"cells": cells, "left": "periodic", "right": "periodic",
                  **({} if block_cells is None else {"block_cells": block_cells})},
        "output": {"snapshot_interval": dt},
    })


def ping_pong(communicator, nbytes: int, repeats: int) -> float:
    """Half the median round trip of ``nbytes`` between processes 0 and 1 (seconds)."""
    comm = communicator.comm
    buffer = numpy.zeros(max(nbytes // 8, 1))
    times = []
    for _ in range(repeats):
        comm.Barrier()
        began = time.perf_counter()
        if communicator.rank == 0:
            comm.Send(buffer, dest=1, tag=7)
            comm.Recv(buffer, source=1, tag=7)
        elif communicator.rank == 1:
            comm.Recv(buffer, source=0, tag=7)
            comm.Send(buffer, dest=0, tag=7)
        times.append(time.perf_counter() - began)
    return 0.5 * statistics.median(times)


def worker(config: dict) -> None:
    """One timed run on the processes this one was launched with; process 0 prints a JSON
    line of the measurements."""
    from granframe.parallel import world
    from granframe.run import storage
    from granframe.run.runner import Simulation

    communicator = world()
    d = description(config["dimension"], config["n_modes"], config["cells"],
                    backend=config.get("backend", "numpy"))
    simulation = Simulation(d, communicator=communicator)
    problem = simulation.problem
    dt = d.time_step
    state = problem.state(problem.f0)
    state = problem.step(0.0, state, dt)          # plans and caches fill here
    problem.record(state)
    halo = problem.domain.neighbours
    if halo is not None:
        halo.seconds = 0.0
    problem.reduction_seconds = 0.0
    steps, times = config["steps"], []
    for k in range(steps):
        began = time.perf_counter()
        state = problem.step(k * dt, state, dt)
        problem.record(state)
        times.append(time.perf_counter() - began)
    halo_seconds = (halo.seconds if halo is not None else 0.0) / steps
    reduction_seconds = problem.reduction_seconds / steps
    exchange_seconds = None
    if halo is not None:        # the exchange alone: no compute between, so no waiting
        transport, repeats = problem.transport, 50
        communicator.allgather_object(None)
        began = time.perf_counter()
        for _ in range(repeats):
            problem.domain.exchange(state, transport.left, transport.right, 0.0)
        exchange_seconds = (time.perf_counter() - began) / repeats
    commits = []
    original = storage.RunStore.commit_together

    def timed(self, *args, **kwargs):
        began = time.perf_counter()
        original(self, *args, **kwargs)
        commits.append(time.perf_counter() - began)

    storage.RunStore.commit_together = timed
    folder = communicator.bcast(tempfile.mkdtemp(prefix="scaling-")
                                if communicator.rank == 0 else None)
    simulation.run(pathlib.Path(folder) / "run.zarr", progress=False)
    storage.RunStore.commit_together = original
    latency = bandwidth = None
    if communicator.size == 2:
        nbytes = problem.reconstruction.ghost * d.grid.n_modes ** d.grid.dimension * 8
        latency = ping_pong(communicator, 8, 200)
        bandwidth = nbytes / max(ping_pong(communicator, nbytes, 50) - latency, 1e-9)
    parts = communicator.allgather_object((halo_seconds, reduction_seconds, exchange_seconds))
    if communicator.rank == 0:
        shutil.rmtree(folder, ignore_errors=True)
        print(json.dumps({
            **config, "processes": communicator.size,
            "step_seconds": statistics.median(times), "steps_timed": steps,
            "step_times": times,
            "halo_seconds": max(p[0] for p in parts),
            "reduction_seconds": max(p[1] for p in parts),
            "exchange_seconds": None if exchange_seconds is None else max(p[2] for p in parts),
            "commit_seconds": statistics.median(commits[1:]) if len(commits) > 1
            else commits[0],
            "ghost_bytes": problem.reconstruction.ghost * d.grid.n_modes ** d.grid.dimension * 8,
            "ranges": [list(r) for r in problem.ranges],
            "latency": latency, "bandwidth": bandwidth}), flush=True)


def launch(config: dict, processes: int) -> dict:
    """Run :func:`worker` on ``processes`` processes and return its measurements."""
    mpiexec = shutil.which("mpiexec", path=str(pathlib.Path(sys.executable).parent)) \
        or shutil.which("mpiexec")
    command = [mpiexec, "-bind-to", "core", "-n", str(processes), sys.executable, __file__,
               "--worker", json.dumps(config)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=3600,
                          env={**os.environ, **SINGLE_THREAD})
    if done.returncode:
        raise RuntimeError(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


#: the network and store of the predictions (assumed, not measured here): an InfiniBand
#: HDR cluster (latency 2 us, 12 GB/s per message, 3 us per stage of a collective), a
#: commit every 100 steps
CLUSTER = {"latency": 2e-6, "bandwidth": 12e9, "collective": 3e-6, "steps_per_commit": 100}
#: a GPU per process: the host-staged ghost cells cross PCIe twice per message (25 GB/s,
#: 10 us per copy and synchronisation); with a CUDA-aware MPI they do not
PCIE = {"bandwidth": 25e9, "latency": 10e-6}
#: time per evaluation of the fast operator in 3D on one GPU (the review's Table: a GTX
#: 2080 Ti, N_rho = 30, M = 32), the per-cell cost of a GPU in the predictions
GPU_EVALUATION = {16: 5.97e-3, 32: 12.1e-3}
#: the collision evaluations of one step (SSP RK2)
EVALUATIONS = 2
#: the predicted runs: (name, n_modes, cells)
PREDICTED = (("64 cells, N = 16", 16, 64), ("512 cells, N = 32", 32, 512))


def model(t_cell: float, processes: int, cells: int, ghost_bytes: float, commit: float,
          staged: bool = False, network=CLUSTER) -> float:
    """T(P) of the module notes, seconds per step on ``processes`` processes owning whole
    cells (store chunks of one cell); ``staged``: the ghost cells also cross PCIe twice
    (a GPU per process without a CUDA-aware MPI)."""
    owned = math.ceil(cells / processes)
    message = network["latency"] + ghost_bytes / network["bandwidth"]
    if staged:
        message += 2.0 * (PCIE["latency"] + ghost_bytes / PCIE["bandwidth"])
    halo = 6.0 * message if processes > 1 else 0.0
    reduction = network["collective"] * math.ceil(math.log2(processes)) if processes > 1 \
        else 0.0
    return t_cell * owned + halo + reduction + commit / network["steps_per_commit"]


def predictions(t_cell: dict, commit: float) -> list[dict]:
    """The efficiency T(1) / (P T(P)) of :data:`PREDICTED` at 8, 64 and 512 processes, on
    CPUs (``t_cell`` measured per N) and on GPUs (host-staged and CUDA-aware ghosts)."""
    rows = []
    for name, n_modes, cells in PREDICTED:
        ghost_bytes = 2 * n_modes ** 3 * 8          # MUSCL: 2 ghost cells
        for device, cost, staged in (("CPU core", t_cell[n_modes], False),
                                     ("GPU, staged", EVALUATIONS * GPU_EVALUATION[n_modes], True),
                                     ("GPU, CUDA-aware", EVALUATIONS * GPU_EVALUATION[n_modes],
                                      False)):
            one = model(cost, 1, cells, ghost_bytes, commit, staged)
            row = {"case": name, "device": device, "t_cell": cost}
            for processes in (8, 64, 512):
                if processes > cells:
                    row[processes] = None
                    continue
                step = model(cost, processes, cells, ghost_bytes, commit, staged)
                compute = cost * math.ceil(cells / processes)
                communication = step - compute - commit / CLUSTER["steps_per_commit"]
                row[processes] = {"efficiency": one / (processes * step),
                                  "step": step, "communication": communication / step}
            rows.append(row)
    return rows


def table(rows, columns) -> str:
    """A Markdown table of ``rows`` (dicts) with ``columns`` (key, heading, format)."""
    lines = ["| " + " | ".join(h for _, h, _ in columns) + " |",
             "|" + "|".join("---" for _ in columns) + "|"]
    for row in rows:
        lines.append("| " + " | ".join("-" if row[k] is None else f.format(row[k])
                                       for k, _, f in columns) + " |")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path)
    parser.add_argument("--steps", type=number(1, kind=int, low_open=False), default=5)
    parser.add_argument("--repeats", type=number(1, kind=int, low_open=False), default=3)
    parser.add_argument("--backend", default="numpy", help="array backend of the runs "
                        "(cupy: one GPU per process)")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(json.loads(args.worker))
        return
    name, dimension, n_modes, cells = STRONG
    runs = {"strong": [], "weak": []}
    for _ in range(args.repeats):          # interleaved: 1 then 2 processes, each time
        for processes in (1, 2):
            base = {"dimension": dimension, "n_modes": n_modes, "steps": args.steps,
                    "backend": args.backend}
            runs["strong"].append(launch({**base, "cells": cells}, processes))
            runs["weak"].append(launch({**base, "cells": WEAK_CELLS * processes}, processes))
    rows = []
    for kind, measured in runs.items():
        for processes in (1, 2):
            of = [m for m in measured if m["processes"] == processes]
            row = {"kind": kind, "processes": processes, "cells": of[0]["cells"]}
            for key in ("step_seconds", "halo_seconds", "reduction_seconds", "commit_seconds"):
                row[key] = statistics.median(m[key] for m in of)
            row["best_step"] = min(min(m["step_times"]) for m in of)
            row["exchange_seconds"] = (None if processes == 1 else
                                       statistics.median(m["exchange_seconds"] for m in of))
            row["messages_share"] = (None if processes == 1 else
                                     (6 * row["exchange_seconds"] + row["reduction_seconds"])
                                     / row["step_seconds"])
            row["halo_share"] = (row["halo_seconds"] + row["reduction_seconds"]) \
                / row["step_seconds"]
            rows.append(row)
    for kind in ("strong", "weak"):
        one, two = [r for r in rows if r["kind"] == kind]
        ratio = one["step_seconds"] / two["step_seconds"]
        best = one["best_step"] / two["best_step"]
        two["speedup"] = ratio if kind == "strong" else None
        two["efficiency"] = ratio / 2.0 if kind == "strong" else ratio
        two["best_speedup"] = best if kind == "strong" else None
        two["best_efficiency"] = best / 2.0 if kind == "strong" else best
        one["speedup"] = one["efficiency"] = one["best_speedup"] = one["best_efficiency"] = 1.0
    pairs = [m for m in runs["strong"] if m["processes"] == 2]
    latency = statistics.median(m["latency"] for m in pairs)
    bandwidth = statistics.median(m["bandwidth"] for m in pairs)
    one = next(r for r in rows if r["kind"] == "strong" and r["processes"] == 1)
    measured = {"t_cell": one["step_seconds"] / cells, "latency": latency,
                "bandwidth": bandwidth, "commit": one["commit_seconds"]}
    large = launch({"dimension": 3, "n_modes": 32, "steps": 2, "cells": 5,
                    "backend": args.backend}, 1)
    t_cell = {16: measured["t_cell"], 32: large["step_seconds"] / large["cells"]}
    measured["t_cell_32"] = t_cell[32]
    predicted = predictions(t_cell, max(r["commit_seconds"] for r in rows))

    def cell(value):
        return "-" if value is None else (f"{value['efficiency']:.3f} ({value['step']:.3g} s, "
                                          f"{value['communication']:.1%})")

    report = {"rows": rows, "measured": measured, "runs": runs, "predictions": predicted}
    text = ["## Measured (this machine, one thread per process)", "",
            table(rows, [("kind", "scaling", "{}"), ("processes", "P", "{}"),
                         ("cells", "cells", "{}"), ("step_seconds", "step (s)", "{:.4g}"),
                         ("speedup", "speed-up", "{:.3g}"),
                         ("efficiency", "efficiency", "{:.3g}"),
                         ("best_step", "best step (s)", "{:.4g}"),
                         ("best_speedup", "best speed-up", "{:.3g}"),
                         ("best_efficiency", "best efficiency", "{:.3g}"),
                         ("halo_seconds", "halo (s/step)", "{:.2e}"),
                         ("reduction_seconds", "reduction (s/step)", "{:.2e}"),
                         ("halo_share", "halo + reduction share", "{:.2%}"),
                         ("exchange_seconds", "one exchange alone (s)", "{:.2e}"),
                         ("messages_share", "6 exchanges + reduction share", "{:.3%}"),
                         ("commit_seconds", "commit (s)", "{:.3g}")]),
            "", f"t_cell = {measured['t_cell']:.4g} s per cell and step (3D N = {n_modes}); "
            f"ping-pong latency {latency * 1e6:.3g} us, bandwidth {bandwidth / 1e9:.3g} GB/s "
            "(shared memory).", "",
            "## Predicted efficiency T(1) / (P T(P)) (step time, communication share)", "",
            f"CPU cores: t_cell measured here (N = 32: {t_cell[32]:.3g} s per cell and step); "
            "GPUs: the review's time per evaluation, x 2 evaluations per step; network "
            f"{CLUSTER}.", "",
            table([{**row, **{p: cell(row[p]) for p in (8, 64, 512)}} for row in predicted],
                  [("case", "case", "{}"), ("device", "per process", "{}"),
                   ("t_cell", "t_cell (s)", "{:.3g}")]
                  + [(p, f"P = {p}", "{}") for p in (8, 64, 512)])]
    print("\n".join(text))
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "scaling.json").write_text(json.dumps(report, indent=1, default=str))
        (args.out / "scaling.md").write_text("\n".join(text) + "\n")


if __name__ == "__main__":
    raise SystemExit(finish(main))
