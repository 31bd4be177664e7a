"""The CuPy backend: its code path checked on the host (module='numpy') everywhere, and on a
GPU where there is one (marked ``gpu``, skipped cleanly otherwise). One body per check,
parametrised over where it runs."""

import importlib.util

import numpy
import pytest

import granframe as gf
from granframe.description import RunDescription
from granframe.runner import Simulation
from granframe.storage import RunStore
from granframe_cupy import CuPyBackend, gpu_available

WHERE = ["numpy", pytest.param("cupy", marks=[pytest.mark.gpu, pytest.mark.skipif(
    not gpu_available(), reason="needs CuPy and a CUDA GPU")])]


def _operator(backend, dimension, n_modes, method="fast_spectral", **options):
    grid = gf.VelocityGrid(dimension, n_modes, 4.0)
    kernel = gf.VariableHardSpheres(1.0, angular=lambda c: 1 + 0.3 * c)
    law = gf.restitution_law("tanh", asymptotic_value=0.3)
    if method == "fast_spectral":
        sphere = gf.CircleTrapezoid(16) if dimension == 2 else gf.Lebedev(11)
        options = {"radial_points": 12, "sphere": sphere, **options}
    return gf.collision_operator(method, grid, kernel, law, backend=backend, **options)


def _anisotropic(grid):
    f = grid.maxwellian(velocity=[0.4] + [0.0] * (grid.dimension - 1), temperature=0.8)
    return f + grid.maxwellian(velocity=[-0.5] + [0.2] * (grid.dimension - 1),
                               temperature=0.5)


@pytest.mark.parametrize("where", WHERE)
@pytest.mark.parametrize("dimension,n_modes,method", [(2, 24, "fast_spectral"),
                                                      (3, 16, "fast_spectral"),
                                                      (2, 12, "direct_spectral")])
def test_operator_equals_the_numpy_backend(where, dimension, n_modes, method):
    """The same operator code on this backend gives the NumPy backend's Q to 1e-12."""
    backend = CuPyBackend(module=where)
    reference = _operator(gf.array_backend("numpy"), dimension, n_modes, method)
    operator = _operator(backend, dimension, n_modes, method)
    f = _anisotropic(reference.grid)
    expected = reference(f)
    got = backend.to_numpy(operator(backend.asarray(f)))
    assert isinstance(got, numpy.ndarray)
    assert numpy.max(numpy.abs(got - expected)) <= 1e-12 * numpy.max(numpy.abs(expected))


@pytest.mark.parametrize("where", WHERE)
def test_float32_stays_within_its_floor(where):
    backend = CuPyBackend(module=where)
    single = _operator(backend, 3, 16, precision="float32")
    double = _operator(gf.array_backend("numpy"), 3, 16)
    f = _anisotropic(double.grid)
    expected = double(f)
    got = backend.to_numpy(single(backend.asarray(f)))
    assert numpy.max(numpy.abs(got - expected)) <= 2e-5 * numpy.max(numpy.abs(expected))


@pytest.mark.parametrize("where", WHERE)
def test_a_run_on_the_backend_equals_the_numpy_run(where, tmp_path):
    """The runner keeps f on the backend between steps and writes host arrays."""
    table = {"final_time": 0.5, "time_step": 0.05, "heat_bath": 0.1,
             "grid": {"dimension": 2, "n_modes": 24, "support_radius": 4.0},
             "kernel": "hard_spheres", "restitution": {"name": "constant", "value": 0.7},
             "initial": {"name": "maxwellian", "temperature": 1.0},
             "operator": {"name": "fast_spectral", "radial_points": 12,
                          "sphere": {"name": "circle_trapezoid", "n_points": 12}},
             "output": {"snapshot_interval": 0.25}}
    runs = {}
    for name, backend in (("numpy", {"name": "numpy"}),
                          ("here", {"name": "cupy", "module": where})):
        description = RunDescription.from_dict({**table, "backend": backend})
        Simulation(description).run(tmp_path / f"{name}.zarr", progress=False)
        runs[name] = RunStore.open(tmp_path / f"{name}.zarr").group["f"][:]
    expected = runs["numpy"]
    assert numpy.max(numpy.abs(runs["here"] - expected)) <= 1e-12 * numpy.max(expected)


@pytest.mark.gpu
@pytest.mark.skipif(not gpu_available(), reason="needs CuPy and a CUDA GPU")
def test_bench_times_with_cuda_events_and_reports_device_memory():
    from granframe.bench import measure

    record = measure(3, 16, 8, 32, "cupy", 1, 5)
    assert record["evaluation_s"] > 0 and record["device_memory_gib"] > 0


@pytest.mark.skipif(importlib.util.find_spec("cupy") is not None, reason="CuPy is installed")
def test_without_cupy_the_backend_says_what_to_install():
    with pytest.raises(ValueError, match=r"needs the cupy package.*granframe\[gpu\]"):
        gf.array_backend("cupy")


def test_bad_parameters_are_refused_by_name():
    with pytest.raises(ValueError, match="'module'"):
        CuPyBackend(module="torch")
    with pytest.raises((ValueError, TypeError), match="'device'"):
        CuPyBackend(device=-1, module="numpy")
    with pytest.raises((ValueError, TypeError), match="'memory_limit'"):
        CuPyBackend(memory_limit=0, module="numpy")
