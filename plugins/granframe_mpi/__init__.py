"""MPI for granframe: the processes of a space run as an MPI communicator (mpi4py).

Installed with ``pip install 'granframe[mpi]'``, which brings mpi4py and an MPI library
from the package index (MPICH's ``mpich`` wheel, with its ``mpiexec``). The plugin
registers the communicator ``mpi``; :func:`granframe.parallel.world` creates it when a
launcher started several processes (``mpiexec -n 4 granframe run ...``, ``srun``).
mpi4py is imported, and MPI initialised, only then: importing this plugin imports
neither.

Ghost cells on a device (CuPy arrays) travel as they are through an MPI built with CUDA
support, when ``GRANFRAME_CUDA_AWARE_MPI=1`` says so (or MPICH's ``MPIR_CVAR_ENABLE_GPU=1``
is set); otherwise through page-locked host buffers, one per message, made once and
reused: the device array is copied into one before it is sent and out of one after it is
received (docs/scaling.md).
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
        self.local_rank = node.Get_rank()
        node.Free()
        self.device_aware = cuda_aware() if device_aware is None else bool(device_aware)
        self._buffers = {}

    def _buffer(self, key, array):
        """A page-locked host buffer for the device array ``array`` (made once per key)."""
        buffer = self._buffers.get(key)
        if buffer is None or buffer.shape != array.shape or buffer.dtype != array.dtype:
            import cupyx

            buffer = self._buffers[key] = cupyx.empty_pinned(array.shape, array.dtype)
        return buffer

    def start(self, sends, receives) -> Pending:
        comm, requests, staged, synchronized = self.comm, [], [], False
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
                    if not synchronized:      # MPI reads the memory outside CuPy's stream
                        import cupy

                        cupy.cuda.get_current_stream().synchronize()
                        synchronized = True
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
        self.comm.Abort(code)

    def __repr__(self) -> str:
        return f"MPICommunicator(rank={self.rank}, size={self.size})"


@hookimpl
def granframe_register_communicators(registry):
    registry.add("mpi", MPICommunicator,
                 description="the processes of MPI.COMM_WORLD (mpi4py), for mpiexec and srun")
