"""``granframe bench``: time one evaluation of a collision operator against the FFT floor.

Each configuration runs in a fresh subprocess so that its peak resident memory
is its own. Reported per configuration: precomputation time, the median of
``repeats`` evaluations after one warm-up, the FFT floor -- the median time of
one real forward + inverse transform of a batch of B grids of size N^d (B the
operator's own batch of pairs) on the same backend and threads, times P/B for
the P (rho, ghat) pairs the operator transforms -- the ratio time/floor, the
peak resident set size of the process, and the device memory of device backends.
Batching the floor as the operator batches keeps it a floor on a GPU, where one
small transform alone is bound by its launch, not by the transform.

With a stack size D (``--batch D``) the operator evaluates a stack of D distinct
distributions at once; reported per distribution are the time of that evaluation / D
and the floor of the same batched transforms: the median time of one forward + inverse
transform of the T = D max(1, B / D) grids of one pipeline call
(:meth:`~granframe_spectral.FastSpectral.stack_transforms`), times D P / T calls, / D,
i.e. ``fft_batch_s * P / T``. D = 1 is the floor above (T = B).

With ``quadrature`` (``--quadrature auto review``) a configuration D:N is timed with the
rules the operator takes from that preset of its ``quadrature`` option (the default ``auto``,
chosen from the grid, or the review's), instead of the configuration's N_rho and M; the
record gives the rules taken.

Evaluations and floor are timed in alternating rounds (one evaluation, then the floor's
ceil(D P / T) transform calls), so that a machine whose speed drifts between minutes
moves both medians together instead of the ratio.
"""

from __future__ import annotations

import inspect
import json
import math
import resource
import subprocess
import sys
import time

import numpy

from granframe import validators as check
from granframe.registry import default_registries

#: Largest stack size D of ``--batch``.
MAX_BATCH = 4096

#: The review's configurations (section 3): (dimension, N, N_rho, M).
DEFAULT_CONFIGS = ((2, 64, 32, 16), (2, 128, 32, 16), (3, 16, 30, 32), (3, 32, 30, 32),
                   (3, 64, 30, 32))


