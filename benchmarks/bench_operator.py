"""One call of the fast spectral collision operator (``fast_spectral``).

The configurations of ``granframe bench`` (docs/benchmarks.md): hard spheres, constant
restitution e = 0.8, float64, f a Maxwellian of temperature 1 on a grid of support
radius 4, quadratures fixed as D:N:N_rho:M (N_rho radial points, M directions), 2 threads.
"""

from __future__ import annotations

from benchmarks._support import array_backend, cached, parse_config, sphere_rule

#: (d, N, N_rho, M) as 'D:N:N_RHO:M'; the first is the smallest (the test suite's).
CONFIGS = ["2:64:32:16", "3:16:30:32", "3:32:30:32"]
BACKENDS = ["numpy", "pyfftw"]
#: the parameters the test suite (tests/test_benchmarks.py) runs each benchmark with
QUICK = {"config": CONFIGS[0]}


def build_operator(config: str, backend: str):
    """(operator, f) for a configuration 'D:N:N_RHO:M' on the array backend ``backend``,
    built once per process; the operator has been called once (FFTW plans, numba
    kernels compiled or loaded)."""

    def build():
        import granframe as gf

        dimension, n_modes, radial, points = parse_config(config)
        xp_backend = array_backend(backend)
        grid = gf.VelocityGrid(dimension, n_modes, 4.0)
        operator = gf.collision_operator(
            "fast_spectral", grid, gf.collision_kernel("hard_spheres"),
            gf.restitution_law("constant", value=0.8), backend=xp_backend,
            radial_points=radial, sphere=sphere_rule(dimension, points))
        f = xp_backend.asarray(grid.maxwellian(temperature=1.0))
        operator(f)
        xp_backend.synchronize()
        return operator, f

    return cached(("operator", config, backend), build)


class FastOperator:
    """Seconds per call of the operator, Q(f) for one distribution f."""

    params = [CONFIGS, BACKENDS]
    param_names = ["config", "backend"]
    # 3D N = 32 precomputes for seconds (phase tables, FFTW_MEASURE plans)
    timeout = 300
    # asv runs each timed call after setup; at 3D N = 32 a call is ~30 ms
    repeat = (3, 15, 20.0)

    def setup(self, config, backend):
        self.operator, self.f = build_operator(config, backend)
        self.backend = self.operator.backend

    def time_call(self, config, backend):
        self.operator(self.f)
        self.backend.synchronize()
