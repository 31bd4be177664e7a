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
    """

    name: str
    xp: ModuleType

    def asarray(self, a, dtype=None):
        return self.xp.asarray(a, dtype=dtype)

    def to_numpy(self, a) -> numpy.ndarray:
        return numpy.asarray(a)

    def synchronize(self) -> None:
        """Block until queued work is done (no-op on CPU backends)."""

    def fftn(self, a, axes=None):
        raise NotImplementedError

    def ifftn(self, a, axes=None):
        raise NotImplementedError

    def rfftn(self, a, axes=None):
        raise NotImplementedError

    def irfftn(self, a, s, axes=None):
        raise NotImplementedError


@attrs.frozen
class NumpyBackend(ArrayBackend):
    """NumPy arrays with SciPy's pocketfft transforms run on ``threads`` threads.

    Parameters
    ----------
    threads : int or None
        Worker threads for the FFTs; ``None`` uses every CPU available.
    """

    threads: int | None = attrs.field(default=None, converter=check.to_int)
    name = "numpy"
    xp = numpy

    @threads.validator
    def _check_threads(self, attribute, value):
        if value is not None:
            check.integer(lower=1)(self, attribute, value)

    @property
    def workers(self) -> int:
        return available_cpus() if self.threads is None else self.threads

    def fftn(self, a, axes=None):
        return scipy.fft.fftn(a, axes=axes, workers=self.workers)

    def ifftn(self, a, axes=None):
        return scipy.fft.ifftn(a, axes=axes, workers=self.workers)

    def rfftn(self, a, axes=None):
        return scipy.fft.rfftn(a, axes=axes, workers=self.workers)

    def irfftn(self, a, s, axes=None):
        return scipy.fft.irfftn(a, s=s, axes=axes, workers=self.workers)
