"""The element-wise operations every array backend supplies (fused or generic) against einsum.

One body per operation runs on every backend of ``conftest.BACKENDS``; the CUDA source of
the CuPy backend's fused kernels is also compiled for the host with a one-thread launch
shim and run through the backend's own launch code by the same bodies, so its index
arithmetic and the backend's arguments are checked without a GPU.
"""

import ctypes
import pathlib
import shutil
import subprocess

import numpy
import pytest

import granframe as gf
import granframe_cupy

SEPARABLE_SHAPES = [(1, 4, 3), (6, 16, 144), (5, 7, 33)]
LOWRANK_CASES = [(rank, groups, per_group) for rank in (1, 2, 5)
                 for groups, per_group in ((1, 1), (1, 4), (3, 2))]
DTYPES = {"complex128": 1e-13, "complex64": 2e-6}     # tolerance relative to max |expected|


def complex_normal(rng, dtype, *shape):
    return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(dtype)


def check_separable_product(backend, dtype, batch, rows, cols):
    rng = numpy.random.default_rng(batch * rows + cols)
    spectrum = complex_normal(rng, dtype, rows, cols)
    head, tail = complex_normal(rng, dtype, batch, rows), complex_normal(rng, dtype, batch, cols)
    out = backend.asarray(numpy.full((batch, rows, cols), numpy.nan, dtype=dtype))
    result = backend.separable_product(out, *map(backend.asarray, (spectrum, head, tail)))
    expected = numpy.einsum("ij,bi,bj->bij", spectrum.astype(complex), head, tail)
    assert result is out
    numpy.testing.assert_allclose(backend.to_numpy(out), expected, rtol=0,
                                  atol=DTYPES[dtype] * numpy.abs(expected).max())


def check_lowrank_accumulate(backend, dtype, rank, groups, per_group):
    rng = numpy.random.default_rng(100 * rank + 10 * groups + per_group)
    batch, rows, cols = groups * per_group, 9, 17
    heads = complex_normal(rng, dtype, batch, rows, rank)
    tails = complex_normal(rng, dtype, batch, rank, cols)
    values = complex_normal(rng, dtype, batch, rows, cols)
    start = complex_normal(rng, dtype, groups, rows, cols)
    expected = start + numpy.einsum("bit,btj,bij->bij", heads.astype(complex), tails,
                                    values).reshape(groups, per_group, rows, cols).sum(axis=1)
    acc = backend.asarray(start.copy())
    result = backend.lowrank_accumulate(acc, *map(backend.asarray, (heads, tails, values)))
    assert result is acc
    numpy.testing.assert_allclose(backend.to_numpy(acc), expected, rtol=0,
                                  atol=DTYPES[dtype] * numpy.abs(expected).max())


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("batch,rows,cols", SEPARABLE_SHAPES)
def test_separable_product(backend, dtype, batch, rows, cols):
    check_separable_product(backend, dtype, batch, rows, cols)


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("rank,groups,per_group", LOWRANK_CASES)
def test_lowrank_accumulate(backend, dtype, rank, groups, per_group):
    check_lowrank_accumulate(backend, dtype, rank, groups, per_group)


FACE_SHAPES = [(9, 1, 4, 4), (14, 5, 8, 8), (10, 7, 3, 3, 3), (40, 3, 16, 16),
               (24, 8, 40, 40)]       # the last above THREADED_SIZE: shared by threads


@pytest.mark.parametrize("limiter", ["minmod", "van_leer", "mc"])
@pytest.mark.parametrize("shape", FACE_SHAPES)
def test_muscl_faces_are_the_reconstructions_own_to_the_bit(backend, limiter, shape):
    """Every backend's face values (a fused kernel where it has one) equal MUSCL's NumPy
    ones bit for bit: on plateaus (a or b zero), on a strided view (a transport along y),
    in float32, and NaN where f has one."""
    from granframe.space.reconstruction import MUSCL

    rng = numpy.random.default_rng(len(shape) * shape[0])
    f = rng.random(shape)
    f[rng.random(shape) < 0.15] = 0.5
    f.flat[7] = numpy.nan
    reconstruction = MUSCL(limiter=limiter)
    views = {"contiguous": f, "strided": numpy.swapaxes(f, 0, 1)[:, 1:-1],
             "float32": f.astype(numpy.float32)}
    for name, view in views.items():
        if view.shape[0] < 4:
            continue
        want = reconstruction.faces(numpy.ascontiguousarray(view), numpy)
        got = backend.faces(reconstruction, backend.asarray(view))
        for a, b in zip(got, want):
            numpy.testing.assert_array_equal(backend.to_numpy(a), b, err_msg=name)


