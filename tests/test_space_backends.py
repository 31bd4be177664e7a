"""A space run gives the same result on every array backend of ``conftest.BACKENDS`` (NumPy,
pyFFTW, the CuPy backend's code path on the host, CuPy on a GPU): transport, walls,
collisions and fields are written once against the backend's array namespace. The GPU
cases skip cleanly without one."""

import numpy

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation

TOML = """
final_time = 0.02
time_step = 0.004
knudsen = 0.1
integrator = "penalised_ars222"
heat_bath = 0.05
[grid]
dimension = 2
n_modes = 24
support_radius = 3.2
[kernel]
name = "hard_spheres"
[restitution]
name = "constant"
value = 0.8
[initial]
name = "riemann"
left = {density = 1.0, velocity = 0.2, temperature = 1.0}
right = {density = 0.5, temperature = 0.8}
[operator]
name = "fast_spectral"
quadrature = "review"
[space]
cells = 24
block_cells = 8
reconstruction = "weno5"
left = {name = "diffuse", temperature = 1.1, velocity = 0.3, accommodation = 0.7}
right = "specular"
"""


def _run(backend_table):
    d = RunDescription.from_toml(TOML).replace(backend=backend_table)
    return Simulation(d).run(None, progress=False).dataset


def test_a_space_run_equals_the_numpy_backend(backend_table):
    reference = _run({"name": "numpy"})
    result = _run(backend_table)
    f, g = reference.f.values, result.f.values
    assert numpy.max(numpy.abs(f - g)) <= 1e-12 * numpy.max(numpy.abs(f))
    for name in ("density", "temperature", "heat_flux", "wall_mass", "wall_energy", "mass"):
        a, b = reference[name].values, result[name].values
        assert numpy.max(numpy.abs(a - b)) <= 1e-12 * max(1.0, numpy.max(numpy.abs(a))), name
