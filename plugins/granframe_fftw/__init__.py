"""pyFFTW array backend: NumPy arrays, planned FFTW transforms, fused numba kernels.

Install with ``pip install granframe[fftw]`` (pyfftw and numba). Both are
imported when the backend is built, not when granframe discovers the plugin,
so a missing package only matters to someone asking for this backend.
"""

from __future__ import annotations

import concurrent.futures
import functools

import attrs
import numpy

from granframe import hookimpl
from granframe import validators as check
from granframe.abc import RealFFT
from granframe.backends import CPUBackend, SciPyFFTBackend
from granframe.errors import BackendUnavailableError


def _pyfftw():
    try:
        import pyfftw
    except ImportError as exc:
        raise BackendUnavailableError("array backend 'pyfftw' needs the pyfftw package: "
                                      "pip install 'granframe[fftw]'") from exc
    return pyfftw


def _kernels():
    try:
        from granframe_fftw import _numba_kernels
    except ImportError as exc:
        raise BackendUnavailableError("array backend 'pyfftw' needs the numba package for its "
                                      "fused kernels: pip install 'granframe[fftw]'") from exc
    return _numba_kernels


@functools.cache
def _executor(workers: int):
    """The threads that share a fused transport kernel with the calling one (None for
    one worker), one pool per worker count."""
    return (concurrent.futures.ThreadPoolExecutor(workers - 1, "granframe-faces")
            if workers > 1 else None)


_EFFORTS = ("FFTW_ESTIMATE", "FFTW_MEASURE", "FFTW_PATIENT")


@attrs.frozen
class PyFFTWBackend(CPUBackend, SciPyFFTBackend):
    """NumPy arrays; FFTW transforms planned once per shape and reused; fused kernels.

    :meth:`separable_product`, :meth:`lowrank_accumulate` and MUSCL's
    :meth:`faces` are numba kernels (one pass over memory, GIL released)
    instead of NumPy's several passes.

    Parameters
    ----------
    threads : int or None
        As in :class:`granframe.backends.CPUBackend`.
    planner_effort : str
        FFTW planner flag: FFTW_ESTIMATE, FFTW_MEASURE (default) or FFTW_PATIENT.
    """

    planner_effort: str = attrs.field(default="FFTW_MEASURE")
    name = "pyfftw"

    @planner_effort.validator
    def _check_effort(self, attribute, value):
        if value not in _EFFORTS:
            check.reject("PyFFTWBackend", "planner_effort", value, f"must be one of {list(_EFFORTS)}")

    def __attrs_post_init__(self):
        _pyfftw()  # fail early and clearly when pyfftw or numba is missing
        _kernels()

    def separable_product(self, out, spectrum, head, tail):
        return _kernels().separable_product(out, spectrum, head, tail)

    def lowrank_accumulate(self, acc, heads, tails, values):
        return _kernels().lowrank_accumulate(acc, heads, tails, values)

    def faces(self, reconstruction, f):
        """MUSCL's face values of float64 f by a fused kernel over ``threads`` threads (one
        pass over f instead of NumPy's dozen, the same values to the bit: in float32
        numba's float constants would promote the van Leer slope); other reconstructions
        and dtypes as the base class computes them."""
        from granframe.space.reconstruction import MUSCL

        if type(reconstruction) is not MUSCL or f.ndim < 2 or f.dtype != numpy.float64 \
                or 0 in f.shape:
            return super().faces(reconstruction, f)
        workers = self.workers
        return _kernels().muscl_faces(f, reconstruction.limiter, _executor(workers), workers)

    def fft_module(self):
        """pyFFTW's :mod:`scipy.fft`-style interface, its plans cached between calls (the
        one-off transforms; operators use :meth:`real_fft`'s planned buffers)."""
        pyfftw = _pyfftw()
        pyfftw.interfaces.cache.enable()
        return pyfftw.interfaces.scipy_fft

    def real_fft(self, shape, axes, threads: int = 1, precision: str = "float64") -> RealFFT:
        return _FFTWRealFFT(self, tuple(shape), tuple(axes), threads, precision)


class _FFTWRealFFT(RealFFT):
    """FFTW r2c/c2r plans over aligned buffers ``real`` and ``spectrum`` (fftw for
    float64, fftwf for float32)."""

    def __init__(self, backend, shape, axes, threads, precision):
        pyfftw = _pyfftw()
        super().__init__(backend, shape, axes, zeros=pyfftw.zeros_aligned, precision=precision)
        flags = (backend.planner_effort,)
        self._forward = pyfftw.FFTW(self.real, self.spectrum, axes=axes, threads=threads,
                                    flags=flags + ("FFTW_DESTROY_INPUT",))
        self._inverse = pyfftw.FFTW(self.spectrum, self.real, axes=axes, threads=threads,
                                    direction="FFTW_BACKWARD", flags=flags + ("FFTW_DESTROY_INPUT",))

    def forward(self):
        self._forward.execute()
        return self.spectrum

    def inverse(self):
        self._inverse.execute()  # unnormalised, as RealFFT documents
        return self.real


@hookimpl
def granframe_register_array_backends(registry):
    registry.add("pyfftw", PyFFTWBackend,
                 description="NumPy arrays with planned, reused FFTW transforms (pyfftw)")
