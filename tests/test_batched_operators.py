"""Collision operators on stacks of distributions: f of shape (..., *grid.shape).

Every registered operator, on every backend of ``conftest.BACKENDS``, evaluates a stack
in its batched transforms; each distribution of the stack must get the Q of its own call,
to round-off (also with an energy-dependent and an anisotropic kernel), and keep its own
mass. The distribution axis of the element-wise steps is checked against einsum on each
backend and in the CUDA source compiled for the host.
"""

import ctypes
import shutil
import subprocess

import numpy
import pytest

import granframe as gf
import granframe_cupy

METHODS = ("fast_spectral", "direct_spectral")
GRIDS = {("fast_spectral", 2): 16, ("fast_spectral", 3): 12,
         ("direct_spectral", 2): 12, ("direct_spectral", 3): 8}
KERNELS = {
    "isotropic": gf.VariableHardSpheres(1.0),
    "energy": gf.VariableHardSpheres(0.5, energy_exponent=0.5),
    "anisotropic": gf.VariableHardSpheres(1.0, angular=lambda c: 1 + 0.4 * c),
}
TOLERANCE = 1e-12      # relative to max |Q|


def _operator(method, backend, dimension, kernel, **options):
    grid = gf.VelocityGrid(dimension, GRIDS[method, dimension], 4.0)
    if method == "fast_spectral":
        options = {"radial_points": 8, "sphere": gf.CircleTrapezoid(8) if dimension == 2
                   else gf.SphereProduct(2), "sigma": gf.CircleTrapezoid(8) if dimension == 2
                   else gf.SphereProduct(2), **options}
    law = gf.restitution_law("constant", value=0.7)
    return gf.collision_operator(method, grid, KERNELS[kernel], law, backend=backend, **options)


def _distributions(grid, count, seed=0):
    """``count`` distinct sums of two Maxwellians (different masses, drifts, temperatures)."""
    rng = numpy.random.default_rng(seed)
    d = grid.dimension
    stack = []
    for _ in range(count):
        f = grid.maxwellian(density=0.5 + rng.random(), velocity=0.3 * rng.normal(size=d),
                            temperature=0.8 + 0.6 * rng.random())
        f += grid.maxwellian(density=0.3 * rng.random(), velocity=0.4 * rng.normal(size=d),
                             temperature=0.9 + 0.3 * rng.random())
        stack.append(f)
    return numpy.stack(stack)


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("method", METHODS)
def test_stack_equals_separate_calls(backend, method, dimension, kernel):
    op = _operator(method, backend, dimension, kernel)
    grid = op.grid
    host = _distributions(grid, 7)
    separate = numpy.stack([backend.to_numpy(op(backend.asarray(f))) for f in host])
    scale = numpy.abs(separate).max()
    stacked = backend.to_numpy(op(backend.asarray(host)))
    assert stacked.shape == host.shape
    numpy.testing.assert_allclose(stacked, separate, rtol=0, atol=TOLERANCE * scale)
    # two batch axes, (2, 3, *grid.shape), and then a plain f again (the buffers resized)
    nested = backend.to_numpy(op(backend.asarray(host[:6].reshape((2, 3) + grid.shape))))
    assert nested.shape == (2, 3) + grid.shape
    numpy.testing.assert_allclose(nested.reshape((6,) + grid.shape), separate[:6], rtol=0,
                                  atol=TOLERANCE * scale)
    single = backend.to_numpy(op(backend.asarray(host[3])))
    assert single.shape == grid.shape
    numpy.testing.assert_allclose(single, separate[3], rtol=0, atol=TOLERANCE * scale)
    # mass conservation per distribution: int Q_b dv = 0 to round-off
    masses = stacked.reshape(7, -1).sum(axis=1) * grid.cell_volume
    gains = numpy.abs(stacked).reshape(7, -1).sum(axis=1) * grid.cell_volume
    assert numpy.all(numpy.abs(masses) <= 1e-12 * gains)


@pytest.mark.parametrize("batch", [12, 3])
@pytest.mark.parametrize("dimension", [2, 3])
def test_fast_stack_in_chunks_equals_separate_calls(backend, dimension, batch):
    """A stack goes in chunks of min(D, max(1, batch // P)) distributions, P = 4 pairs per
    rho here: batch 12 gives chunks of 3, 3, 1 distributions; batch 3 chunks of one
    with part-filled blocks of pairs (3, 1)."""
    op = _operator("fast_spectral", backend, dimension, "anisotropic", batch=batch)
    host = _distributions(op.grid, 7, seed=1)
    separate = numpy.stack([backend.to_numpy(op(backend.asarray(f))) for f in host])
    stacked = backend.to_numpy(op(backend.asarray(host)))
    assert op._pipelines[0].chunk == {12: 3, 3: 1}[batch]
    numpy.testing.assert_allclose(stacked, separate, rtol=0,
                                  atol=TOLERANCE * numpy.abs(separate).max())


@pytest.mark.parametrize("method", METHODS)
def test_wrong_trailing_shape_is_refused(method):
    op = _operator(method, gf.array_backend("numpy"), 2, "isotropic")
    n = op.grid.n_modes
    with pytest.raises(ValueError, match=rf"^{method}: parameter 'f.shape' = \(3, {n}, "
                                         rf"{n + 1}\) is invalid; must be the grid shape"):
        op(numpy.ones((3, n, n + 1)))
    with pytest.raises(ValueError, match=rf"^{method}: parameter 'f.shape' = \(0, {n}, {n}\)"):
        op(numpy.ones((0, n, n)))


