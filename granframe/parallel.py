r"""A space run spread over processes: who owns which cells, and the ghost cells between them.

A space run on P processes cuts the cells [0, cells) into P contiguous ranges of whole
store chunks (:func:`partition`); process r owns range r, steps it, and writes its
chunks of the store. Collisions are local to a cell and the transport reads ``ghost``
cells beyond each end of a range (the reconstruction's stencil), so the only messages of
a step are the ghost cells of the ends of each range (:class:`Halo`, before each
transport stage: six per step) and one reduction of the totals
(:meth:`~granframe.abc.Communicator.allgather` of a few numbers per process). That is
domain decomposition with halo exchange (W. Gropp, E. Lusk, A. Skjellum, *Using MPI*,
3rd ed., MIT Press 2014, ch. 4).

:func:`world` gives the processes this one was launched with: :class:`SerialCommunicator`
(one process) unless an MPI launcher (``mpiexec``, ``srun``) started several, which it
tells from the launcher's environment (:func:`launched`) without importing an MPI
library; then the plugin registered as ``communicators`` ``mpi`` (``pip install
granframe[mpi]``) gives the MPI communicator. The core never imports mpi4py.
"""

from __future__ import annotations

import math
import os
import time

import numpy

from granframe import validators as check
from granframe.abc import Communicator, Pending
from granframe.abc.space import AXIS_NAMES, Side

#: environment variables by which launchers tell a process how many were started and its
#: number: MPICH's Hydra and Intel MPI (PMI), Open MPI, MVAPICH, and Slurm's srun (set in
#: a job step only, not in the batch script that calls srun)
LAUNCHER_VARIABLES = (("PMI_SIZE", "PMI_RANK"), ("OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK"),
                      ("MV2_COMM_WORLD_SIZE", "MV2_COMM_WORLD_RANK"),
                      ("SLURM_STEP_NUM_TASKS", "SLURM_PROCID"))

#: the message tags of the ghost cells: sent towards the right neighbour (the receiver's
#: left ghosts), towards the left one (its right ghosts)
RIGHTWARD, LEFTWARD = 0, 1


def launched(environ=None) -> tuple[int, int, str | None]:
    """``(size, rank, variable)``: how many processes a launcher started, this one's
    number and the variable that said so; ``(1, 0, None)`` outside a launcher."""
    environ = os.environ if environ is None else environ
    for size_name, rank_name in LAUNCHER_VARIABLES:
        size = environ.get(size_name, "")
        if size.strip().isdigit() and int(size) > 1:
            rank = environ.get(rank_name, "0")
            return int(size), int(rank) if rank.strip().isdigit() else 0, size_name
    return 1, 0, None


class _Done(Pending):
    def wait(self) -> None:
        """Nothing in flight."""


class SerialCommunicator(Communicator):
    """One process: the collectives return its own values, and a message to itself is a
    copy (posted at :meth:`start`, so the receive buffer holds it at once)."""

    rank, size, local_rank, local_size = 0, 1, 0, 1

    def start(self, sends, receives) -> Pending:
        sent = {tag: array for peer, tag, array in sends if peer == 0}
        for peer, tag, array in receives:
            if peer != 0 or tag not in sent:
                check.reject("SerialCommunicator.start", "receives", (peer, tag),
                             "must match a send of this process (the only one)")
            array[...] = sent[tag]
        return _Done()

    def allgather(self, vector) -> numpy.ndarray:
        return numpy.asarray(vector, dtype=float).reshape(1, -1)

    def allgather_object(self, value) -> list:
        return [value]

    def bcast(self, value, root: int = 0):
        return value

    def __repr__(self) -> str:
        return "SerialCommunicator()"


_WORLD: list = []


def world() -> Communicator:
    """The processes this one runs with (see the module notes), made once per process.

    Raises
    ------
    ValueError
        A launcher started several processes and no ``mpi`` communicator is installed, or
        MPI sees fewer processes than the launcher started (mpi4py built against another
        MPI than the launcher's: every process would run the whole problem alone).
    """
    if _WORLD:
        return _WORLD[0]
    size, rank, variable = launched()
    if size == 1:
        communicator = SerialCommunicator()
    else:
        from granframe.registry import default_registries

        registries = default_registries()
        if "mpi" not in registries.names("communicators"):
            raise ValueError(f"granframe: this process is rank {rank} of {size} ({variable} = "
                             f"{size}), and no MPI communicator is installed: pip install "
                             "'granframe[mpi]' (mpi4py with an MPI from the package index)")
        communicator = registries.create("communicators", "mpi")
        if communicator.size != size:
            raise ValueError(f"granframe: the launcher started {size} processes ({variable}) "
                             f"but MPI sees {communicator.size}: mpiexec and mpi4py belong to "
                             "different MPI libraries; use the mpiexec of the MPI that mpi4py "
                             "was built with (with granframe[mpi], the one installed beside it)")
    _WORLD.append(communicator)
    return communicator