# -- the CUDA source of the fused kernels, on the host -----------------------------------------
SHIM = r"""
#include <complex>
#define GRANFRAME_HOST_SHIM
#define __global__
struct LaunchIndex { unsigned int x; };
static const LaunchIndex blockIdx{0}, threadIdx{0}, blockDim{1}, gridDim{1};
#include "kernels.cu"
#define HOST_ENTRY(T, SUFFIX) \
    extern "C" void separable_product_##SUFFIX(T* out, const T* s, const T* h, const T* t, \
            long long b, long long r, long long c) { separable_product<T>(out, s, h, t, b, r, c); } \
    extern "C" void lowrank_accumulate_##SUFFIX(T* acc, const T* h, const T* t, const T* v, \
            long long q, long long g, long long r, long long c, long long k) { \
        lowrank_accumulate<T>(acc, h, t, v, q, g, r, c, k); }
HOST_ENTRY(std::complex<float>, complex64)
HOST_ENTRY(std::complex<double>, complex128)
"""


class HostModule:
    """Stands in for the CuPy RawModule of kernels.cu: ``get_function`` takes the same name
    expressions and returns launchers that run the host-compiled source as one thread (the
    kernels' grid-stride loops then visit every element in order)."""

    def __init__(self, library: pathlib.Path):
        self.library = ctypes.CDLL(str(library))
        self.types = {cuda: dtype for dtype, cuda in granframe_cupy._CUDA_TYPES.items()}

    def get_function(self, name):
        kernel, cuda_type = name[:-1].split("<", 1)
        function = getattr(self.library, f"{kernel}_{self.types[cuda_type]}")

        def launch(grid, block, arguments):
            assert len(grid) == len(block) == 1 and grid[0] >= 1 and block[0] >= 1
            arrays = [a for a in arguments if isinstance(a, numpy.ndarray)]
            sizes = [a for a in arguments if isinstance(a, numpy.int64)]
            assert len(arrays) + len(sizes) == len(arguments)
            assert all(a.flags.c_contiguous and a.dtype.name == self.types[cuda_type]
                       for a in arrays)
            function(*(a.ctypes.data_as(ctypes.c_void_p) for a in arrays),
                     *map(ctypes.c_longlong, sizes))

        return launch


@pytest.fixture(scope="module")
def host_kernels(tmp_path_factory):
    compiler = shutil.which("c++") or shutil.which("g++")
    if compiler is None:
        pytest.skip("no C++ compiler to build kernels.cu for the host")
    folder = tmp_path_factory.mktemp("kernels")
    (folder / "shim.cpp").write_text(SHIM)
    # the very source the backend hands to NVRTC
    (folder / "kernels.cu").write_text(granframe_cupy.kernel_source())
    subprocess.run([compiler, "-std=c++17", "-O1", "-Wall", "-Werror", "-shared", "-fPIC",
                    str(folder / "shim.cpp"), "-o", str(folder / "kernels.so")],
                   check=True, capture_output=True)
    return HostModule(folder / "kernels.so")


@pytest.fixture
def host_launched(host_kernels, monkeypatch):
    """The CuPy backend's fused path (argument checks, launches) on host arrays, with the
    host-compiled kernels.cu in place of the NVRTC-compiled module."""
    monkeypatch.setattr(granframe_cupy, "_module", lambda device: host_kernels)
    monkeypatch.setattr(granframe_cupy.CuPyBackend, "_uses_kernels", True)
    return granframe_cupy.CuPyBackend(module="numpy")


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("batch,rows,cols", SEPARABLE_SHAPES)
def test_cuda_separable_product_on_the_host(host_launched, dtype, batch, rows, cols):
    check_separable_product(host_launched, dtype, batch, rows, cols)


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("rank,groups,per_group", LOWRANK_CASES)
def test_cuda_lowrank_accumulate_on_the_host(host_launched, dtype, rank, groups, per_group):
    check_lowrank_accumulate(host_launched, dtype, rank, groups, per_group)


@pytest.mark.parametrize("kernel", ["hard_spheres", gf.VariableHardSpheres(
    0.5, angular=lambda c: 1 + 0.4 * c, energy_exponent=0.5)], ids=["rank-2", "anisotropic"])
@pytest.mark.parametrize("batch", [3, None])
@pytest.mark.parametrize("precision,tolerance", [("float64", 1e-12), ("float32", 2e-5)])
def test_fast_operator_with_the_cuda_kernels_on_the_host(host_launched, kernel, batch,
                                                         precision, tolerance):
    """The fast operator through the fused path (part-filled batches of 3, or the backend's
    large default batch) equals the NumPy backend's float64 operator."""
    grid = gf.VelocityGrid(3, 12, 4.0)
    f = grid.maxwellian(velocity=[0.2, 0.1, -0.3], temperature=0.9)
    f += grid.maxwellian(density=0.5, velocity=[-0.6, 0.3, 0.0], temperature=0.5)
    kernel = gf.collision_kernel(kernel) if isinstance(kernel, str) else kernel
    law = gf.restitution_law("constant", value=0.7)
    reference = gf.collision_operator("fast_spectral", grid, kernel, law,
                                      backend=gf.array_backend("numpy"))(f)
    q = gf.collision_operator("fast_spectral", grid, kernel, law, backend=host_launched,
                              batch=batch, precision=precision)(f)
    assert q.dtype == numpy.dtype(precision)
    numpy.testing.assert_allclose(q, reference, rtol=0,
                                  atol=tolerance * numpy.abs(reference).max())
