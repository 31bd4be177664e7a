"""Backend parity: the same operator code on every array backend of ``conftest.BACKENDS``
(NumPy, pyFFTW, the CuPy backend's code path on the host, and CuPy on a GPU with and
without its fused kernels) equals the NumPy backend, one body per check. The GPU cases are
marked ``gpu`` and skip cleanly without one."""

import importlib.util
import json

import numpy
import pytest

import granframe as gf
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore
from granframe.testing import evaluate_on_host
from granframe_cupy import CuPyBackend, gpu_available


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


@pytest.mark.parametrize("dimension,n_modes,method", [(2, 24, "fast_spectral"),
                                                      (3, 16, "fast_spectral"),
                                                      (3, 32, "fast_spectral"),
                                                      (2, 12, "direct_spectral")])
def test_operator_equals_the_numpy_backend(backend, dimension, n_modes, method):
    """The same operator code on this backend gives the NumPy backend's Q to 1e-12,
    returned as the backend's array."""
    reference = _operator(gf.array_backend("numpy"), dimension, n_modes, method)
    operator = _operator(backend, dimension, n_modes, method)
    f = _anisotropic(reference.grid)
    expected = reference(f)
    q = operator(backend.asarray(f))
    assert isinstance(q, backend.xp.ndarray)
    got = backend.to_numpy(q)
    assert isinstance(got, numpy.ndarray)
    assert numpy.max(numpy.abs(got - expected)) <= 1e-12 * numpy.max(numpy.abs(expected))


def test_float32_stays_within_its_floor(backend):
    single = _operator(backend, 3, 16, precision="float32")
    double = _operator(gf.array_backend("numpy"), 3, 16)
    f = _anisotropic(double.grid)
    expected = double(f)
    got = evaluate_on_host(single, f)
    assert got.dtype == numpy.float32
    assert numpy.max(numpy.abs(got - expected)) <= 2e-5 * numpy.max(numpy.abs(expected))


#: Runs that reach every part of a right-hand side and integrator on the backend: the heat
#: bath (explicit and as an integrating factor), the BGK penalisation, the rescaled
#: formulation's spectral drift, and an adaptive step controller.
SCENES = {
    "rk4-heated": {"heat_bath": 0.1, "time_step": 0.05},
    "if_rk4-heated": {"heat_bath": 0.1, "time_step": 0.05, "integrator": "if_rk4"},
    "penalised": {"heat_bath": 0.1, "time_step": 0.05, "knudsen": 0.2,
                  "integrator": "penalised_ars222"},
    "rescaled": {"time_step": 0.05, "rescaled": True, "integrator": "ssp_rk3"},
    "adaptive": {"heat_bath": 0.1, "time_step": 0.05, "tolerance": 1e-6,
                 "integrator": "dopri54"},
}


@pytest.mark.parametrize("scene", SCENES)
def test_a_run_on_the_backend_equals_the_numpy_run(backend_table, scene, tmp_path):
    """The runner keeps f on the backend between steps and writes host arrays."""
    table = {"final_time": 0.5, **SCENES[scene],
             "grid": {"dimension": 2, "n_modes": 24, "support_radius": 4.0},
             "kernel": "hard_spheres", "restitution": {"name": "constant", "value": 0.7},
             "initial": {"name": "maxwellian", "temperature": 1.0},
             "operator": {"name": "fast_spectral", "radial_points": 12,
                          "sphere": {"name": "circle_trapezoid", "n_points": 12}},
             "output": {"snapshot_interval": 0.25}}
    runs = {}
    for name, backend in (("numpy", {"name": "numpy"}), ("here", backend_table)):
        description = RunDescription.from_dict({**table, "backend": backend})
        Simulation(description).run(tmp_path / f"{name}.zarr", progress=False)
        runs[name] = RunStore.open(tmp_path / f"{name}.zarr").group["f"][:]
    expected = runs["numpy"]
    assert numpy.max(numpy.abs(runs["here"] - expected)) <= 1e-12 * numpy.max(expected)


def test_f_moves_to_the_host_only_when_a_snapshot_is_written(tmp_path, monkeypatch):
    """20 steps, snapshots at t = 0, 0.5, 1: f crosses to the host twice (the snapshot at
    t = 0 is the host's f0; the moments of every step come back as scalars)."""
    moved = []
    to_numpy = CuPyBackend.to_numpy
    monkeypatch.setattr(CuPyBackend, "to_numpy",
                        lambda self, a: moved.append(a.shape) or to_numpy(self, a))
    description = RunDescription.from_dict({
        "final_time": 1.0, "time_step": 0.05, "kernel": "maxwell",
        "grid": {"dimension": 2, "n_modes": 32, "support_radius": 4.0},
        "restitution": {"name": "constant", "value": 0.7},
        "initial": {"name": "maxwellian", "temperature": 1.0},
        "operator": {"name": "fast_spectral", "radial_points": 8,
                     "sphere": {"name": "circle_trapezoid", "n_points": 8}},
        "output": {"snapshot_interval": 0.5}, "backend": {"name": "cupy", "module": "numpy"}})
    Simulation(description).run(tmp_path / "run.zarr", progress=False)
    store = RunStore.open(tmp_path / "run.zarr")
    assert store.group["f"].shape[0] == 3
    assert moved == [(32, 32)] * 2


@pytest.mark.gpu
@pytest.mark.skipif(not gpu_available(), reason="needs CuPy and a CUDA GPU")
def test_bench_times_with_cuda_events_and_reports_device_memory():
    from granframe.tools.bench import measure

    record = measure(3, 16, 8, 32, "cupy", 1, 5)
    assert record["evaluation_s"] > 0 and record["device_memory_gib"] > 0


def test_validation_benchmark_steps_on_the_host(tmp_path):
    """The validation script's timing and report, on the host code path (small grids)."""
    from granframe_cupy import validate

    text = validate.benchmark(tmp_path, "host", 2, configs=[(3, 8, 4, 8), (3, 12, 4, 8)],
                              options={"module": "numpy"})
    records = json.loads((tmp_path / "bench.json").read_text())["records"]
    assert [(r["n_modes"], r["precision"], r["backend_options"]) for r in records] == [
        (n, precision, {**variant, "module": "numpy"}) for _, precision, variant in
        validate.VARIANTS for n in (8, 12)]
    assert all(r["evaluation_s"] > 0 and r["floor_s"] > 0 for r in records)
    assert (tmp_path / "bench.md").read_text() == text
    assert "### float64, generic steps" in text and "3D N = 12 ran." in text


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
    with pytest.raises((ValueError, TypeError), match="'fused' = 'yes'"):
        CuPyBackend(fused="yes", module="numpy")
