"""An array backend that counts the copies between host and device, on the host.

A GPU backend pays for every copy between host and device memory: a device->host copy
(``.get()``, ``float(a)``, ``bool(a)``, ``a.item()``) also waits for all queued work.
:class:`CountingBackend` runs granframe's code with NumPy, but keeps "device" arrays
(:class:`DeviceArray`) apart from host ones, with CuPy's rules of when data crosses:

- device -> host: :meth:`DeviceArray.get` (into a new array, or into a host buffer with
  ``out=``), ``float``/``int``/``bool``/``complex`` of a device array, ``.item()`` and
  ``.tolist()``;
- host -> device: ``xp.asarray``/``xp.array``/``xp.ascontiguousarray`` of host data,
  :meth:`DeviceArray.set` (a host array copied into a device one), and a host array (not a
  Python scalar) used as an operand of a device operation (CuPy refuses that; here it is
  counted as the copy it would need).

Every crossing is recorded in :attr:`CountingBackend.log` with its direction, shape and a
fingerprint of the data, so a test can tell a copy of a constant array made in every step
from one made once. Operators, transports and reductions run unchanged on it: the
namespace ``xp`` is NumPy with the array-creating functions returning device arrays, and the
transforms are SciPy's on device arrays.

With ``CountingBackend(cuda_interface=True)`` the device arrays are :class:`CudaLikeArray`:
they also expose ``__cuda_array_interface__``, which is how code that hands arrays to other
libraries (the MPI plugin's ghost-cell messages, plugins/granframe_mpi) tells a CuPy array
from a host one. They stand for CuPy arrays there: through the host-staged path
(``get(out=buffer)`` before a send, ``set(buffer)`` after a receive, both counted), or
handed to MPI as they are (a CUDA-aware MPI), which works since they are host memory.

Examples
--------
>>> from granframe.testing.transfers import CountingBackend
>>> backend = CountingBackend()
>>> a = backend.xp.ones(3)            # made on the device: no copy
>>> float(a.sum())                    # one device -> host copy
3.0
>>> backend.counts()
{'to_host': 1, 'to_device': 0}
"""

from __future__ import annotations

import hashlib
from types import ModuleType

import numpy
import scipy.fft

from granframe.backends import SciPyFFTBackend

#: NumPy functions that make new arrays from shapes or values: they return device arrays
_CREATORS = ("zeros", "ones", "empty", "full", "zeros_like", "ones_like", "empty_like",
             "full_like", "arange", "linspace", "eye", "identity")
#: NumPy functions that move host data onto the device (counted when given host data)
_UPLOADS = ("asarray", "array", "ascontiguousarray", "asanyarray")


def _fingerprint(value) -> str:
    data = numpy.ascontiguousarray(value)
    return hashlib.blake2b(data.tobytes() + str(data.shape).encode(), digest_size=8).hexdigest()


class DeviceArray(numpy.ndarray):
    """A NumPy array standing for one in device memory (see the module notes)."""

    #: the backend that counts this array's crossings
    counter: "CountingBackend | None" = None

    def __array_finalize__(self, obj):
        self.counter = getattr(obj, "counter", None)

    def __array_ufunc__(self, ufunc, method, *inputs, out=None, **kwargs):
        counter = next((a.counter for a in inputs + (out or ())
                        if isinstance(a, DeviceArray) and a.counter is not None), None)
        plain = []
        for a in inputs:
            if isinstance(a, DeviceArray):
                plain.append(a.view(numpy.ndarray))
            else:
                if isinstance(a, numpy.ndarray) and a.ndim > 0 and counter is not None:
                    counter._record("to_device", a)
                plain.append(a)
        if out is not None:
            kwargs["out"] = tuple(o.view(numpy.ndarray) if isinstance(o, DeviceArray) else o
                                  for o in out)
        result = getattr(ufunc, method)(*plain, **kwargs)
        if out is not None:
            return out[0] if len(out) == 1 else out
        return _wrap(result, counter, scalars=True)

    def __getitem__(self, key):
        return _wrap(super().__getitem__(key), self.counter, scalars=True)

    def _download(self):
        if self.counter is not None:
            self.counter._record("to_host", self)
        return self.view(numpy.ndarray)

    def get(self, stream=None, order="C", out=None, blocking=True) -> numpy.ndarray:
        """A host copy (one device -> host copy); with ``out``, into that host array of
        this array's shape and dtype, which is returned (CuPy's ``ndarray.get``, whose
        checks of ``out`` it makes)."""
        if out is None:
            return numpy.array(self._download(), order=order)
        self._check_host("get", "out", out, out)
        out[...] = self._download()
        return out

    def set(self, arr, stream=None) -> None:
        """Copy the host array ``arr`` of this array's shape and dtype into it (one host ->
        device copy; CuPy's ``ndarray.set``, whose checks it makes: ``self`` contiguous)."""
        self._check_host("set", "arr", arr, self)
        if self.counter is not None:
            self.counter._record("to_device", arr)
        self.view(numpy.ndarray)[...] = arr

    def _check_host(self, method: str, name: str, host, contiguous) -> None:
        """CuPy's checks of the host array ``host`` of a copy (``get(out=)``, ``set``):
        a host ndarray of this array's dtype and shape, and ``contiguous`` contiguous."""
        owner = f"DeviceArray.{method}"
        if isinstance(host, DeviceArray) or not isinstance(host, numpy.ndarray):
            raise TypeError(f"{owner}: {name} must be a host numpy.ndarray, not "
                            f"{type(host).__name__}")
        if host.dtype != self.dtype:
            raise TypeError(f"{owner}: {name} has dtype {host.dtype}, the array {self.dtype}")
        if host.shape != self.shape:
            raise ValueError(f"{owner}: {name} has shape {host.shape}, the array "
                             f"{self.shape}")
        if not (contiguous.flags.c_contiguous or contiguous.flags.f_contiguous):
            what = "out must be contiguous" if method == "get" else \
                "cannot set a non-contiguous array"
            raise RuntimeError(f"{owner}: {what}")

    def __float__(self):
        return float(self._download())

    def __int__(self):
        return int(self._download())

    def __index__(self):
        return int(self._download())

    def __bool__(self):
        return bool(self._download())

    def __complex__(self):
        return complex(self._download())

    def item(self, *args):
        return self._download().item(*args)

    def tolist(self):
        return self._download().tolist()


