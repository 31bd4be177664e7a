"""The conformance check of communicators: ranks and sizes, the collective operations
(gathers and broadcasts) and the point-to-point messages of a halo exchange.
"""

from __future__ import annotations

import numpy

from granframe.abc import Communicator, Pending
from granframe.testing.conformance.common import require, require_contract


def check_communicator(communicator) -> None:
    """The contract of :class:`granframe.abc.Communicator`, in one process or several
    (collective: every process of the communicator calls it, at once):

    - ``rank``, ``size`` and ``local_rank`` whole numbers, 0 <= rank, local_rank < size;
    - ``allgather`` of a float64 vector: shape (size, n), row r process r's vector;
      ``allgather_object``: a list of size values in rank order; ``bcast``: process 0's
      value (and that of the last process, as ``root``) in every process;
    - ``start``: a ring of messages as a halo posts them (contiguous views of one block
      array): each process sends two messages, tags 0 and 1, to the next process and
      receives two from the previous one, posted in the other order, into views of its
      own array; it returns a :class:`~granframe.abc.Pending` at once, and after
      ``wait`` each receive holds the message of its tag, unchanged by later writes to
      the sent arrays; nothing else of the array is written. With one process the ring is
      the process itself.
    """
    name = type(communicator).__name__
    require(isinstance(communicator, Communicator),
            f"{communicator!r} is not a granframe.abc.Communicator")
    require_contract("communicators", communicator)
    _check_ranks(communicator, name)
    _check_collectives(communicator, name)
    _check_messages(communicator, name)


def _check_ranks(communicator, name: str) -> None:
    """``rank``, ``size`` and ``local_rank`` whole numbers, 0 <= rank, local_rank < size."""
    rank, size, local = communicator.rank, communicator.size, communicator.local_rank
    require(all(isinstance(v, (int, numpy.integer)) and not isinstance(v, bool)
                for v in (rank, size, local)),
            f"{name}: rank, size and local_rank must be whole numbers, got {rank!r}, "
            f"{size!r}, {local!r}")
    require(size >= 1 and 0 <= rank < size and 0 <= local < size,
            f"{name}: rank = {rank} and local_rank = {local} must lie in [0, size = {size})")


def _check_collectives(communicator, name: str) -> None:
    """``allgather`` of a float64 vector, ``allgather_object``, and ``bcast`` from process 0
    and from the last process (:func:`check_communicator`)."""
    rank, size = communicator.rank, communicator.size
    vector = numpy.array([rank, 0.5 * rank, -1.0, 1e300])
    gathered = numpy.asarray(communicator.allgather(vector))
    expected = numpy.array([[r, 0.5 * r, -1.0, 1e300] for r in range(size)])
    require(gathered.shape == expected.shape and numpy.array_equal(gathered, expected),
            f"{name}: allgather of a vector of 4 floats must give each process's vector as "
            f"row rank of a ({size}, 4) array, got {gathered!r}")
    values = communicator.allgather_object({"rank": rank, "cells": (rank, rank + 1)})
    require(list(values) == [{"rank": r, "cells": (r, r + 1)} for r in range(size)],
            f"{name}: allgather_object must give every process's value in rank order, "
            f"got {values!r}")
    for root in sorted({0, size - 1}):
        value = communicator.bcast({"from": rank, "data": [rank] * 3}, root=root)
        require(value == {"from": root, "data": [root] * 3},
                f"{name}: bcast(root={root}) must give process {root}'s value in every "
                f"process, got {value!r} in process {rank}")


def _check_messages(communicator, name: str) -> None:
    """``start`` and ``wait`` on a ring of two messages per process, posted as a halo posts
    them (:func:`check_communicator`)."""
    rank, size = communicator.rank, communicator.size
    after, before = (rank + 1) % size, (rank - 1) % size
    shape = (2, 9, 3, 4)                 # blocks, cells with ghosts, velocity nodes

    def sent(r):
        return 1000.0 * r + numpy.arange(numpy.prod(shape), dtype=float).reshape(shape)

    array = sent(rank)
    sends = [(after, 0, array[-1, 4:6]), (after, 1, array[0, 2:4])]
    into = numpy.full(shape, numpy.nan)
    receives = [(before, 1, into[0, 7:9]), (before, 0, into[-1, :2])]
    pending = communicator.start(sends, receives)
    require(isinstance(pending, Pending),
            f"{name}: start must return a granframe.abc.Pending, got {pending!r}")
    pending.wait()
    array[...] = -1.0                    # the messages are complete: the buffers are free
    other = sent(before)
    require(numpy.array_equal(into[-1, :2], other[-1, 4:6])
            and numpy.array_equal(into[0, 7:9], other[0, 2:4]),
            f"{name}: after wait each receive must hold the message of its tag from its "
            f"peer (matched by (peer, tag), not by the order of posting)")
    written = numpy.zeros(shape, dtype=bool)
    written[-1, :2] = written[0, 7:9] = True
    require(bool(numpy.all(numpy.isnan(into[~written]))),
            f"{name}: start wrote outside the receive arrays")
