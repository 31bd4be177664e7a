"""Array backends: an array namespace plus the FFTs the spectral operators need.

Operators are written once against this interface; a backend supplies
``xp`` (a NumPy-compatible namespace) and the transforms. The NumPy backend
is built in; pyFFTW and CuPy backends are plugins. The core never imports
pyfftw or cupy.
"""

from __future__ import annotations

import os

from types import ModuleType

import attrs
import numpy
import scipy.fft

from granframe import validators as check
from granframe.abc import ArrayBackend, RealFFT


def to_host(a) -> numpy.ndarray:
    """``a`` as a NumPy array: a device array (CuPy's, with ``get``) is copied to the host."""
    return a.get() if hasattr(a, "get") else numpy.asarray(a)


def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


#: The backend name meaning :func:`preferred_backend`.
AUTO = "auto"


def preferred_backend() -> str:
    """The array backend that ``backend = "auto"`` (a run description's default), ``granframe
    bench`` and the studies use: 'pyfftw' when that backend is registered and can be built
    (pyfftw and numba installed), else 'numpy'. The one home of that policy."""
    from granframe.registry import default_registries

    registries = default_registries()
    if "pyfftw" in registries.names("array_backends"):
        try:
            registries.create("array_backends", "pyfftw")
            return "pyfftw"
        except ValueError:
            pass
    return "numpy"


def resolve_backend(name: str) -> str:
    """The registered backend a name stands for: :func:`preferred_backend` for ``"auto"``,
    else the name itself."""
    return preferred_backend() if name == AUTO else name


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

    def thread_options(self, threads: int | None) -> dict:
        """``workers`` of :mod:`scipy.fft`-style modules: ``threads``, or all of the
        backend's threads when None."""
        return {"workers": self.workers if threads is None else threads}


class SciPyFFTBackend(ArrayBackend):
    """A backend whose transforms come from a module with :mod:`scipy.fft`'s interface.

    The transforms are written once here for every such module: SciPy's pocketfft
    (:class:`NumpyBackend`), pyFFTW's ``interfaces.scipy_fft`` (the one-off transforms of
    the pyFFTW backend) and CuPy's ``cupyx.scipy.fft`` (cuFFT). A subclass names the module
    (:meth:`fft_module`) and how it is told a number of threads (:meth:`thread_options`).
    """

    def fft_module(self) -> ModuleType:
        """The module providing ``fftn``, ``ifftn``, ``rfftn`` and ``irfftn`` with
        :mod:`scipy.fft`'s signatures."""
        raise NotImplementedError(f"{type(self).__name__} must name its FFT module")

    def thread_options(self, threads: int | None) -> dict:
        """Keyword arguments running one transform on ``threads`` threads (None: the
        backend's own count); none by default (a device library)."""
        return {}

    def fftn(self, a, axes=None):
        return self.fft_module().fftn(a, axes=axes, **self.thread_options(None))

    def ifftn(self, a, axes=None):
        return self.fft_module().ifftn(a, axes=axes, **self.thread_options(None))

    def rfftn(self, a, axes=None):
        return self.fft_module().rfftn(a, axes=axes, **self.thread_options(None))

    def irfftn(self, a, s, axes=None):
        return self.fft_module().irfftn(a, s=s, axes=axes, **self.thread_options(None))

    def real_fft(self, shape, axes, threads: int = 1, precision: str = "float64") -> RealFFT:
        return SciPyRealFFT(self, tuple(shape), tuple(axes), threads, precision)


class SciPyRealFFT(RealFFT):
    """:class:`~granframe.abc.RealFFT` through a :class:`SciPyFFTBackend`'s module: the input
    may be destroyed (``overwrite_x``), and the inverse is unnormalised by
    ``norm="forward"`` rather than by a scaling pass (both keep float32 in single precision)."""

    def __init__(self, backend: SciPyFFTBackend, shape, axes, threads, precision):
        super().__init__(backend, shape, axes, precision=precision)
        self._module = backend.fft_module()
        self._options = backend.thread_options(threads)

    def forward(self):
        return self._module.rfftn(self.real, axes=self.axes, overwrite_x=True, **self._options)

    def inverse(self):
        return self._module.irfftn(self.spectrum, s=self._sizes, axes=self.axes, norm="forward",
                                   overwrite_x=True, **self._options)


@attrs.frozen
class NumpyBackend(CPUBackend, SciPyFFTBackend):
    """NumPy arrays with SciPy's pocketfft transforms (``threads`` as in :class:`CPUBackend`)."""

    name = "numpy"

    def fft_module(self) -> ModuleType:
        return scipy.fft
