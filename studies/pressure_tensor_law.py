"""The pressure tensor of inelastic Maxwell molecules against its exact law (docs/validation.md).

Run: ``python studies/pressure_tensor_law.py`` (about two minutes on 2 cores). Prints two
Markdown tables, each at two resolutions (the refinement column):

1. The operator: max |int Q v_i v_j dv - rho (a1 P + a2 tr P I)| / max |rho (a1 P + ...)|
   for fast_spectral on an anisotropic, non-Maxwellian Gaussian mixture
   (:func:`granframe.model.exact.maxwell_pressure_rate`).
2. Runs: the stored P_ij(t) of e = 0.5 runs from that mixture (RK4 to t = 1) against
   :func:`granframe.model.exact.maxwell_pressure_tensor` from the stored P(0), the largest
   relative error over every step.

tests/test_pressure_tensor.py checks the finer resolution of each row.
"""

from __future__ import annotations

import pathlib
import tempfile
import time

import numpy

import granframe as gf
from granframe.model.exact import maxwell_pressure_law, maxwell_pressure_rate
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.testing import evaluate_on_host

#: an anisotropic, non-Maxwellian mixture: two shifted Gaussians with tilted covariances
MIXTURE = {
    2: [{"density": 0.6, "velocity": [0.2, -0.1], "covariance": [[1.2, 0.15], [0.15, 0.8]]},
        {"density": 0.4, "velocity": [-0.3, 0.15], "covariance": [[0.8, -0.1], [-0.1, 1.1]]}],
    3: [{"density": 0.6, "velocity": [0.2, -0.1, 0.1],
         "covariance": [[1.2, 0.15, 0.05], [0.15, 0.8, -0.05], [0.05, -0.05, 1.0]]},
        {"density": 0.4, "velocity": [-0.3, 0.15, -0.15],
         "covariance": [[0.8, -0.1, 0.0], [-0.1, 1.1, 0.1], [0.0, 0.1, 0.9]]}],
}

#: (N, S, sphere, N_rho) of the operator check: the coarser and the finer resolution
OPERATOR_RESOLUTIONS = {
    2: [(48, 4.5, gf.CircleTrapezoid(24), 32), (64, 5.5, gf.CircleTrapezoid(24), 32)],
    3: [(32, 4.0, gf.Lebedev(17), 30), (40, 4.5, gf.Lebedev(17), 30)],
}

#: (N, S, sphere table, N_rho, dt) of the runs: the coarser and the finer resolution
RUN_RESOLUTIONS = {
    2: [(48, 4.5, {"name": "circle_trapezoid", "n_points": 24}, 32, 0.1),
        (64, 5.5, {"name": "circle_trapezoid", "n_points": 24}, 32, 0.1)],
    3: [(24, 3.5, {"name": "lebedev", "order": 11}, 20, 0.25),
        (32, 4.0, {"name": "lebedev", "order": 11}, 20, 0.25)],
}


def mixture(dimension: int):
    """The mixture :data:`MIXTURE` as an initial condition."""
    return gf.initial_condition("gaussian_mixture", components=MIXTURE[dimension])


def operator_error(dimension, n_modes, support, sphere, radial, restitution, kernel) -> float:
    """max |int Q v_i v_j - rho (a1 P + a2 tr P I)| / max |rho (a1 P + a2 tr P I)| of
    fast_spectral on the projected mixture, the moments by the rectangle rule."""
    grid = gf.VelocityGrid(dimension, n_modes, support)
    operator = gf.collision_operator("fast_spectral", grid, kernel,
                                     gf.restitution_law("constant", value=restitution),
                                     backend=gf.array_backend("numpy"), radial_points=radial,
                                     sphere=sphere)
    f = grid.project(mixture(dimension).sample(grid))
    q, mesh = evaluate_on_host(operator, f), grid.mesh()
    rate = numpy.array([[numpy.sum(q * mesh[i] * mesh[j]) for j in range(dimension)]
                        for i in range(dimension)]) * grid.cell_volume
    moments = grid.moments(f)
    exact = maxwell_pressure_rate(moments["pressure_tensor"], moments["mass"], restitution,
                                  kernel)
    return float(numpy.abs(rate - exact).max() / numpy.abs(exact).max())


#: the 2D cooling run (tau = 0) at the finer resolution with dt halved, and on a larger
#: box and grid: what limits its error
LIMIT_CHECKS = [(64, 5.5, {"name": "circle_trapezoid", "n_points": 24}, 32, 0.05),
                (80, 6.0, {"name": "circle_trapezoid", "n_points": 32}, 40, 0.1)]


