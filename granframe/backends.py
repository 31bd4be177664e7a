"""Array backends: an array namespace plus the FFTs the spectral operators need.

Operators are written once against this interface; a backend supplies
``xp`` (a NumPy-compatible namespace) and the transforms. The NumPy backend
is built in; pyFFTW and CuPy backends are plugins. The core never imports
pyfftw or cupy.
"""

from __future__ import annotations

import os

import attrs
import numpy
import scipy.fft

from granframe import validators as check
from granframe.abc import ArrayBackend, RealFFT


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
