"""MPI for granframe: the processes of a space run as an MPI communicator (mpi4py).

Installed with ``pip install 'granframe[mpi]'``, which brings mpi4py and an MPI library
from the package index (MPICH's ``mpich`` wheel, with its ``mpiexec``). The plugin
registers the communicator ``mpi``; :func:`granframe.parallel.world` creates it when a
launcher started several processes (``mpiexec -n 4 granframe run ...``, ``srun``).
mpi4py is imported, and MPI initialised, only then: importing this plugin imports
neither.

Ghost cells on a device (CuPy arrays) travel as they are through an MPI built with CUDA
support, when ``GRANFRAME_CUDA_AWARE_MPI=1`` says so (or MPICH's ``MPIR_CVAR_ENABLE_GPU=1``
is set); otherwise through host buffers, one per message, made once and reused: the device
array is copied into one before it is sent (``array.get(out=buffer)``) and out of one after
it is received (``array.set(buffer)``), one device->host and one host->device copy per
message (docs/scaling.md). The buffers of a CuPy array are page-locked
(``cupyx.empty_pinned``: the copies run at full speed); any other device array with
CuPy's ``get(out=)`` and ``set`` (the counting backend's stand-ins,
:class:`granframe.testing.transfers.CudaLikeArray`) gets plain ``numpy.empty`` buffers, as
does every array where ``cupyx`` cannot be imported.
"""

from __future__ import annotations

import os

import numpy

from granframe.abc import Communicator, Pending
from granframe.hookspecs import hookimpl

#: "1": the MPI library reads and writes device memory itself (CUDA-aware); "0": it does
#: not, and device arrays travel through host buffers; unset: as MPICH's
#: ``MPIR_CVAR_ENABLE_GPU`` says, else through host buffers
CUDA_AWARE = "GRANFRAME_CUDA_AWARE_MPI"


def cuda_aware(environ=None) -> bool:
    """Whether device arrays are handed to MPI as they are (see :data:`CUDA_AWARE`)."""
    environ = os.environ if environ is None else environ
    if environ.get(CUDA_AWARE, "").strip() in ("0", "1"):
        return environ[CUDA_AWARE].strip() == "1"
    return environ.get("MPIR_CVAR_ENABLE_GPU", "").strip() == "1"


def on_device(array) -> bool:
    """Whether ``array`` lives in device memory (CUDA's array interface)."""
    return hasattr(array, "__cuda_array_interface__")


def _is_cupy(array) -> bool:
    """Whether ``array`` is CuPy's (by its type's module: importing nothing)."""
    return type(array).__module__.split(".")[0] == "cupy"


def host_buffer(array) -> numpy.ndarray:
    """A host array of ``array``'s shape and dtype to stage it through: page-locked for a
    CuPy array (``cupyx.empty_pinned``), ``numpy.empty`` for any other, or when ``cupyx``
    cannot be imported (pinned memory only matters for the copies of a real GPU)."""
    if _is_cupy(array):
        try:
            import cupyx
        except ImportError:
            pass
        else:
            return cupyx.empty_pinned(array.shape, array.dtype)
    return numpy.empty(array.shape, array.dtype)


def _synchronize(array) -> None:
    """Wait for the queued work on ``array``'s device before MPI reads its memory outside
    CuPy's stream (CuPy's current stream; nothing for a device array that is not CuPy's)."""
    if _is_cupy(array):
        import cupy

        cupy.cuda.get_current_stream().synchronize()


class _Requests(Pending):
    """MPI requests in flight, and the received host buffers to copy onto the device."""

    def __init__(self, mpi, requests, staged):
        self.mpi, self.requests, self.staged = mpi, requests, staged

    def wait(self) -> None:
        self.mpi.Request.Waitall(self.requests)
        for array, buffer in self.staged:
            array.set(buffer)


class MPICommunicator(Communicator):
    """The processes of ``MPI.COMM_WORLD`` (see the module notes).

    Parameters
    ----------
    device_aware : bool or None
        Whether device arrays go to MPI as they are; None: :func:`cuda_aware`.
    """

    def __init__(self, device_aware: bool | None = None):
        from mpi4py import MPI

        self.mpi = MPI
        self.comm = MPI.COMM_WORLD
        self.rank, self.size = self.comm.Get_rank(), self.comm.Get_size()
        node = self.comm.Split_type(MPI.COMM_TYPE_SHARED)
        self.local_rank, self.local_size = node.Get_rank(), node.Get_size()
        node.Free()
        self.device_aware = cuda_aware() if device_aware is None else bool(device_aware)
        self._buffers = {}

    def _buffer(self, key, array):
        """The host buffer (:func:`host_buffer`) of the device array ``array``, made once
        per key and remade when the array's shape or dtype changes."""
        buffer = self._buffers.get(key)
        if buffer is None or buffer.shape != array.shape or buffer.dtype != array.dtype:
            buffer = self._buffers[key] = host_buffer(array)
        return buffer

    def start(self, sends, receives) -> Pending:
        """Post the receives, then the sends (see :meth:`Communicator.start`). Device
        arrays go to MPI as they are when :attr:`device_aware`, after one wait for the
        device's queued work (MPI reads and writes their memory outside CuPy's stream:
        the sends' data must be there, and no queued kernel may still use a receive's
        memory); otherwise each is staged through its host buffer, the sends copied into
        theirs here, the receives copied out of theirs by ``wait``."""
        comm, requests, staged = self.comm, [], []
        if self.device_aware:
            device = next((a for _, _, a in list(receives) + list(sends) if on_device(a)),
                          None)
            if device is not None:
                _synchronize(device)
        for peer, tag, array in receives:
            if on_device(array) and not self.device_aware:
                buffer = self._buffer(("in", peer, tag), array)
                staged.append((array, buffer))
                requests.append(comm.Irecv(buffer, source=peer, tag=tag))
            else:
                requests.append(comm.Irecv(array, source=peer, tag=tag))
        for peer, tag, array in sends:
            if on_device(array):
                if self.device_aware:
                    requests.append(comm.Isend(array, dest=peer, tag=tag))
                    continue
                array = array.get(out=self._buffer(("out", peer, tag), array))
            requests.append(comm.Isend(numpy.ascontiguousarray(array), dest=peer, tag=tag))
        return _Requests(self.mpi, requests, staged)

    def allgather(self, vector) -> numpy.ndarray:
        vector = numpy.ascontiguousarray(vector, dtype=float).reshape(-1)
        gathered = numpy.empty((self.size, vector.size))
        self.comm.Allgather(vector, gathered)
        return gathered

    def allgather_object(self, value) -> list:
        return self.comm.allgather(value)

    def bcast(self, value, root: int = 0):
        return self.comm.bcast(value, root=root)

    def abort(self, code: int) -> None:
        """``MPI_Abort``, then leave at once: under MPICH's Hydra the call may return before
        the launcher ends the process, which must not go on."""
        self.comm.Abort(code)
        os._exit(code)

    def __repr__(self) -> str:
        return f"MPICommunicator(rank={self.rank}, size={self.size})"


@hookimpl
def granframe_register_communicators(registry):
    registry.add("mpi", MPICommunicator,
                 description="the processes of MPI.COMM_WORLD (mpi4py), for mpiexec and srun")