def peak_rss_kib() -> int:
    """Peak resident set size of this process in KiB: ``VmHWM`` of /proc/self/status where
    there is one (Linux), else ``ru_maxrss``. On Linux ``ru_maxrss`` survives fork + exec,
    so a configuration's subprocess would report its parent's peak when that is larger
    (``granframe bench`` at 0.19 GiB against 0.08 GiB of the subprocess's own)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def median_time(function, repeats: int, backend) -> float:
    """Median of ``repeats`` timings of ``function`` by ``backend.elapsed`` (host clock with
    synchronisation, or device events on a GPU)."""
    return float(numpy.median([backend.elapsed(function) for _ in range(repeats)]))


def measure(dimension: int, n_modes: int, radial_points: int, sphere_points: int,
            backend: str, threads: int, repeats: int, method: str = "fast_spectral",
            precision: str = "float64", options: dict | None = None,
            distributions: int = 1, quadrature: str | None = None) -> dict:
    """Build and time one operator in this process; returns a JSON-ready record.
    ``options`` are further parameters of the array backend (e.g. ``{"fused": False}``);
    ``distributions`` D > 1 times stacks of D distributions, per distribution (module
    notes); ``quadrature`` (``auto`` or ``review``) takes the rules of that preset instead
    of ``radial_points`` and ``sphere_points``."""
    import granframe as gf

    baseline = peak_rss_kib()
    grid = gf.VelocityGrid(dimension, n_modes, 4.0)
    array_backend = _array_backend(backend, threads, options)
    rules = _rules(dimension, radial_points, sphere_points, quadrature)
    start = time.perf_counter()
    operator = gf.collision_operator(method, grid, gf.collision_kernel("hard_spheres"),
                                     gf.restitution_law("constant", value=0.8),
                                     backend=array_backend, **rules,
                                     **({} if precision == "float64" else {"precision": precision}))
    precompute = time.perf_counter() - start
    f = _distributions(grid, array_backend, distributions)
    transforms = operator.stack_transforms(distributions)
    floor_round, calls = _floor_round(operator, grid, array_backend, f, distributions,
                                      transforms, threads, precision)
    evaluation, single = _alternating_medians(operator, f, floor_round, calls, repeats,
                                              distributions, array_backend)
    batch = operator.batch
    floor = single * operator.transform_pairs / transforms
    peak = peak_rss_kib()
    device = array_backend.device_memory()
    return {
        "dimension": dimension, "n_modes": n_modes, "radial_points": operator.radial_points,
        "sphere_points": operator.sphere.n_points, "quadrature": quadrature,
        "sphere_rule": _rule_name(operator.sphere), "method": method, "backend": backend,
        "threads": threads,
        "precision": precision, "backend_options": options or {},
        "transform_pairs": operator.transform_pairs, "batch": batch,
        "distributions": distributions, "stack_transforms": transforms,
        "precompute_s": precompute,
        "evaluation_s": evaluation, "repeats": repeats, "fft_batch_s": single, "floor_s": floor,
        "time_over_floor": evaluation / floor, "peak_rss_gib": peak / 2 ** 20,
        "baseline_rss_gib": baseline / 2 ** 20,
        "device_memory_gib": None if device is None else device / 2 ** 30,
    }


def _array_backend(backend: str, threads: int, options: dict | None):
    """The array backend ``backend`` with ``options``, and ``threads`` if it takes them."""
    import granframe as gf

    factory = gf.default_registries().get("array_backends", backend).factory
    takes_threads = "threads" in inspect.signature(factory).parameters
    return gf.array_backend(backend, **({"threads": threads} if takes_threads else {}),
                            **(options or {}))


def _rules(dimension: int, radial_points: int, sphere_points: int,
           quadrature: str | None) -> dict:
    """The operator's quadrature options: the preset ``quadrature``, or N_rho and the
    sphere rule of M points (the circle's trapezoid rule in 2D, the Gauss product rule of
    M = 2 n^2 points in 3D)."""
    from granframe.velocity.quadratures import CircleTrapezoid, SphereProduct

    if quadrature is not None:
        return {"quadrature": quadrature}
    if dimension == 2:
        return {"radial_points": radial_points, "sphere": CircleTrapezoid(sphere_points)}
    n_polar = int(round((sphere_points / 2) ** 0.5))
    if 2 * n_polar ** 2 != sphere_points:
        raise ValueError(f"bench: parameter 'sphere_points' = {sphere_points} is invalid; "
                         "in 3D it must be 2 n^2 (Gauss product rule), e.g. 32")
    return {"radial_points": radial_points, "sphere": SphereProduct(n_polar)}


def _distributions(grid, array_backend, distributions: int):
    """What the operator evaluates: the Maxwellian of T = 1, or a stack of D distinct ones
    (temperatures 0.8 to 1.2)."""
    if distributions == 1:
        return array_backend.asarray(grid.maxwellian(temperature=1.0))
    return array_backend.asarray(numpy.stack([
        grid.maxwellian(temperature=t) for t in numpy.linspace(0.8, 1.2, distributions)]))


def _floor_round(operator, grid, array_backend, f, distributions: int, transforms: int,
                 threads: int, precision: str):
    """One round of the FFT floor (module notes) and its number of transform calls: as
    many forward + inverse transforms of the operator's batch of ``transforms`` grids as
    one evaluation makes (at least one)."""
    fft = array_backend.real_fft((transforms,) + grid.shape,
                                 tuple(range(1, grid.dimension + 1)), threads=threads,
                                 precision=precision)
    fft.real[...] = f.reshape((-1,) + grid.shape)[:1]
    calls = max(1, math.ceil(distributions * operator.transform_pairs / transforms))

    def floor_round():
        for _ in range(calls):
            fft.forward()
            fft.inverse()

    return floor_round, calls


def _alternating_medians(operator, f, floor_round, calls: int, repeats: int,
                         distributions: int, array_backend) -> tuple[float, float]:
    """The medians of ``repeats`` evaluations per distribution and of ``repeats`` floor
    rounds per transform call, after one warm-up of each.

    They are timed in alternating blocks, so that both medians come from the same minutes
    of a machine whose speed drifts; an evaluation right after a floor round is not timed:
    FFTW's threads keep spinning after it and took a core from the operator (2D N = 64:
    10.5 ms against 5.8 ms)."""
    operator(f)
    floor_round()
    array_backend.synchronize()
    evaluations, pair_times = [], []
    blocks = min(repeats, 2)
    for block in range(blocks):
        count = repeats // blocks + (1 if block < repeats % blocks else 0)
        operator(f)
        array_backend.synchronize()
        for _ in range(count):
            evaluations.append(array_backend.elapsed(lambda: operator(f)) / distributions)
        for _ in range(count):
            pair_times.append(array_backend.elapsed(floor_round) / calls)
    return float(numpy.median(evaluations)), float(numpy.median(pair_times))


def check_options(backend: str, threads: int, repeats: int) -> None:
    """Refuse a backend that is not registered, ``threads`` outside 1..MAX_THREADS and
    ``repeats`` < 1 (a median of no timings is NaN), before any subprocess starts."""
    from granframe.backends import MAX_THREADS
    from granframe.registry import default_registries, did_you_mean

    names = default_registries().names("array_backends")
    if backend not in names:
        check.reject("bench", "backend", backend,
                     f"must be a registered array backend: {', '.join(names)}"
                     f"{did_you_mean(backend, names)}")
    if not check.is_integer(threads) or not 1 <= threads <= MAX_THREADS:
        check.reject("bench", "threads", threads, f"must be an integer >= 1 and <= {MAX_THREADS}")
    if not check.is_integer(repeats) or repeats < 1:
        check.reject("bench", "repeats", repeats, "must be an integer >= 1 (the time is the "
                     "median of that many evaluations)")


def run(configs, backend: str, threads: int, repeats: int,
        precision: str = "float64", options: dict | None = None,
        batches=(1,), quadratures=(None,)) -> list[dict]:
    """Measure each configuration, for each quadrature of ``quadratures`` and each stack
    size D of ``batches``, in its own subprocess (``options``, D, a quadrature: see
    :func:`measure`; ``None`` times the configuration's own N_rho and M); records in the
    order configuration, quadrature, then D.

    The options, every configuration, every quadrature (``None`` or a value of
    fast_spectral's ``quadrature``) and every D (an integer >= 1) are checked first
    (:func:`check_options`, :func:`check_config`); a configuration that fails in its
    subprocess is reported by its last line, the error, not by the subprocess's traceback.
    """
    fast = default_registries().get("collision_operators", "fast_spectral").factory
    quadrature_names = getattr(fast, "quadratures", ())
    check_options(backend, threads, repeats)
    for config in configs:
        check_config(config)
    for stack in batches:
        if not check.is_integer(stack) or not 1 <= stack <= MAX_BATCH:
            check.reject("bench", "batch", stack, f"must be an integer >= 1 and <= {MAX_BATCH}")
    for quadrature in quadratures:
        if quadrature is not None and quadrature not in quadrature_names:
            check.reject("bench", "quadrature", quadrature,
                         f"must be one of {', '.join(quadrature_names)}")
    records = []
    for dimension, n_modes, radial, sphere in configs:
        for quadrature in quadratures:
            for stack in batches:
                command = [sys.executable, "-c",
                           "import json, sys; from granframe.tools.bench import measure; "
                           f"print(json.dumps(measure({dimension}, {n_modes}, {radial}, "
                           f"{sphere}, {backend!r}, {threads}, {repeats}, "
                           f"precision={precision!r}, options={options!r}, "
                           f"distributions={int(stack)}, quadrature={quadrature!r})))"]
                done = subprocess.run(command, capture_output=True, text=True)
                if done.returncode != 0:
                    lines = (done.stderr.strip().splitlines()
                             or [f"exit status {done.returncode}"])
                    raise ValueError(f"bench: configuration d={dimension} N={n_modes} "
                                     f"batch={stack} failed: {lines[-1]}")
                records.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return records


def _rule_name(rule) -> str:
    """A sphere rule as the table names it: ``circle 16``, ``Lebedev 23``, ``product 4``."""
    from granframe.velocity.quadratures import CircleTrapezoid, Lebedev, SphereProduct

    if isinstance(rule, Lebedev):
        return f"Lebedev {rule.order}"
    if isinstance(rule, SphereProduct):
        return f"product {rule.n_polar}"
    if isinstance(rule, CircleTrapezoid):
        return f"circle {rule.n_points}"
    return type(rule).__name__


def table(records) -> str:
    """Markdown table of bench records (with the device memory of device backends, the
    stack size D, time and floor per distribution, when a record has D > 1, and the preset
    and sphere rule when a record was timed with a ``quadrature`` preset)."""
    device = any(r.get("device_memory_gib") is not None for r in records)
    stacks = any(r.get("distributions", 1) > 1 for r in records)
    presets = any(r.get("quadrature") is not None for r in records)
    lines = ["| d | N |" + (" quadrature | sphere rule |" if presets else "")
             + " N_rho | M | precision | pairs | batch |" + (" B |" if stacks else "")
             + " precompute | " + ("time / distribution" if stacks else "time / eval")
             + (" | floor / distribution" if stacks else " | FFT floor")
             + " | time/floor | peak RSS |" + (" device memory |" if device else ""),
             "|---|---|---|---|---|---|---|---|---|---|---|---|" + ("---|" if stacks else "")
             + ("---|---|" if presets else "")
             + ("---|" if device else "")]
    for r in records:
        lines.append(
            f"| {r['dimension']} | {r['n_modes']} |"
            + (f" {r.get('quadrature') or '—'} | {r.get('sphere_rule', '—')} |" if presets
               else "")
            + f" {r['radial_points']} | {r['sphere_points']} "
            f"| {r.get('precision', 'float64')} "
            f"| {r['transform_pairs']} | {r['batch']} |"
            + (f" {r.get('distributions', 1)} |" if stacks else "")
            + f" {r['precompute_s']:.2f} s "
            f"| {_ms(r['evaluation_s'])} "
            f"| {_ms(r['floor_s'])} | {r['time_over_floor']:.2f} | {r['peak_rss_gib']:.2f} GiB |"
            + (f" {r['device_memory_gib']:.2f} GiB |" if device else ""))
    return "\n".join(lines)


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def check_config(config) -> tuple:
    """Refuse a configuration (d, N, N_rho, M) the operator would refuse, naming the
    parameter: d in {2, 3}, N an even integer in [4, 65536] (the grid's rule), N_rho in
    [1, MAX_GAUSS_POINTS], M in [1, MAX_SURFACE_POINTS] (in 3D 2 n^2, a Gauss product
    rule)."""
    from granframe.velocity.quadratures import MAX_GAUSS_POINTS, MAX_SURFACE_POINTS

    dimension, n_modes, radial, sphere = config
    rules = (("config", dimension, dimension in (2, 3), "D must be 2 or 3"),
             ("n_modes", n_modes, n_modes >= 4 and n_modes % 2 == 0 and n_modes <= 2 ** 16,
              "must be an even integer >= 4 and <= 65536"),
             ("radial_points", radial, 1 <= radial <= MAX_GAUSS_POINTS,
              f"must be an integer >= 1 and <= {MAX_GAUSS_POINTS}"),
             ("sphere_points", sphere, 1 <= sphere <= MAX_SURFACE_POINTS
              and (dimension == 2 or 2 * math.isqrt(sphere // 2) ** 2 == sphere),
              f"must be an integer >= 1 and <= {MAX_SURFACE_POINTS}, in 3D 2 n^2 (Gauss "
              "product rule), e.g. 32"))
    for name, value, good, allowed in rules:
        if not good:
            check.reject("bench", name, value, allowed)
    return config


#: The review's quadrature (N_rho, M) per dimension: what a configuration without them takes.
REVIEW_RULES = {2: [32, 16], 3: [30, 32]}


def _integers(text: str, name: str, counts: tuple, usage: str) -> list:
    """The integers of 'A:B:...' (``counts`` of them, the first the dimension 2 or 3), the
    review's N_rho and M appended when they are left out; refused naming ``name``."""
    try:
        values = [int(p) for p in text.split(":")]
    except ValueError:
        values = []
    if len(values) not in counts or values[0] not in (2, 3):
        raise ValueError(f"bench: parameter '{name}' = {text!r} is invalid; use {usage}")
    return values + (REVIEW_RULES[values[0]] if len(values) == counts[0] else [])


def parse_config(text: str):
    """'D:N' or 'D:N:NRHO:M' -> (d, N, N_rho, M) with the review's quadrature by default,
    checked by :func:`check_config`."""
    return check_config(tuple(_integers(text, "config", (2, 4), "D:N or D:N:N_RHO:M with D "
                                        "in {2, 3}, e.g. 3:32 or 3:32:30:32")))


#: The space configurations of ``--space``: (dimension, N, cells, N_rho, M).
DEFAULT_SPACE_CONFIGS = ((3, 32, 64, 30, 32), (2, 64, 256, 32, 16))


def measure_space(dimension: int, n_modes: int, cells: int, radial_points: int,
                  sphere_points: int, backend: str, threads: int, repeats: int,
                  reconstruction: str = "muscl") -> dict:
    """Time one full step of a space run and its parts, in this process.

    The run: hard spheres, e = 0.8, RK4 collisions (4 operator calls per step) with the
    review's rules (N_rho, M), ``cells`` cells between two diffuse walls, a density wave,
    dt at the transport's CFL limit; ``cells`` a pair (C_x, C_y): a rectangle with diffuse
    walls at its four sides and a density wave along the diagonal. Reported (medians of ``repeats``, in alternating
    rounds): the step (:meth:`~granframe.abc.Problem.step`); its parts -- collisions (the
    integrator's step on all cells), transport (two half steps, walls included), of which
    the walls (ghost exchange and wall fluxes, the 6 stages' worth); the record
    (:meth:`~granframe.abc.Problem.record`: fields, totals and wall totals of every cell,
    one transfer); the batched operator time per distribution (one call on all cells /
    cells); the ratio (step + record) / (cells x that x 4 calls), at most 1.1 by target;
    and the peak resident memory.
    """
    from granframe.run.problems import make_problem

    baseline = peak_rss_kib()
    description = _space_description(dimension, n_modes, cells, radial_points, sphere_points,
                                     backend, threads, reconstruction)
    count = math.prod(cells) if isinstance(cells, (tuple, list)) else cells
    start = time.perf_counter()
    problem = make_problem(description)
    precompute = time.perf_counter() - start
    parts, dt = _space_parts(problem)
    medians = _medians(parts, repeats, problem.backend)
    per_distribution = medians["operator"] / count
    target = count * per_distribution * 4
    return {"dimension": dimension, "n_modes": n_modes,
            "cells": list(cells) if isinstance(cells, (tuple, list)) else cells,
            "radial_points": radial_points, "sphere_points": sphere_points,
            "reconstruction": reconstruction, "backend": backend, "threads": threads,
            "repeats": repeats, "precompute_s": precompute, "time_step": dt,
            "step_s": medians["step"], "collisions_s": medians["collisions"],
            "transport_s": medians["transport"], "walls_s": medians["walls"],
            "moments_s": medians["moments"], "operator_per_distribution_s": per_distribution,
            "operator_calls_per_step": 4, "target_s": target,
            "step_over_target": (medians["step"] + medians["moments"]) / target,
            "others_share": (medians["transport"] + medians["moments"])
            / (medians["step"] + medians["moments"]),
            "peak_rss_gib": peak_rss_kib() / 2 ** 20, "baseline_rss_gib": baseline / 2 ** 20}


def _space_description(dimension: int, n_modes: int, cells: int, radial_points: int,
                       sphere_points: int, backend: str, threads: int, reconstruction: str):
    """The run :func:`measure_space` times, as a :class:`RunDescription`."""
    from granframe.run.description import RunDescription

    # S = 4 resolves the wave's T = 0.8 .. 1.2 from N = 24; N = 16 needs the narrower box
    grid = {"dimension": dimension, "n_modes": n_modes,
            "support_radius": 4.0 if n_modes > 16 else 3.2}
    plane = isinstance(cells, (tuple, list))
    space = {"cells": list(cells) if plane else cells, "reconstruction": reconstruction,
             "left": "diffuse", "right": "diffuse",
             **({"bottom": "diffuse", "top": "diffuse"} if plane else {})}
    if dimension == 2:
        sphere = {"name": "circle_trapezoid", "n_points": sphere_points}
    else:
        sphere = {"name": "sphere_product", "n_polar": int(round((sphere_points / 2) ** 0.5))}
    return RunDescription.from_dict({
        "final_time": 1.0, "time_step": 1e-6, "grid": grid, "kernel": "hard_spheres",
        "restitution": {"name": "constant", "value": 0.8},
        "initial": {"name": "sinusoidal_mode", "field": "density", "amplitude": 0.2,
                    **({"mode": [1, 1]} if plane else {})},
        "operator": {"name": "fast_spectral", "radial_points": radial_points, "sphere": sphere},
        "backend": {"name": backend, **({"threads": threads} if backend != "numpy" else {})},
        "space": space,
        "health": {"step_limit": False}})


def _space_parts(problem):
    """The parts of a space step that :func:`measure_space` times, by name, each a function
    of no arguments, and the time step dt they take (the transport's CFL limit)."""
    array_backend = problem.backend
    split = problem.integrator                  # the Strang step: its stages are timed
    transport = split.transport
    domain = transport.domain
    dt = 2.0 * transport.time_step_limit()
    array = problem.state(problem.f0)
    cells_f = array_backend.asarray(problem.f0)

    def step():
        problem.step(0.0, array, dt)

    def collisions():
        split.collision_stage(array, 0.0, dt)

    def transport_both():
        split.transport_stage(array, 0.0, 0.5 * dt)
        split.transport_stage(array, 0.5 * dt, 0.5 * dt)

    def walls():
        g, xp = domain.ghost, array_backend.xp
        for _ in range(6):
            if hasattr(transport, "walls"):         # a rectangle: its four sides
                domain.exchange(array, transport.walls, 0.0)
                for side, wall in zip(domain.sides, transport.walls):
                    strip = domain.along(array, side.axis)[g if side.end == 0 else -g - 1]
                    wall.emit(side.to_wall(strip, problem.grid.dimension, xp), problem.grid,
                              xp, t=0.0, side=side)
                continue
            domain.exchange(array, transport.left, transport.right, 0.0)
            transport.left.emit(array[0, g], problem.grid, xp, t=0.0, side="left")
            transport.right.emit(array[-1, -g - 1], problem.grid, xp, t=0.0, side="right")

    def moments():
        problem.record(array)

    def operator():
        problem.operator(cells_f)

    parts = {"step": step, "collisions": collisions, "transport": transport_both,
             "walls": walls, "moments": moments, "operator": operator}
    return parts, dt


def _medians(parts, repeats: int, array_backend) -> dict:
    """The median time of each part over ``repeats`` alternating rounds (one call of every
    part a round), after one warm-up call of each."""
    for function in parts.values():       # warm-up
        function()
    times = {name: [] for name in parts}
    for _ in range(repeats):
        for name, function in parts.items():
            times[name].append(array_backend.elapsed(function))
    return {name: float(numpy.median(values)) for name, values in times.items()}


def run_space(configs, backend: str, threads: int, repeats: int,
              reconstruction: str = "muscl") -> list[dict]:
    """:func:`measure_space` for each (d, N, cells, N_rho, M) in its own subprocess."""
    check_options(backend, threads, repeats)
    records = []
    for dimension, n_modes, cells, radial, sphere in configs:
        check_config((dimension, n_modes, radial, sphere))
        counts = cells if isinstance(cells, (tuple, list)) else (cells,)
        if not all(check.is_integer(c) and c >= 7 for c in counts) or len(counts) > 2:
            check.reject("bench", "cells", cells, "must be an integer >= 7, or two (a "
                         "rectangle, CXxCY)")
        cells = tuple(counts) if len(counts) == 2 else cells
        command = [sys.executable, "-c",
                   "import json; from granframe.tools.bench import measure_space; "
                   f"print(json.dumps(measure_space({dimension}, {n_modes}, {cells}, {radial}, "
                   f"{sphere}, {backend!r}, {threads}, {repeats}, {reconstruction!r})))"]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            lines = done.stderr.strip().splitlines() or [f"exit status {done.returncode}"]
            raise ValueError(f"bench: space configuration d={dimension} N={n_modes} "
                             f"cells={cells} failed: {lines[-1]}")
        records.append(json.loads(done.stdout.strip().splitlines()[-1]))
    return records


def space_table(records) -> str:
    """Markdown table of :func:`measure_space` records."""
    lines = ["| velocities | cells | N_rho | M | step | collisions | transport (walls) | record "
             "| operator / distribution | cells x op x 4 | (step + record) / (cells x op x 4) "
             "| transport + moments share | peak RSS |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in records:
        cells = (f"{r['cells'][0]} x {r['cells'][1]}" if isinstance(r["cells"], list)
                 else r["cells"])
        lines.append(
            f"| {r['dimension']}D N = {r['n_modes']} | {cells} | {r['radial_points']} "
            f"| {r['sphere_points']} | {_ms(r['step_s'])} | {_ms(r['collisions_s'])} "
            f"| {_ms(r['transport_s'])} ({_ms(r['walls_s'])}) | {_ms(r['moments_s'])} "
            f"| {_ms(r['operator_per_distribution_s'])} | {_ms(r['target_s'])} "
            f"| {r['step_over_target']:.3f} | {100 * r['others_share']:.1f} % "
            f"| {r['peak_rss_gib']:.2f} GiB |")
    return "\n".join(lines)


def parse_space_config(text: str):
    """'D:N:CELLS' or 'D:N:CELLS:NRHO:M' -> (d, N, cells, N_rho, M), the review's rules by
    default."""
    usage = ("D:N:CELLS or D:N:CELLS:N_RHO:M with D in {2, 3} and CELLS a number or CXxCY "
             "(a rectangle), e.g. 3:32:64, 2:64:256:32:16 or 2:32:64x64")
    parts = text.split(":")
    plane = None
    if len(parts) >= 3 and "x" in parts[2]:
        try:
            plane = tuple(int(c) for c in parts[2].split("x"))
        except ValueError:
            plane = ()
        if len(plane) != 2:
            raise ValueError(f"bench: parameter 'space' = {text!r} is invalid; use {usage}")
        parts[2] = "0"
    values = _integers(":".join(parts), "space", (3, 5), usage)
    check_config((values[0], values[1], values[3], values[4]))
    if plane is not None:
        values[2] = plane
    return tuple(values)