#: the attribute by which an exception says it was raised in every process at the same
#: point (:func:`in_every_process`, ``granframe.run.storage.collective``): the processes
#: stop together, and one of them speaks for all
RAISED_EVERYWHERE = "granframe_raised_everywhere"


def raised_everywhere(exc: BaseException) -> BaseException:
    """``exc`` marked as raised in every process (:data:`RAISED_EVERYWHERE`)."""
    try:
        setattr(exc, RAISED_EVERYWHERE, True)
    except AttributeError:      # an exception type without a __dict__: left unmarked
        pass
    return exc


def in_every_process(communicator: Communicator, function):
    """``function()`` run by every process; when it raises in any of them, every process
    raises, so that none waits for the others in a later collective: the failing process
    its own exception, the others one of the same built-in type (ValueError, TypeError,
    OSError; else RuntimeError) with the first failing process's message and its number,
    all marked :func:`raised_everywhere`. One allgather of a small object when several
    processes run; KeyboardInterrupt passes through."""
    try:
        value, error = function(), None
    except Exception as exc:       # reported to every process below
        value, error = None, exc
    if communicator.size == 1:
        if error is not None:
            raise error
        return value
    kinds = (ValueError, TypeError, OSError)
    summary = None if error is None else (
        next((k.__name__ for k in kinds if isinstance(error, k)), "RuntimeError"), str(error))
    failures = [(rank, s) for rank, s in enumerate(communicator.allgather_object(summary))
                if s is not None]
    if not failures:
        return value
    if error is not None:
        raise raised_everywhere(error)
    rank, (kind, message) = failures[0]
    raise raised_everywhere({"ValueError": ValueError, "TypeError": TypeError,
                             "OSError": OSError}.get(kind, RuntimeError)(
        f"{message} (in process {rank} of {communicator.size})"))


def partition(cells: int, chunk: int, processes: int, ghost: int,
              counts=None, axis: int = 0) -> list[tuple[int, int]]:
    """The cells ``(start, stop)`` of each process: contiguous, whole chunks, in rank order.

    Parameters
    ----------
    cells : int
        The cells of the axis.
    chunk : int
        The width along the axis of the store's chunks (``space.block_cells``): each
        process writes whole chunks, so each range starts and ends on a chunk boundary.
    processes : int
        The number of processes that share the axis.
    ghost : int
        The reconstruction's ghost width: each range must hold at least that many cells,
        since its ghost cells come from the next range alone.
    counts : sequence of int, optional
        The cells of each process, given explicitly; by default the chunks are shared as
        evenly as possible (the first ``chunks mod processes`` processes one more).
    axis : int, optional
        The space axis (0: x), which the messages name.

    Raises
    ------
    ValueError
        More processes than cells or than chunks, or ``counts`` that do not cut the
        cells into ranges of whole chunks of at least ``ghost`` cells, one per process.
    """
    owner = "partition"
    if processes > cells:
        check.reject(owner, "processes", processes, f"must be at most space.cells = {cells}: "
                     "each process owns at least one cell")
    chunks = cells // chunk
    if processes > chunks:
        check.reject(owner, "processes", processes, f"must be at most the {chunks} chunks of "
                     f"space.block_cells = {chunk} cells that the store is cut into along "
                     f"{AXIS_NAMES[axis]} "
                     f"(each process writes whole chunks): set space.block_cells to a divisor "
                     f"of {cells} of at most {cells // processes}, or run on fewer processes")
    if counts is None:
        base, extra = divmod(chunks, processes)
        counts = [chunk * (base + (r < extra)) for r in range(processes)]
    else:
        counts = [int(c) if check.is_integer(c) else c for c in counts]
        if (len(counts) != processes or not all(check.is_integer(c) and c > 0 for c in counts)
                or sum(counts) != cells or any(c % chunk for c in counts)):
            check.reject(owner, "partition", list(counts), f"must give the cells of each of "
                         f"the {processes} processes, multiples of space.block_cells = "
                         f"{chunk} adding up to space.cells = {cells}")
    if min(counts) < ghost:
        check.reject(owner, "partition", list(counts), f"must give every process at least "
                     f"{ghost} cells, the reconstruction's ghost width (a range's ghost cells "
                     "come from the next range alone)")
    stops = numpy.cumsum(counts).tolist()
    return [(stop - count, stop) for count, stop in zip(counts, stops)]


