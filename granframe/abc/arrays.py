"""The contract of an array backend and its planned real transforms, and the supported
precisions.

:mod:`granframe.backends` implements it (NumPy, SciPy's transforms), the plugins
``granframe_fftw`` and ``granframe_cupy`` with planned FFTW and cuFFT transforms and fused
kernels. Imported from :mod:`granframe.abc`.
"""

from __future__ import annotations

import time
from types import ModuleType

import numpy


#: Supported precisions: real dtype and its complex counterpart.
PRECISIONS = {"float64": ("float64", "complex128"), "float32": ("float32", "complex64")}


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

    The transport of a space run takes its face values through :meth:`faces`.
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

    #: whether the arrays live in device memory, where every copy to the host (``float``
    #: of a reduction, a check's flag) waits for the queued work: such copies are kept out
    #: of the steps of a run
    on_device: bool = False

    def device_memory(self) -> int | None:
        """Bytes of device memory the backend holds; None for host backends."""
        return None

    def for_process(self, local_rank: int) -> "ArrayBackend":
        """The backend of the process ``local_rank`` among the processes of a run on this
        host (:attr:`~granframe.abc.Communicator.local_rank`): a device backend gives each
        process its own device (local rank modulo the devices); a host backend is shared as
        it is."""
        return self

    def separable_product(self, out, spectrum, head, tail):
        r"""Batch of spectra times separable factors, into ``out``.

        .. math:: \mathrm{out}_{d,b,i,j} = S_{d,i,j}\, h_{b,i}\, t_{b,j}

        with ``spectrum`` S of shape (D, I, J), ``head`` h (B, I), ``tail`` t
        (B, J) and ``out`` (D, B, I, J), all complex: every one of D spectra
        (distributions) times every one of B factors. Without the leading D axis
        (S of shape (I, J), ``out`` (B, I, J)) it is the case D = 1. Returns ``out``.
        """
        self.xp.multiply(spectrum[..., None, :, :], tail[:, None, :], out=out)
        out *= head[:, :, None]
        return out

    def faces(self, reconstruction, f):
        """The face values (f^-, f^+) of ``reconstruction`` (a
        :class:`~granframe.abc.Reconstruction`) along axis 0 of ``f``: its own
        :meth:`~granframe.abc.Reconstruction.faces` in ``xp``. A backend may override it
        with a fused kernel for the reconstructions it knows, which must give the same
        values."""
        return reconstruction.faces(f, self.xp)

    def lowrank_accumulate(self, acc, heads, tails, values):
        r"""Add low-rank-weighted batches of spectra into per-group accumulators.

        .. math:: \mathrm{acc}_{d,q,i,j} \mathrel{+}= \sum_{b \in q} \Big(\sum_t
           H_{b,i,t} T_{b,t,j}\Big) V_{d,b,i,j}

        with ``acc`` (D, Q, I, J), ``heads`` H (B, I, R), ``tails`` T (B, R, J) and
        ``values`` V (D, B, I, J), all complex: the weights are shared by the D
        distributions. Group q holds the consecutive batch entries
        b = q B/Q, ..., (q+1) B/Q - 1. Without the leading D axis (``acc`` (Q, I, J),
        ``values`` (B, I, J)) it is the case D = 1. ``values`` may be overwritten.
        Returns ``acc``.
        """
        values *= self.xp.matmul(heads, tails)
        groups, rows, cols = acc.shape[-3:]
        acc += values.reshape(values.shape[:-3] + (groups, -1, rows, cols)).sum(axis=-3)
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
