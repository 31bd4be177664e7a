"""Array backends: an array namespace plus the FFTs the spectral operators need.

Operators are written once against this interface; a backend supplies
``xp`` (a NumPy-compatible namespace) and the transforms. The NumPy backend
is built in; pyFFTW and CuPy backends are plugins. The core never imports
pyfftw or cupy.
"""

from __future__ import annotations

import os
import time
from types import ModuleType

import attrs
import numpy
import scipy.fft

from granframe import validators as check


#: Supported precisions: real dtype and its complex counterpart.
PRECISIONS = {"float64": ("float64", "complex128"), "float32": ("float32", "complex64")}


def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class ArrayBackend:
    """Interface of an array backend.

    Attributes
    ----------
    name : str
        Registry name.
    xp : module
        NumPy-compatible array namespace used by operators for every array.

    Methods ``fftn``, ``ifftn``, ``rfftn`` and ``irfftn`` follow the
    :mod:`numpy.fft` conventions (unnormalised forward, 1/n inverse) over the
    given ``axes``; ``asarray`` moves data onto the backend's device,
    ``to_numpy`` back to host memory, and ``synchronize`` waits for queued
    work (a no-op on the CPU) so that timings are honest.

    For hot loops, :meth:`real_fft` returns a reusable :class:`RealFFT` with
    its own buffers, and ``concurrency`` says how many such pipelines the
    backend runs well side by side (CPU threads, each pipeline with
    single-threaded transforms; 1 on a GPU).

    Spectral operators multiply spectra by separable (per-axis) phase factors
    many times per evaluation. :meth:`separable_product` and
    :meth:`lowrank_accumulate` are those element-wise steps, written here once
    in ``xp``; a backend may override them with fused kernels (one pass over
    memory instead of several) that must give the same result to round-off.
    """

    name: str
    xp: ModuleType
    concurrency: int = 1
    #: Bytes of spectra an operator pipeline transforms in one batch (the fast operator's
    #: batch size aims at it). On a CPU a batch should stay in cache: 3D, 2 pipelines,
    #: 1 MiB -> 4 MiB took N = 16 from 3.6 to 3.1 ms and N = 32 from 30 to 25 ms, and
    #: larger batches fell out of cache. A GPU backend sets it large, so that each
    #: transform and kernel launch covers many pairs.
    batch_bytes: int = 4 * 2 ** 20

    def real_fft(self, shape, axes, threads: int = 1, precision: str = "float64") -> "RealFFT":
        """A planned real transform pair over ``axes`` of arrays of ``shape``, in
        ``precision`` (a key of :data:`PRECISIONS`)."""
        return RealFFT(self, tuple(shape), tuple(axes), precision=precision)

    def asarray(self, a, dtype=None):
        return self.xp.asarray(a, dtype=dtype)

    def to_numpy(self, a) -> numpy.ndarray:
        return numpy.asarray(a)

    def synchronize(self) -> None:
        """Block until queued work is done (no-op on CPU backends)."""

    def elapsed(self, function) -> float:
        """Seconds one call of ``function`` takes, its queued work included (host clock and
        :meth:`synchronize`; a device backend may time with device events instead)."""
        start = time.perf_counter()
        function()
        self.synchronize()
        return time.perf_counter() - start

    def device_memory(self) -> int | None:
        """Bytes of device memory the backend holds; None for host backends."""
        return None

    def separable_product(self, out, spectrum, head, tail):
        r"""Batch of spectra times separable factors, into ``out``.

        .. math:: \mathrm{out}_{b,i,j} = S_{i,j}\, h_{b,i}\, t_{b,j}

        with ``spectrum`` S of shape (I, J), ``head`` h (B, I), ``tail`` t
        (B, J) and ``out`` (B, I, J), all complex. Returns ``out``.
        """
        self.xp.multiply(spectrum, tail[:, None, :], out=out)
        out *= head[:, :, None]
        return out

    def lowrank_accumulate(self, acc, heads, tails, values):
        r"""Add low-rank-weighted batches of spectra into per-group accumulators.

        .. math:: \mathrm{acc}_{q,i,j} \mathrel{+}= \sum_{b \in q} \Big(\sum_t
           H_{b,i,t} T_{b,t,j}\Big) V_{b,i,j}

        with ``acc`` (Q, I, J), ``heads`` H (B, I, R), ``tails`` T (B, R, J) and
        ``values`` V (B, I, J), all complex; group q holds the consecutive
        batch entries b = q B/Q, ..., (q+1) B/Q - 1. ``values`` may be
        overwritten. Returns ``acc``.
        """
        weighted = self.xp.matmul(heads, tails)
        weighted *= values
        groups = acc.shape[0]
        acc += weighted.reshape((groups, -1) + weighted.shape[1:]).sum(axis=1)
        return acc

    def fftn(self, a, axes=None):
        raise NotImplementedError

    def ifftn(self, a, axes=None):
        raise NotImplementedError

    def rfftn(self, a, axes=None):
        raise NotImplementedError

    def irfftn(self, a, s, axes=None):
        raise NotImplementedError