def cell_divisors(cells: int, low: int, high: int | None = None) -> list[int]:
    """The divisors of ``cells`` from ``low`` to ``high`` (``cells`` by default), in
    increasing order: the block and chunk widths that cut the cells into equal parts.
    Found in pairs (b, cells / b) with b up to sqrt(cells): 31623 trials for 1e9 cells."""
    high = cells if high is None else high
    pairs = [b for b in range(1, math.isqrt(cells) + 1) if cells % b == 0]
    divisors = sorted(set(pairs) | {cells // b for b in pairs})
    return [b for b in divisors if low <= b <= high]


def store_chunk(cells: int, ghost: int, block_cells: int | None = None) -> int:
    """The store's chunk width along a space axis: ``block_cells``, or by default the
    largest divisor of ``cells`` from ``ghost`` to min(64, cells / 16), so that the axis has
    about 16 chunks or more to share among processes (each writes whole chunks:
    :func:`partition`), and otherwise the smallest divisor from ``ghost`` (all cells when
    there is none)."""
    if block_cells is not None:
        return block_cells
    ghost = max(ghost, 1)
    divisors = cell_divisors(cells, ghost)
    small = [b for b in divisors if b <= min(64, max(ghost, cells // 16))]
    return small[-1] if small else divisors[0]


def batch_block(owned: int, ghost: int, block_cells: int | None = None) -> int:
    """The cells per block of a process's batched transport
    (:class:`~granframe.space.domain.Domain`): ``block_cells`` when given (then equal to
    the store's chunk), else the largest divisor of its ``owned`` cells from ``ghost`` to
    64 (all of them when there is none). Larger than the store's chunk by default: the
    blocks only batch the transport, the ghost cells between blocks are copies, so the
    result does not depend on them, and fewer blocks copy fewer ghosts."""
    if block_cells is not None:
        return block_cells
    divisors = cell_divisors(owned, max(ghost, 1), min(owned, 64))
    return divisors[-1] if divisors else owned


class CellLayout:
    """How the cells of a space axis are cut, in one place: the store's chunks, the
    ranges of the processes that share the axis (whole chunks, :func:`partition`) and this
    process's batch blocks (:func:`batch_block`), as Dedalus's distributor holds its
    layouts; a store resumed by these processes is checked against their ranges by
    :func:`check_store_chunks`. A serial run is the case of one process owning every cell;
    a decomposition of several axes is one layout per axis, each with the processes along
    it and this one's place among them.

    Parameters
    ----------
    cells, ghost : int
        The cells of the axis and the reconstruction's ghost width.
    processes, index : int
        The processes that share the axis, and this one's place among them (in one space
        dimension the communicator's size and rank).
    block_cells : int or None
        The description's ``space.block_cells`` (None: the defaults of :func:`store_chunk`
        and :func:`batch_block`).
    counts : sequence of int, optional
        The cells of each process (:func:`partition`).
    axis : int, optional
        The space axis (0: x).

    Attributes
    ----------
    chunk : int
        The store's chunk width along the axis.
    ranges : list of (int, int)
        The cells (start, stop) of every process along the axis, in order.
    block : int
        The cells per batch block of this process.
    """

    def __init__(self, cells: int, ghost: int, processes: int, index: int,
                 block_cells: int | None = None, counts=None, axis: int = 0):
        if not (check.is_integer(index) and check.is_integer(processes)
                and 0 <= index < processes):
            check.reject("CellLayout", "index", index, f"must be this process's place among "
                         f"the {processes} processes along the axis, 0 to {processes - 1}")
        self.axis = int(axis)
        self.chunk = store_chunk(cells, ghost, block_cells)
        self.ranges = partition(cells, self.chunk, processes, ghost, counts, self.axis)
        self.start, self.stop = self.ranges[index]
        self.block = batch_block(self.stop - self.start, ghost, block_cells)

    @property
    def owned(self) -> slice:
        """The cells this process owns."""
        return slice(self.start, self.stop)


def check_store_chunks(ranges, chunk: int, cells, path, axis: int = 0) -> None:
    """Refuse to let processes with the cells ``ranges`` share a store chunked by
    ``chunk`` cells along ``axis`` (of ``cells``) whose chunks do not fall on the
    boundaries of their ranges (a store made with another ``block_cells``): each process
    writes whole chunks (:func:`partition`)."""
    starts = [a for a, _ in ranges]
    if any(start % chunk for start in starts):
        check.reject("run", "processes", len(ranges), f"cannot share the store '{path}' "
                     f"among themselves: it is chunked by {chunk} cells along "
                     f"{AXIS_NAMES[axis]}, and the "
                     f"cells of the processes start at {starts}; each must start at a "
                     f"multiple of {chunk} (run on a number of processes that divides "
                     f"{cells} // {chunk} chunks, or give the partition)")


def process_grid(processes: int, cells, chunks, ghost: int) -> tuple:
    """The processes along each axis (P_x, P_y[, P_z]) of a block decomposition of
    ``processes`` processes over ``cells`` cells cut into store chunks of ``chunks`` cells:
    among the factorisations whose blocks hold whole chunks of at least ``ghost`` cells,
    the one whose cuts cross the fewest cell faces, sum_a (P_a - 1) prod_{b != a} C_b,
    the cells a step's ghost exchange sends (near square on a square, more cuts across the
    shorter side otherwise); the first such in lexicographic order on a tie.

    Raises
    ------
    ValueError
        No factorisation fits: more processes than the chunks can be shared by.
    """
    cells, chunks = tuple(int(c) for c in cells), tuple(int(c) for c in chunks)
    best = None
    for counts in _factorisations(int(processes), len(cells)):
        if any(p > c // k or (c // k) // p * k < ghost
               for p, c, k in zip(counts, cells, chunks)):
            continue
        crossed = sum((p - 1) * math.prod(c for b, c in enumerate(cells) if b != a)
                      for a, p in enumerate(counts))
        if best is None or crossed < best[0]:
            best = (crossed, counts)
    if best is None:
        shares = " x ".join(f"{c // k}" for c, k in zip(cells, chunks))
        check.reject("process_grid", "processes", processes, f"must factor into processes "
                     f"along each axis that share its store chunks ({shares} chunks of "
                     f"{' x '.join(map(str, chunks))} cells), at least {ghost} cells each: "
                     "run on fewer processes, or give space.block_cells smaller chunks")
    return best[1]


def _factorisations(number: int, parts: int):
    """Every ordered tuple of ``parts`` positive integers whose product is ``number``."""
    if parts == 1:
        yield (number,)
        return
    for first in range(1, number + 1):
        if number % first == 0:
            for rest in _factorisations(number // first, parts - 1):
                yield (first,) + rest


class BoxHalo:
    """The ghost strips of the sides of an owned block that other processes own: the
    ``neighbours`` of a :class:`~granframe.space.domain.Box` in a block decomposition.

    The processes form a grid of ``counts`` (P_x, P_y[, P_z]) in C order (rank
    r = i_x P_y + i_y); the block of place (i_x, i_y) has the neighbours i_x +- 1 along x
    and i_y +- 1 along y (wrapped on a periodic axis, none at a wall). Along axis a the
    ghost-width strip of owned cells at the lower side goes to the lower neighbour with
    tag 2a + 1 and fills that neighbour's upper ghosts; the strip at the upper side goes
    to the upper neighbour with tag 2a and fills its lower ghosts. The strips across y are
    not contiguous in the block: each is sent from a contiguous copy and received into
    one, copied into the ghosts when the exchange completes (the
    :class:`~granframe.abc.Communicator` posts contiguous arrays).

    Parameters
    ----------
    communicator : Communicator
    peers : sequence of (int or None)
        The rank beyond each side of :attr:`Box.sides <granframe.space.domain.Box.sides>`
        (left, right, bottom, top), None at a wall.

    Attributes
    ----------
    seconds : float
        Wall time spent posting and completing the exchanges.
    exchanges : int
        The exchanges made.
    """

    def __init__(self, communicator: Communicator, peers):
        self.communicator, self.peers = communicator, tuple(peers)
        self.seconds, self.exchanges = 0.0, 0

    @classmethod
    def of(cls, communicator: Communicator, counts, periodic) -> BoxHalo:
        """The halo of this process in the process grid ``counts``; ``periodic``: whether
        each axis is."""
        counts = tuple(int(c) for c in counts)
        place = numpy.unravel_index(communicator.rank, counts)
        peers = []
        for axis, (count, wraps) in enumerate(zip(counts, periodic)):
            for step in (-1, 1):
                i = int(place[axis]) + step
                if not 0 <= i < count:
                    if not wraps:
                        peers.append(None)
                        continue
                    i %= count
                other = list(place)
                other[axis] = i
                peers.append(int(numpy.ravel_multi_index(tuple(other), counts)))
        return cls(communicator, peers)

    def start(self, box, array, sides) -> Pending:
        """Post the exchange of the ghost strips of ``sides`` (of ``box.sides``) of the
        block array ``array``."""
        began = time.perf_counter()
        g, xp = box.ghost, box.xp
        sends, receives, fills = [], [], []
        for side in map(Side.named, sides):
            view = box.along(array, side.axis)
            n = box.sizes[side.axis]
            peer = self.peers[2 * side.axis + side.end]
            if side.end == 0:
                strip, ghosts, out, back = view[g:2 * g], view[:g], LEFTWARD, RIGHTWARD
            else:
                strip, ghosts, out, back = view[n:n + g], view[g + n:], RIGHTWARD, LEFTWARD
            buffer = xp.empty(ghosts.shape)
            sends.append((peer, 2 * side.axis + out, xp.ascontiguousarray(strip)))
            receives.append((peer, 2 * side.axis + back, buffer))
            fills.append((ghosts, buffer))
        pending = self.communicator.start(sends, receives)
        self.seconds += time.perf_counter() - began
        self.exchanges += 1
        return _Filled(_Timed(pending, self), fills)


class _Filled(Pending):
    """A pending exchange whose receive buffers are copied into the ghosts it completes."""

    def __init__(self, pending: Pending, fills):
        self.pending, self.fills = pending, fills

    def wait(self) -> None:
        self.pending.wait()
        for ghosts, buffer in self.fills:
            ghosts[...] = buffer


class Halo:
    """The ghost cells of the ends of an owned range that other processes own: the
    ``neighbours`` of a :class:`~granframe.space.domain.Domain`.

    Parameters
    ----------
    communicator : Communicator
    left, right : int or None
        The ranks that own the cells below ``start`` and above ``stop`` along the domain's
        axis (the last and the first for a periodic axis), None at a wall.

    Attributes
    ----------
    seconds : float
        Wall time spent posting and completing the exchanges (the part not hidden
        behind the local ghost fills), summed over the exchanges.
    exchanges : int
        The exchanges made.
    """

    def __init__(self, communicator: Communicator, left: int | None, right: int | None):
        self.communicator, self.left, self.right = communicator, left, right
        self.seconds, self.exchanges = 0.0, 0

    @classmethod
    def of(cls, communicator: Communicator, ranges, periodic: bool) -> "Halo":
        """The halo of this process for the ranges of :func:`partition`."""
        rank, size = communicator.rank, communicator.size
        left = rank - 1 if rank > 0 else (size - 1 if periodic else None)
        right = rank + 1 if rank < size - 1 else (0 if periodic else None)
        return cls(communicator, left, right)

    def start(self, domain, array, sides) -> Pending:
        """Post the exchange of the ghost cells of ``sides`` (of ``domain.sides``, or their
        names) of the block array ``array``: this range's first (last) ``ghost`` cells go to
        the neighbour at the lower (upper) end, whose last (first) ones fill the ghost
        cells."""
        began = time.perf_counter()
        g, n = domain.ghost, domain.block_cells
        ends = {Side.named(side).end for side in sides}
        sends, receives = [], []
        if 0 in ends:
            sends.append((self.left, LEFTWARD, array[0, g:2 * g]))
            receives.append((self.left, RIGHTWARD, array[0, :g]))
        if 1 in ends:
            sends.append((self.right, RIGHTWARD, array[-1, n:n + g]))
            receives.append((self.right, LEFTWARD, array[-1, g + n:]))
        pending = self.communicator.start(sends, receives)
        self.seconds += time.perf_counter() - began
        self.exchanges += 1
        return _Timed(pending, self)


class _Timed(Pending):
    """A pending exchange whose wait counts in its halo's seconds."""

    def __init__(self, pending: Pending, halo: Halo):
        self.pending, self.halo = pending, halo

    def wait(self) -> None:
        began = time.perf_counter()
        self.pending.wait()
        self.halo.seconds += time.perf_counter() - began
