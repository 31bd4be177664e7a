"""CuPy array backend: the operators' arrays and transforms on a CUDA GPU.

Install with ``pip install granframe[gpu]`` (CuPy). CuPy is imported when the backend is
built, not when granframe discovers the plugin, so a machine without CuPy or without a GPU
only notices when it asks for this backend (a clear error, not an import failure).

The operators are not rewritten for the GPU. They use ``backend.xp`` and the backend's
transforms, so the same code runs on ``cupy``. The solution stays on the device across
time steps; the runner moves f to the host only when it writes a snapshot, and the
moments as scalars. What this backend changes is how the work is cut and fused:

- transforms through ``cupyx.scipy.fft`` (cuFFT plans cached by CuPy), the inverse
  unnormalised by ``norm="forward"`` instead of a separate scaling pass;
- large batches (:attr:`CuPyBackend.batch_bytes`), so that one cuFFT call and one kernel
  launch cover many (rho, ghat) pairs;
- the two element-wise steps of :class:`granframe.abc.ArrayBackend` as fused CUDA
  kernels (``kernels.cu``), one pass over memory each.

``module = "numpy"`` runs this backend's own code path with NumPy on the host: the same
methods, with ``numpy`` and ``scipy.fft`` (the same call signatures) in place of ``cupy``
and ``cupyx.scipy.fft``, and the generic element-wise steps. That is how the backend is
checked where there is no GPU (tests/test_cupy_backend.py); the CUDA source of the fused
kernels is checked on the host by tests/test_backend_kernels.py.
"""

from __future__ import annotations

import functools
import importlib
import importlib.resources

import attrs
import numpy

from granframe import hookimpl
from granframe import validators as check
from granframe.backends import SciPyFFTBackend
from granframe.errors import BackendUnavailableError

#: Array namespace and its SciPy-style transforms, per ``module``.
MODULES = {"cupy": ("cupy", "cupyx.scipy.fft"), "numpy": ("numpy", "scipy.fft")}

#: Threads per block of the fused kernels, and the most blocks a launch uses (the kernels
#: loop over the rest: 8192 blocks of 256 fill an H100's 132 multiprocessors many times).
THREADS, MAX_BLOCKS = 256, 8192


def _import(module: str):
    try:
        return tuple(importlib.import_module(name) for name in MODULES[module])
    except ImportError as exc:
        raise BackendUnavailableError("array backend 'cupy' needs the cupy package and a CUDA "
                                      "GPU: pip install 'granframe[gpu]'") from exc


def kernel_source() -> str:
    """CUDA source of the fused kernels (``kernels.cu`` beside this module)."""
    return importlib.resources.files(__name__).joinpath("kernels.cu").read_text()


#: CUDA name of each complex dtype in the kernels' templates.
_CUDA_TYPES = {"complex64": "complex<float>", "complex128": "complex<double>"}
_KERNELS = ("separable_product", "lowrank_accumulate")


def device_for(local_rank: int, count: int, first: int = 0) -> int:
    """The CUDA device of the process of local rank ``local_rank`` on a host with
    ``count`` devices, the first process on ``first``: ``(first + local_rank) mod count``.

    The processes of a run on one host take the devices in turn from ``first``, one each
    while there are as many devices as processes; beyond that they share them, in turn.
    A launcher that shows each process its own device alone (Slurm's ``--gpus-per-task``,
    ``CUDA_VISIBLE_DEVICES`` per process) makes ``count`` 1: every process its device 0.

    Raises
    ------
    ValueError
        ``count`` below 1, ``local_rank`` negative, or ``first`` not a device (0 <= first
        < count).
    """
    if not (check.is_integer(count) and count >= 1):
        check.reject("device_for", "count", count, "must be an integer >= 1 (CUDA devices)")
    if not (check.is_integer(local_rank) and local_rank >= 0):
        check.reject("device_for", "local_rank", local_rank, "must be an integer >= 0")
    if not (check.is_integer(first) and 0 <= first < count):
        check.reject("device_for", "first", first,
                     f"must be a device number below the {count} devices here")
    return (int(first) + int(local_rank)) % int(count)


@functools.cache
def _module(device: int):
    """The fused kernels compiled for ``device`` (by CuPy's NVRTC, cached on disk by CuPy)."""
    import cupy

    names = [f"{kernel}<{t}>" for kernel in _KERNELS for t in _CUDA_TYPES.values()]
    with cupy.cuda.Device(device):
        return cupy.RawModule(code=kernel_source(), name_expressions=names)


