"""One step of a run in space: collisions in every cell (RK4, four batched operator calls)
and the transport in x between two diffuse walls (Strang splitting), as ``granframe bench
--space`` times it, on a small problem: 3D N = 16 in 8 cells. The support radius is 3.5,
not ``granframe bench``'s 4: at N = 16 a radius of 4 leaves the initial Maxwellians
under-resolved (their Nyquist projection changes the temperature by 2 %, which a run
refuses) and 3 cuts them off at the faces of the box.

Built through the public run API: a description with a ``[space]`` table, the simulation's
``problem``, its state from f0 and one ``problem.step(t, state, dt)`` at the transport's
CFL limit.
"""

from __future__ import annotations

from benchmarks._support import THREADS, array_backend, cached, require

#: 'D:N:CELLS:N_RHO:M'; the first is the smallest.
CONFIGS = ["3:16:8:30:32"]
BACKENDS = ["numpy", "pyfftw"]
#: the test suite's configuration (tests/test_benchmarks.py): 2D N = 32 in 8 cells
QUICK = {"config": "2:32:8:8:8"}
#: support radius S of the velocity grid
SUPPORT_RADIUS = 3.5


def description(config: str, backend: str) -> dict:
    """The run description (a table) of a space configuration: hard spheres, e = 0.8, a
    density wave of amplitude 0.2, MUSCL reconstruction, diffuse walls at both ends."""
    dimension, n_modes, cells, radial, points = (int(p) for p in config.split(":"))
    if dimension == 2:
        sphere = {"name": "circle_trapezoid", "n_points": points}
    else:
        sphere = {"name": "sphere_product", "n_polar": round((points / 2) ** 0.5)}
    return {
        "final_time": 1.0, "time_step": 1e-6,
        "grid": {"dimension": dimension, "n_modes": n_modes, "support_radius": SUPPORT_RADIUS},
        "kernel": "hard_spheres", "restitution": {"name": "constant", "value": 0.8},
        "initial": {"name": "sinusoidal_mode", "field": "density", "amplitude": 0.2},
        "operator": {"name": "fast_spectral", "radial_points": radial, "sphere": sphere},
        "backend": {"name": backend, "threads": THREADS},
        "space": {"cells": cells, "reconstruction": "muscl", "left": "diffuse",
                  "right": "diffuse"},
        "health": {"step_limit": False}}


def simulation(table: dict):
    """``granframe.Simulation`` of a description table."""
    import granframe as gf

    description = require("granframe.run.description", "a run in space").RunDescription
    build = getattr(gf, "Simulation", None)
    if build is None:                       # not re-exported by granframe (yet)
        build = require("granframe.run.runner", "a run in space").Simulation
    return build(description.from_dict(table))


class _Stepper:
    """What the benchmark uses of a problem (:class:`granframe.abc.Problem`): ``f0``,
    ``backend``, ``state(f_host)`` and ``step(t, state, dt)``. For commits whose
    simulation has no ``problem`` yet, the same step through the space simulation's
    integrator, so that the benchmark also runs on them."""

    def __init__(self, sim):
        self.sim = sim
        self.f0, self.backend = sim.f0, sim.backend

    def state(self, f_host):
        return self.sim._state(f_host)

    def step(self, t, state, dt):
        return self.sim.integrator.step(self.sim.equation, t, state, dt)


def build_problem(config: str, backend: str):
    """(problem, dt) built once per process, the problem stepped once (plans, kernels);
    dt is the transport's CFL limit."""

    def build():
        array_backend(backend)              # NotImplementedError (skipped) when absent
        table = description(config, backend)
        sim = simulation(table)
        problem = getattr(sim, "problem", None) or _Stepper(sim)
        dt = sim.description.space.transport_limit(sim.description.grid)
        problem.step(0.0, problem.state(problem.f0), dt)
        problem.backend.synchronize()
        return problem, dt

    return cached(("space", config, backend), build)


class SpaceStep:
    """Seconds per step of the whole run (every cell), from f0 each time."""

    params = [CONFIGS, BACKENDS]
    param_names = ["config", "backend"]
    timeout = 300
    repeat = (3, 10, 30.0)

    def setup(self, config, backend):
        self.problem, self.dt = build_problem(config, backend)
        self.state = self.problem.state(self.problem.f0)
        self.problem.backend.synchronize()

    def time_step(self, config, backend):
        self.problem.step(0.0, self.state, self.dt)
        self.problem.backend.synchronize()