class RealFFT:
    """Planned real-to-complex transform pair with buffers, reused across calls.

    Write the real input into ``real`` and call :meth:`forward`, or the
    half spectrum into ``spectrum`` and call :meth:`inverse`. Both return the
    result array, which may be a buffer of the plan (valid until the next
    call) or a new array; either may overwrite its input. Both directions are
    *unnormalised*: ``forward`` gives X_k = sum_j x_j exp(-2 pi i j.k/N) and
    ``inverse`` gives x_j = sum_k X_k exp(+2 pi i j.k/N), i.e. numpy's
    ``irfftn`` times the number of points; callers fold the 1/N^d into their
    own factors instead of paying an extra pass. This generic version calls
    the backend's ``rfftn``/``irfftn``; backends with real planners (FFTW,
    cuFFT) override it. The buffers have the real and complex dtypes of
    ``precision``; the backend's transforms must preserve them.
    """

    def __init__(self, backend: ArrayBackend, shape: tuple, axes: tuple, zeros=None,
                 precision: str = "float64"):
        zeros = backend.xp.zeros if zeros is None else zeros   # e.g. an aligned allocator
        self.backend, self.shape, self.axes = backend, shape, axes
        half = list(shape)
        half[axes[-1]] = shape[axes[-1]] // 2 + 1
        real, complex_ = PRECISIONS[precision]
        self.real = zeros(shape, dtype=real)
        self.spectrum = zeros(tuple(half), dtype=complex_)
        self._sizes = tuple(shape[a] for a in axes)

    def forward(self):
        return self.backend.rfftn(self.real, axes=self.axes)

    def inverse(self):
        return self.backend.irfftn(self.spectrum, s=self._sizes, axes=self.axes) * self._count

    @property
    def _count(self) -> int:
        return int(numpy.prod(self._sizes))


#: Largest ``threads`` of a CPU backend. Not this machine's CPU count: a description or
#: store written on a large machine must still be read on a small one, and tests run two
#: pipelines on one core. 1024 is above the hardware threads of current single machines
#: (two 192-core sockets with SMT: 768); each thread runs an operator pipeline with its own
#: buffers, so a larger count only costs memory and thread start-up.
MAX_THREADS = 1024


def _optional_threads(instance, attribute, value):
    if value is not None:
        check.integer(lower=1, upper=MAX_THREADS)(instance, attribute, value)


@attrs.frozen
class CPUBackend(ArrayBackend):
    """Base of the CPU backends: ``threads`` in all, one operator pipeline per thread.

    Parameters
    ----------
    threads : int or None
        Threads in all, 1 to :data:`MAX_THREADS`; ``None`` uses every CPU
        available. Operators run ``threads`` independent single-threaded pipelines
        (at the sizes of this field the transforms scale better over independent
        pipelines than inside one), while one-off transforms use all threads.
    """

    threads: int | None = attrs.field(default=None, converter=check.to_int,
                                      validator=_optional_threads)
    xp = numpy

    @property
    def workers(self) -> int:
        return available_cpus() if self.threads is None else self.threads

    @property
    def concurrency(self) -> int:
        return self.workers


@attrs.frozen
class NumpyBackend(CPUBackend):
    """NumPy arrays with SciPy's pocketfft transforms (``threads`` as in :class:`CPUBackend`)."""

    name = "numpy"

    def fftn(self, a, axes=None):
        return scipy.fft.fftn(a, axes=axes, workers=self.workers)

    def ifftn(self, a, axes=None):
        return scipy.fft.ifftn(a, axes=axes, workers=self.workers)

    def rfftn(self, a, axes=None):
        return scipy.fft.rfftn(a, axes=axes, workers=self.workers)

    def irfftn(self, a, s, axes=None):
        return scipy.fft.irfftn(a, s=s, axes=axes, workers=self.workers)

    def real_fft(self, shape, axes, threads: int = 1, precision: str = "float64") -> RealFFT:
        return _ScipyRealFFT(self, tuple(shape), tuple(axes), threads, precision)


class _ScipyRealFFT(RealFFT):
    """pocketfft transforms on ``threads`` threads, overwriting the input (pocketfft keeps
    float32 in single precision)."""

    def __init__(self, backend, shape, axes, threads, precision):
        super().__init__(backend, shape, axes, precision=precision)
        self.threads = threads

    def forward(self):
        return scipy.fft.rfftn(self.real, axes=self.axes, workers=self.threads)

    def inverse(self):
        return scipy.fft.irfftn(self.spectrum, s=self._sizes, axes=self.axes, norm="forward",
                                workers=self.threads, overwrite_x=True)