@attrs.frozen
class CuPyBackend(SciPyFFTBackend):
    """CuPy arrays, cuFFT transforms (plans cached by CuPy), CuPy's memory pool.

    Parameters
    ----------
    device : int
        CUDA device number: of a run in one process, and of the first process on a host
        in a run over several (:meth:`for_process`: the others take the next devices in
        turn, so the default 0 spreads them over all the host's devices).
    memory_limit : int or None
        Largest size in bytes of CuPy's device memory pool, or None for no limit.
    module : str
        ``cupy``, or ``numpy`` to run the same code path on the host (for checks
        without a GPU).
    fused : bool
        Use the fused CUDA kernels for the element-wise steps (on the GPU); False runs
        the generic ``xp`` steps, to compare against them.
    """

    name = "cupy"
    #: 512 MiB of spectra per batch: 3D N = 64 takes 15 rho values (240 pairs) per batch,
    #: N = 128 one rho (16 pairs); the operator's memory_budget still caps it.
    batch_bytes = 2 ** 29
    device: int = attrs.field(default=0, converter=check.to_int,
                              validator=check.integer(lower=0))
    memory_limit: int | None = attrs.field(default=None, converter=check.to_int)
    module: str = attrs.field(default="cupy")
    fused: bool = attrs.field(default=True, validator=check.boolean)
    xp = attrs.field(init=False, repr=False, eq=False)
    fft = attrs.field(init=False, repr=False, eq=False)

    @module.validator
    def _check_module(self, attribute, value):
        """Checked as a field (not when importing it), so a description is checked unbuilt."""
        if value not in MODULES:
            check.reject("CuPyBackend", "module", value, f"must be one of {', '.join(MODULES)}")

    @memory_limit.validator
    def _check_limit(self, attribute, value):
        if value is not None:
            check.integer(lower=1)(self, attribute, value)

    def __attrs_post_init__(self):
        xp, fft = _import(self.module)
        if self.module == "cupy":
            try:
                count = xp.cuda.runtime.getDeviceCount()
            except Exception as exc:          # CUDA driver or runtime missing
                raise BackendUnavailableError(f"array backend 'cupy': no usable CUDA device "
                                              f"({exc})") from None
            if not self.device < count:
                check.reject("CuPyBackend", "device", self.device,
                             f"must be below the number of CUDA devices here, {count}",
                             error=BackendUnavailableError)
            if xp.cuda.runtime.getDevice() != self.device:
                # selecting a device makes its context (hundreds of MiB): not when it is
                # current already, so a backend that for_process moves to another device
                # leaves none behind on device 0
                xp.cuda.Device(self.device).use()
            if self.memory_limit is not None:
                xp.get_default_memory_pool().set_limit(size=self.memory_limit)
        object.__setattr__(self, "xp", xp)
        object.__setattr__(self, "fft", fft)

    @property
    def on_device(self) -> bool:
        return self.module == "cupy"

    def for_process(self, local_rank: int) -> "CuPyBackend":
        """This backend for the process of local rank ``local_rank`` among a run's processes
        on this host (:meth:`granframe.abc.ArrayBackend.for_process`): on device
        :func:`device_for` ``(local_rank, devices here, self.device)``, i.e. process r
        on ``(device + r) mod devices``. The given ``device`` is the first process's
        (of a run in one process, the device), not one that all processes share: with the
        default 0 and as many devices as processes each takes its own, with fewer they
        share them in turn. Itself for local rank 0 and on the host (``module =
        "numpy"``); otherwise a copy (:func:`attrs.evolve`) made on the new device, with
        the same memory limit there."""
        if not self.on_device:
            return self
        device = device_for(local_rank, self.xp.cuda.runtime.getDeviceCount(), self.device)
        return self if device == self.device else attrs.evolve(self, device=device)

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

    def fft_module(self):
        """``cupyx.scipy.fft`` (cuFFT, plans cached by CuPy), or ``scipy.fft`` for
        ``module = "numpy"``: the same calls either way."""
        return self.fft

    @property
    def _uses_kernels(self) -> bool:
        return self.on_device and self.fused

    def _launch(self, kernel: str, out, *arguments):
        """Run a fused kernel of ``kernels.cu`` on ``out``'s elements (grid-stride loop)."""
        function = _module(self.device).get_function(f"{kernel}<{_CUDA_TYPES[out.dtype.name]}>")
        blocks = max(1, min(MAX_BLOCKS, -(-out.size // THREADS)))
        function((blocks,), (THREADS,), (out,) + tuple(
            a if hasattr(a, "dtype") else numpy.int64(a) for a in arguments))

    def _operands(self, out, *arrays):
        """``arrays`` C-contiguous, refused unless of ``out``'s complex dtype."""
        if out.dtype.name not in _CUDA_TYPES or not out.flags.c_contiguous:
            check.reject("CuPyBackend", "out", f"{out.dtype} array",
                         "must be a C-contiguous complex64 or complex128 array", error=TypeError)
        for a in arrays:
            if a.dtype != out.dtype:
                check.reject("CuPyBackend", "operand dtype", str(a.dtype),
                             f"must equal the output's {out.dtype}", error=TypeError)
        return [self.xp.ascontiguousarray(a) for a in arrays]

    def separable_product(self, out, spectrum, head, tail):
        """:meth:`ArrayBackend.separable_product`, one fused kernel on the GPU."""
        if not self._uses_kernels:
            return super().separable_product(out, spectrum, head, tail)
        spectrum, head, tail = self._operands(out, spectrum, head, tail)
        batch, rows, cols = out.shape[-3:]
        distributions = out.shape[0] if out.ndim == 4 else 1
        self._launch("separable_product", out, spectrum, head, tail, batch, rows, cols,
                     distributions)
        return out

    def lowrank_accumulate(self, acc, heads, tails, values):
        """:meth:`ArrayBackend.lowrank_accumulate`, one fused kernel on the GPU (the
        weights formed on the fly, never stored)."""
        if not self._uses_kernels:
            return super().lowrank_accumulate(acc, heads, tails, values)
        heads, tails, values = self._operands(acc, heads, tails, values)
        groups, rows, cols = acc.shape[-3:]
        distributions = acc.shape[0] if acc.ndim == 4 else 1
        batch, _, rank = heads.shape
        self._launch("lowrank_accumulate", acc, heads, tails, values, groups, batch // groups,
                     rows, cols, rank, distributions)
        return acc


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
                             "code path on the host)",
                 examples=[{}, {"module": "numpy"}, {"module": "numpy", "fused": False}])