class CudaLikeArray(DeviceArray):
    """A :class:`DeviceArray` that exposes ``__cuda_array_interface__``, so that code which
    detects device arrays by it takes this one for a CuPy array (see the module notes).
    The interface describes the array's host memory truthfully (version 3), so a library
    that reads it rather than the buffer protocol gets the right bytes."""

    @property
    def __cuda_array_interface__(self) -> dict:
        contiguous = self.flags.c_contiguous
        return {"shape": self.shape, "typestr": self.dtype.str, "version": 3,
                "data": (self.__array_interface__["data"][0], not self.flags.writeable),
                "strides": None if contiguous else self.strides}


def _wrap(value, counter, scalars: bool = False):
    """Device arrays from NumPy results: arrays as the counter's device arrays
    (:class:`DeviceArray`, or :class:`CudaLikeArray`), and with ``scalars`` also NumPy
    scalars (an element of a device array stays on the device)."""
    if isinstance(value, tuple):
        return tuple(_wrap(v, counter, scalars) for v in value)
    if isinstance(value, numpy.ndarray) or (scalars and isinstance(value, numpy.generic)):
        kind = DeviceArray if counter is None else counter.array_type
        array = numpy.asarray(value).view(kind)
        array.counter = counter
        return array
    return value


class _Namespace(ModuleType):
    """NumPy as the device's array namespace: creators give device arrays, uploads count;
    ``linalg`` is :mod:`numpy.linalg` under the same rules (CuPy's ``cupy.linalg`` works on
    the device)."""

    def __init__(self, backend: "CountingBackend", module=numpy):
        super().__init__("granframe.testing.transfers.xp")
        self._backend, self._module = backend, module

    def __getattr__(self, name):
        if self._module is numpy and name == "linalg":
            return _Namespace(self._backend, numpy.linalg)
        attribute = getattr(self._module, name)
        backend = self._backend
        if name in _UPLOADS:
            def upload(a, *args, **kwargs):
                if isinstance(a, DeviceArray):
                    return _wrap(attribute(a.view(numpy.ndarray), *args, **kwargs), backend)
                if isinstance(a, numpy.ndarray) or isinstance(a, (list, tuple)):
                    backend._record("to_device", numpy.asarray(a))
                return _wrap(attribute(a, *args, **kwargs), backend, scalars=True)
            return upload
        if name in _CREATORS:
            return lambda *args, **kwargs: _wrap(attribute(*args, **kwargs), backend, scalars=True)
        if callable(attribute) and not isinstance(attribute, type):
            def device(*args, **kwargs):
                arrays = [a for a in args if isinstance(a, numpy.ndarray)]
                if any(isinstance(a, DeviceArray) for a in arrays):
                    for a in arrays:
                        if not isinstance(a, DeviceArray) and a.ndim > 0:
                            backend._record("to_device", a)
                return _wrap(attribute(*args, **kwargs), backend, scalars=True)
            return device
        return attribute


class _FFTModule(ModuleType):
    """:mod:`scipy.fft` on device arrays: device arrays in, device arrays out."""

    def __init__(self, backend: "CountingBackend"):
        super().__init__("granframe.testing.transfers.fft")
        self._backend = backend

    def __getattr__(self, name):
        function = getattr(scipy.fft, name)

        def transform(a, *args, **kwargs):
            plain = a.view(numpy.ndarray) if isinstance(a, DeviceArray) else a
            return _wrap(function(plain, *args, **kwargs), self._backend, scalars=True)
        return transform


class CountingBackend(SciPyFFTBackend):
    """NumPy and SciPy's transforms, with every host/device crossing counted.

    Parameters
    ----------
    cuda_interface : bool
        Make the device arrays :class:`CudaLikeArray` (with ``__cuda_array_interface__``,
        standing for CuPy arrays where arrays leave the backend) rather than plain
        :class:`DeviceArray`.

    Attributes
    ----------
    log : list
        ``(direction, shape, fingerprint)`` of each crossing, ``direction`` "to_host" or
        "to_device", in order.
    array_type : type
        The class of the device arrays.
    """

    name = "counting"
    concurrency = 1
    on_device = True

    def __init__(self, cuda_interface: bool = False):
        self.log = []
        self.array_type = CudaLikeArray if cuda_interface else DeviceArray
        self.xp = _Namespace(self)
        self._fft = _FFTModule(self)

    def _record(self, direction: str, value) -> None:
        self.log.append((direction, tuple(numpy.shape(value)), _fingerprint(value)))

    def fft_module(self) -> ModuleType:
        return self._fft

    def asarray(self, a, dtype=None):
        return self.xp.asarray(a, dtype=dtype)

    def to_numpy(self, a) -> numpy.ndarray:
        return a.get() if isinstance(a, DeviceArray) else numpy.asarray(a)

    def counts(self, since: int = 0) -> dict:
        """The crossings of each direction recorded after the first ``since`` entries."""
        entries = self.log[since:]
        return {direction: sum(1 for e in entries if e[0] == direction)
                for direction in ("to_host", "to_device")}

    def reset(self) -> None:
        """Forget the crossings recorded so far."""
        self.log.clear()