def anisotropic_run(dimension, heat_bath, knudsen=1.0, resolution=-1) -> RunDescription:
    """e = 0.5 Maxwell molecules from :data:`MIXTURE`, RK4 to t = 1, at the resolution
    ``RUN_RESOLUTIONS[dimension][resolution]`` (the finer by default), or at ``resolution``
    itself when it is a tuple (N, S, sphere table, N_rho, dt)."""
    n_modes, support, sphere, radial, dt = (
        resolution if isinstance(resolution, tuple) else RUN_RESOLUTIONS[dimension][resolution])
    return RunDescription(
        title="anisotropic Maxwell molecules",
        grid={"dimension": dimension, "n_modes": n_modes, "support_radius": support},
        kernel="maxwell", restitution={"name": "constant", "value": 0.5},
        initial={"name": "gaussian_mixture", "components": MIXTURE[dimension]},
        operator={"name": "fast_spectral", "radial_points": radial, "sphere": sphere},
        backend={"name": "numpy", "threads": 1}, heat_bath=heat_bath, knudsen=knudsen,
        time_step=dt, final_time=1.0, output={"snapshot_interval": 0.5})


def law_error(store, description) -> float:
    """max over the stored steps of max |P - P_exact| / max |P_exact|, P_exact from the
    stored P(0) and mass (:func:`granframe.model.exact.maxwell_pressure_law`)."""
    ds = gf.open_run(store)
    P, t = ds.pressure_tensor.values, ds.step_time.values
    law = maxwell_pressure_law(description.build("kernel"), description.build("restitution"),
                               description.heat_bath, description.knudsen)
    exact = law(t, P[0], float(ds.mass.values[0]))
    return float((numpy.abs(P - exact).max(axis=(1, 2))
                  / numpy.abs(exact).max(axis=(1, 2))).max())


def _resolution(n_modes, support, sphere, radial) -> str:
    rule = f"M = {sphere.n_points}" if isinstance(sphere, gf.CircleTrapezoid) else \
        f"Lebedev {sphere.order}"
    return f"N = {n_modes}, S = {support}, {rule}, N_ρ = {radial}"


def operator_table() -> list[str]:
    rows = ["| d | b | e | coarser: resolution, error | finer: resolution, error |",
            "|---|---|---|---|---|"]
    angular = gf.VariableHardSpheres(0.0, angular=lambda c: 1 + 0.5 * c + 0.3 * c * c)
    cases = [(2, "1", 0.0), (2, "1", 0.5), (2, "1", 1.0), (2, "1 + 0.5c + 0.3c²", 0.5),
             (3, "1", 0.5)]
    for dimension, b, e in cases:
        kernel = gf.collision_kernel("maxwell") if b == "1" else angular
        cells = [f"{_resolution(*r)}: {operator_error(dimension, *r, e, kernel):.2e}"
                 for r in OPERATOR_RESOLUTIONS[dimension]]
        rows.append(f"| {dimension} | {b} | {e} | {cells[0]} | {cells[1]} |")
    return rows


def _run(folder, dimension, tau, eps, resolution) -> tuple[str, float]:
    """'resolution: error' of one run, and its wall time."""
    description = anisotropic_run(dimension, tau, eps, resolution)
    store = pathlib.Path(folder) / f"{dimension}-{tau}-{eps}-{resolution}.zarr"
    started = time.perf_counter()
    Simulation(description).run(store, progress=False)
    wall = time.perf_counter() - started
    n_modes, support, sphere, radial, dt = (
        resolution if isinstance(resolution, tuple) else RUN_RESOLUTIONS[dimension][resolution])
    rule = (f"M = {sphere['n_points']}" if sphere["name"] == "circle_trapezoid"
            else f"Lebedev {sphere['order']}")
    return (f"N = {n_modes}, S = {support}, {rule}, N_ρ = {radial}, dt = {dt}: "
            f"{law_error(store, description):.2e}"), wall


def run_table() -> list[str]:
    rows = ["| d | τ | ε | coarser: resolution, error | finer: resolution, error | wall (finer) |",
            "|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as folder:
        for dimension, tau, eps in [(2, 0.0, 1.0), (2, 0.1, 0.5), (3, 0.1, 1.0)]:
            coarser, _ = _run(folder, dimension, tau, eps, 0)
            finer, wall = _run(folder, dimension, tau, eps, 1)
            rows.append(f"| {dimension} | {tau} | {eps} | {coarser} | {finer} | {wall:.1f} s |")
        rows += ["", "| d | τ | ε | limit check: resolution, error |", "|---|---|---|---|"]
        for resolution in LIMIT_CHECKS:
            rows.append(f"| 2 | 0.0 | 1.0 | {_run(folder, 2, 0.0, 1.0, resolution)[0]} |")
    return rows


if __name__ == "__main__":
    print("\n".join(operator_table()))
    print()
    print("\n".join(run_table()))