def test_fast_stack_memory_is_counted_and_a_stack_over_the_budget_is_refused():
    backend = gf.array_backend("numpy")
    op = _operator("fast_spectral", backend, 2, "isotropic", batch=4)
    args = (op.grid, op.kernel, op.restitution, backend)
    options = {"radial_points": 8, "sphere": gf.CircleTrapezoid(8), "batch": 4}
    one = type(op).estimate_memory(*args, **options)
    assert op.memory_bytes == one
    many = type(op).estimate_memory(*args, **options, distributions=64)
    assert many > one
    op(_distributions(op.grid, 64))
    assert op.memory_bytes == many
    # chunks of min(D, max(1, batch // P)) distributions: about batch grids per FFT call
    assert op.stack_transforms(64) == 4 and op.stack_transforms(2) == 4
    small = _operator("fast_spectral", backend, 2, "isotropic", batch=4,
                      memory_budget=(one + many) // 2)
    with pytest.raises(ValueError, match=r"^fast_spectral: parameter 'f' = 'a stack of 64 "
                                         r"distributions' is invalid; is too large"):
        small(_distributions(op.grid, 64))
    with pytest.raises(ValueError, match=r"parameter 'distributions' = 0 is invalid"):
        type(op).estimate_memory(*args, **options, distributions=0)


def test_direct_stack_over_the_budget_is_refused():
    backend = gf.array_backend("numpy")
    op = _operator("direct_spectral", backend, 2, "isotropic")
    args = (op.grid, op.kernel, op.restitution, backend)
    needed = type(op).estimate_memory(*args, distributions=5)
    small = _operator("direct_spectral", backend, 2, "isotropic", memory_budget=needed - 1)
    small(_distributions(op.grid, 4))
    with pytest.raises(ValueError, match=r"^direct_spectral: parameter 'f' = 'a stack of 5 "
                                         r"distributions' is invalid; is too large"):
        small(_distributions(op.grid, 5))


# -- the distribution axis of the element-wise steps -------------------------------------------
def _complex(rng, *shape):
    return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)


def check_stacked_steps(backend):
    rng = numpy.random.default_rng(7)
    dists, batch, rows, cols, groups = 3, 4, 5, 6, 2
    spectrum, head, tail = (_complex(rng, dists, rows, cols), _complex(rng, batch, rows),
                            _complex(rng, batch, cols))
    out = backend.asarray(numpy.full((dists, batch, rows, cols), numpy.nan, dtype=complex))
    backend.separable_product(out, *map(backend.asarray, (spectrum, head, tail)))
    numpy.testing.assert_allclose(backend.to_numpy(out),
                                  numpy.einsum("dij,bi,bj->dbij", spectrum, head, tail),
                                  rtol=1e-13)
    for rank in (2, 3):
        heads, tails = _complex(rng, batch, rows, rank), _complex(rng, batch, rank, cols)
        values, start = (_complex(rng, dists, batch, rows, cols),
                         _complex(rng, dists, groups, rows, cols))
        expected = start + numpy.einsum("bit,btj,dbij->dbij", heads, tails, values).reshape(
            dists, groups, batch // groups, rows, cols).sum(axis=2)
        acc = backend.asarray(start.copy())
        backend.lowrank_accumulate(acc, *map(backend.asarray, (heads, tails, values)))
        numpy.testing.assert_allclose(backend.to_numpy(acc), expected, rtol=1e-13)


def test_stacked_element_wise_steps(backend):
    check_stacked_steps(backend)


SHIM = r"""
#include <complex>
#define GRANFRAME_HOST_SHIM
#define __global__
struct LaunchIndex { unsigned int x; };
static const LaunchIndex blockIdx{0}, threadIdx{0}, blockDim{1}, gridDim{1};
#include "kernels.cu"
typedef std::complex<double> T;
extern "C" void separable_product_complex128(T* out, const T* s, const T* h, const T* t,
        long long b, long long r, long long c, long long d) {
    separable_product<T>(out, s, h, t, b, r, c, d); }
extern "C" void lowrank_accumulate_complex128(T* acc, const T* h, const T* t, const T* v,
        long long q, long long g, long long r, long long c, long long k, long long d) {
    lowrank_accumulate<T>(acc, h, t, v, q, g, r, c, k, d); }
"""


def test_cuda_source_distribution_axis_on_the_host(tmp_path, monkeypatch):
    """kernels.cu's distribution axis, compiled for the host (one thread), through the CuPy
    backend's own launch code."""
    compiler = shutil.which("c++") or shutil.which("g++")
    if compiler is None:
        pytest.skip("no C++ compiler to build kernels.cu for the host")
    (tmp_path / "shim.cpp").write_text(SHIM)
    (tmp_path / "kernels.cu").write_text(granframe_cupy.kernel_source())
    subprocess.run([compiler, "-std=c++17", "-O1", "-Wall", "-Werror", "-shared", "-fPIC",
                    str(tmp_path / "shim.cpp"), "-o", str(tmp_path / "kernels.so")],
                   check=True, capture_output=True)
    library = ctypes.CDLL(str(tmp_path / "kernels.so"))

    class Module:
        def get_function(self, name):
            function = getattr(library, name.split("<")[0] + "_complex128")

            def launch(grid, block, arguments):
                function(*(a.ctypes.data_as(ctypes.c_void_p) if isinstance(a, numpy.ndarray)
                           else ctypes.c_longlong(int(a)) for a in arguments))
            return launch

    monkeypatch.setattr(granframe_cupy, "_module", lambda device: Module())
    monkeypatch.setattr(granframe_cupy.CuPyBackend, "_uses_kernels", True)
    check_stacked_steps(granframe_cupy.CuPyBackend(module="numpy"))
