"""CuPy array backend: the operators' arrays and transforms on a CUDA GPU.

Install with ``pip install granframe[gpu]`` (CuPy). CuPy is imported when the backend is
built, not when granframe discovers the plugin, so a machine without CuPy or without a GPU
only notices when it asks for this backend (a clear error, not an import failure).

The operators are not rewritten for the GPU. They use ``backend.xp`` and the backend's
transforms, so the same code runs on ``cupy``. The solution stays on the device across
time steps; the runner moves f to the host only when it writes a snapshot, and the
moments as scalars.

``module = "numpy"`` runs this backend's own code path with NumPy on the host: the same
methods, with ``numpy`` and ``numpy.fft`` in place of ``cupy`` and ``cupy.fft``. That is how
the backend is checked where there is no GPU (tests/test_cupy_backend.py).
"""

from __future__ import annotations

import importlib

import attrs
import numpy

from granframe import hookimpl
from granframe import validators as check
from granframe.backends import ArrayBackend

MODULES = ("cupy", "numpy")


def _import(module: str):
    if module not in MODULES:
        check.reject("CuPyBackend", "module", module, f"must be one of {', '.join(MODULES)}")
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ValueError("array backend 'cupy' needs the cupy package and a CUDA GPU: "
                         "pip install 'granframe[gpu]'") from exc


@attrs.frozen
class CuPyBackend(ArrayBackend):
    """CuPy arrays, cuFFT transforms (plans cached by CuPy), CuPy's memory pool.

    Parameters
    ----------
    device : int
        CUDA device number.
    memory_limit : int or None
        Largest size in bytes of CuPy's device memory pool, or None for no limit.
    module : str
        ``cupy``, or ``numpy`` to run the same code path on the host (for checks
        without a GPU).
    """

    name = "cupy"
    device: int = attrs.field(default=0, converter=check.to_int,
                              validator=check.integer(lower=0))
    memory_limit: int | None = attrs.field(default=None, converter=check.to_int)
    module: str = attrs.field(default="cupy")
    xp = attrs.field(init=False, repr=False, eq=False)

    @memory_limit.validator
    def _check_limit(self, attribute, value):
        if value is not None:
            check.integer(lower=1)(self, attribute, value)

    def __attrs_post_init__(self):
        xp = _import(self.module)
        if self.module == "cupy":
            try:
                count = xp.cuda.runtime.getDeviceCount()
            except Exception as exc:          # CUDA driver or runtime missing
                raise ValueError(f"array backend 'cupy': no usable CUDA device ({exc})") from None
            if not self.device < count:
                check.reject("CuPyBackend", "device", self.device,
                             f"must be below the number of CUDA devices, {count}")
            xp.cuda.Device(self.device).use()
            if self.memory_limit is not None:
                xp.get_default_memory_pool().set_limit(size=self.memory_limit)
        object.__setattr__(self, "xp", xp)

    @property
    def on_device(self) -> bool:
        return self.module == "cupy"

    def to_numpy(self, a) -> numpy.ndarray:
        return self.xp.asnumpy(a) if self.on_device else numpy.asarray(a)

    def synchronize(self) -> None:
        if self.on_device:
            self.xp.cuda.get_current_stream().synchronize()

    def elapsed(self, function) -> float:
        """Seconds one call of ``function`` takes on the device: CUDA events on the current
        stream (host wall time for ``module = "numpy"``)."""
        if not self.on_device:
            return super().elapsed(function)
        start, end = self.xp.cuda.Event(), self.xp.cuda.Event()
        start.record()
        function()
        end.record()
        end.synchronize()
        return self.xp.cuda.get_elapsed_time(start, end) / 1e3

    def device_memory(self) -> int | None:
        """Bytes held by CuPy's memory pool (None on the host)."""
        return int(self.xp.get_default_memory_pool().total_bytes()) if self.on_device else None

    def fftn(self, a, axes=None):
        return self.xp.fft.fftn(a, axes=axes)

    def ifftn(self, a, axes=None):
        return self.xp.fft.ifftn(a, axes=axes)

    def rfftn(self, a, axes=None):
        return self.xp.fft.rfftn(a, axes=axes)

    def irfftn(self, a, s, axes=None):
        return self.xp.fft.irfftn(a, s=s, axes=axes)


def gpu_available() -> bool:
    """Whether CuPy is installed and sees a CUDA device (for skipping GPU checks)."""
    try:
        import cupy
        return cupy.cuda.runtime.getDeviceCount() > 0
    except Exception:
        return False


@hookimpl
def granframe_register_array_backends(registry):
    registry.add("cupy", CuPyBackend,
                 description="CuPy arrays and cuFFT on a CUDA GPU (module='numpy': the same "
                             "code path on the host)")
