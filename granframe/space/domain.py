r"""The cells of [0, ell] along a space axis, the part of them this process owns, and their
ghost cells.

A :class:`Domain` is to the space discretisation what PETSc's DMDA is to a structured grid
(S. Balay et al., PETSc users manual, "DMDA"): it knows the global cells and their edges,
the range of cells this process owns (``start`` to ``stop``), the ghost width
of the reconstruction and which global boundaries the owned range touches. Numerics see
blocks of owned cells with their ghosts and never ask who their neighbours are.

The owned cells are held as contiguous blocks of ``block_cells`` cells, each with its own
``ghost`` ghost cells on either side: an array of shape
(blocks, block_cells + 2 ghost, *grid.shape). :meth:`Domain.exchange` is the one place that
fills ghost cells: between the owned blocks from each other, at a global wall from the
wall's :meth:`~granframe.abc.Boundary.ghosts`, at the two ends of a periodic interval from
each other when this process owns both, and at an end of the owned range inside the
interval (or a periodic end owned elsewhere) from the process next to it, through
:attr:`Domain.neighbours` (docs/space.md, "Blocks and their distribution"). With one
process the domain owns every cell and touches both ends.

The cells lie along one space ``axis`` (0: x, 1: y, 2: z); its two ends are the domain's
:attr:`~Domain.sides` (:class:`~granframe.abc.Side`), through which every wall sees f in
its own frame, and the transport carries f along it with the velocity component
v_{axis+1} (:class:`~granframe.space.transport.Transport`).
"""

from __future__ import annotations

import numpy

from granframe import validators as check
from granframe.abc.space import AXIS_NAMES, Side
from granframe.abc.space import reflect_nodes as reflect

__all__ = ["Box", "Domain", "reflect"]


class Domain:
    """The global cells of [0, ell] along a space axis, the owned range, its blocks and their
    ghost cells.

    Parameters
    ----------
    cells : int
        The number of cells of the whole interval.
    length : float
        ell, the length of the interval; cell j is [j dx, (j + 1) dx], dx = ell / cells.
    block_cells : int
        Cells per block, a divisor of the owned cells (the unit of the batched transport;
        the store's chunks along x are ``space.block_cells``, which a process's range
        holds whole).
    ghost : int
        Ghost cells on each side of a block (the reconstruction's stencil half-width).
    grid : VelocityGrid
    xp : module
        The array namespace of the blocks.
    owned : tuple of int, optional
        ``(start, stop)``: the cells this process owns
        (:func:`granframe.parallel.partition`); all cells by default.
    axis : int, optional
        The space axis the cells lie along: 0 (x, the default), 1 (y) or 2 (z), below the
        velocity dimension.

    Attributes
    ----------
    start, stop : int
        The owned cells are ``start <= j < stop``.
    touches_left, touches_right : bool
        Whether the owned range contains the first (at 0, the lower side) or the last (at
        ell, the upper side) cell of the axis.
    axes : tuple of str
        The name of the axis (:data:`~granframe.abc.space.AXIS_NAMES`), as the store names
        its cell coordinate.
    sides : tuple of Side
        The lower and the upper side of the axis.
    neighbours : object or None
        Exchanges the ghost cells of the ends of the owned range that other processes
        hold: ``neighbours.start(domain, array, sides)`` posts the messages of ``sides``
        (of :attr:`sides`) and returns what to ``wait()`` for
        (:class:`granframe.parallel.Halo`). None for a domain that owns every cell.
    """

    def __init__(self, cells: int, length: float, block_cells: int, ghost: int, grid,
                 xp=numpy, owned: tuple | None = None, axis: int = 0):
        if not check.is_integer(axis) or not 0 <= axis < min(3, grid.dimension):
            check.reject("Domain", "axis", axis, f"must be a space axis below the velocity "
                         f"dimension {grid.dimension}: "
                         + ", ".join(f"{a} ({n})" for a, n in
                                     enumerate(AXIS_NAMES[:grid.dimension])))
        start, stop = (0, cells) if owned is None else (int(owned[0]), int(owned[1]))
        if not 0 <= start < stop <= cells:
            check.reject("Domain", "owned", owned, f"must be (start, stop) with 0 <= start < "
                         f"stop <= {cells}")
        if (stop - start) % block_cells:
            check.reject("Domain", "block_cells", block_cells,
                         f"must divide the number of owned cells ({stop - start})")
        self.cells, self.length, self.block_cells, self.ghost = cells, float(length), \
            block_cells, ghost
        self.start, self.stop = start, stop
        self.touches_left, self.touches_right = start == 0, stop == cells
        self.blocks = (stop - start) // block_cells
        self.grid, self.xp = grid, xp
        self.shape = (self.blocks, block_cells + 2 * ghost) + tuple(grid.shape)
        self.neighbours = None
        self.axis = int(axis)
        self.axes = (AXIS_NAMES[self.axis],)
        self.sides = (Side(self.axis, 0), Side(self.axis, 1))

    # -- geometry ---------------------------------------------------------------------------
    @property
    def dx(self) -> float:
        """The cell width ell / cells."""
        return self.length / self.cells

    def edges(self) -> numpy.ndarray:
        """The cells + 1 global cell edges 0 = x_0 < ... < x_cells = ell."""
        return numpy.linspace(0.0, self.length, self.cells + 1)

    def centres(self) -> numpy.ndarray:
        """The global cell centres (j + 1/2) dx."""
        return (numpy.arange(self.cells) + 0.5) * self.dx

    def coordinates(self) -> dict:
        """The cell centres along every space axis, by the axis's name (:attr:`axes`)."""
        return {self.axes[0]: self.centres()}

    @property
    def owned(self) -> slice:
        """The owned cells as a slice of the global cells."""
        return slice(self.start, self.stop)

    @property
    def owned_cells(self) -> int:
        return self.stop - self.start

    # -- blocks -----------------------------------------------------------------------------
    def empty(self):
        """A block array (ghosts unset)."""
        return self.xp.zeros(self.shape)

    def interior(self, array):
        """The owned cells of ``array`` (a view), shape (blocks, block_cells, *grid.shape)."""
        g = self.ghost
        return array[:, g:g + self.block_cells]

    def from_cells(self, f):
        """A block array holding the owned cells ``f`` (owned cells, *grid.shape)."""
        array = self.empty()
        self.interior(array)[...] = self.xp.asarray(f).reshape(
            (self.blocks, self.block_cells) + tuple(self.grid.shape))
        return array

    def to_cells(self, array):
        """The owned cells of a block array as one array (owned cells, *grid.shape), a
        copy."""
        return self.xp.ascontiguousarray(self.interior(array)).reshape(
            (self.owned_cells,) + tuple(self.grid.shape))

    # -- ghost cells ------------------------------------------------------------------------
    def exchange(self, array, left, right, t: float = 0.0) -> None:
        """Fill every ghost cell of ``array`` (see the module notes); ``left`` and
        ``right`` are the boundaries of the lower and the upper side (:attr:`sides`),
        acting at time ``t``.

        The ghost cells that other processes hold are posted first
        (:meth:`~granframe.parallel.Halo.start`), the local ones filled while they travel,
        and the exchange completed last."""
        g, n, d = self.ghost, self.block_cells, self.grid.dimension
        if g == 0:
            return
        lower, upper = self.sides
        local = left.periodic and self.touches_left and self.touches_right
        remote = [side for side, touches, wall in ((lower, self.touches_left, left),
                                                   (upper, self.touches_right, right))
                  if not local and (wall.periodic or not touches)]
        pending = self._neighbours().start(self, array, remote) if remote else None
        array[1:, :g] = array[:-1, n:n + g]
        array[:-1, g + n:] = array[1:, g:2 * g]
        xp = self.xp
        if local:
            array[0, :g] = array[-1, n:n + g]
            array[-1, g + n:] = array[0, g:2 * g]
        if self.touches_left and not left.periodic:
            inside = lower.to_wall(array[0, g:2 * g], d, xp)
            ghosts = left.ghosts(inside, self.grid, xp, t=t, side=lower)
            array[0, :g] = xp.flip(lower.from_wall(ghosts, d, xp), axis=0)  # wall outwards
        if self.touches_right and not right.periodic:
            inside = upper.to_wall(xp.flip(array[-1, n:n + g], axis=0), d, xp)
            array[-1, g + n:] = upper.from_wall(right.ghosts(inside, self.grid, xp, t=t,
                                                             side=upper), d, xp)
        if pending is not None:
            pending.wait()

    def _neighbours(self):
        if self.neighbours is None:
            raise RuntimeError(f"Domain: cells {self.start}..{self.stop - 1} of {self.cells} "
                               f"have an end that another process owns (along "
                               f"{self.axes[0]}), and no neighbours to fill its ghost cells")
        return self.neighbours


class Box:
    r"""The cells of a rectangle [0, ell_x] x [0, ell_y] (or of a box, one more axis), the
    block of them this process owns, and its ghost cells: the domain of a run in two space
    dimensions (docs/space.md, "Two dimensions").

    Cell (i, j) is [i dx, (i + 1) dx] x [j dy, (j + 1) dy], dx = ell_x / cells_x. A process
    owns one block of cells, a range along every axis (a Px x Py decomposition,
    :func:`granframe.parallel.box_ranges`), held with ``ghost`` ghost cells on each side of
    every axis in one array of shape (n_x + 2 ghost, n_y + 2 ghost, *grid.shape);
    :meth:`interior` is its owned cells, (n_x, n_y, *grid.shape), the batch of every cell of
    the block that the collision step takes at once.

    The transport (:class:`~granframe.space.transport.BoxTransport`) takes its fluxes along
    every axis from the same state (dimension by dimension, in one stage), and the face
    values along an axis read the ghost cells of that axis only, in the rows of owned cells
    of the others: the corner ghost cells are never read, and :meth:`exchange` leaves them
    unset. Along each axis it fills the ghost strips as :class:`Domain` fills its ends:
    from the other end of a periodic axis that this block spans whole, from the wall of a
    side the block touches (:meth:`~granframe.abc.Boundary.ghosts`, seen from the wall as
    :class:`~granframe.abc.Side` maps it, a whole strip of cells at once), and from the
    process beyond an end inside the domain (or a periodic end owned elsewhere) through
    :attr:`neighbours` (:class:`granframe.parallel.BoxHalo`).

    Parameters
    ----------
    cells : tuple of int
        The cells of the whole domain along each space axis (x, y[, z]).
    length : tuple of float
        Its lengths along each axis.
    ghost : int
        Ghost cells on each side (the reconstruction's stencil half-width); at most the
        owned cells along every axis.
    grid : VelocityGrid
        Of dimension at least the number of space axes.
    xp : module
        The array namespace of the block.
    owned : tuple of (int, int), optional
        ``(start, stop)`` along each axis: the block this process owns; all cells by
        default.

    Attributes
    ----------
    start, stop : tuple of int
        The owned cells are start[a] <= j_a < stop[a] along axis a.
    touches : tuple of (bool, bool)
        Whether the block contains the first and the last cell of each axis.
    axes : tuple of str
        The names of the axes (:data:`~granframe.abc.space.AXIS_NAMES`), as the store names
        its cell coordinates.
    sides : tuple of Side
        The lower and the upper side of every axis: left, right, bottom, top (and back,
        front).
    neighbours : object or None
        Posts the ghost strips that other processes hold: ``neighbours.start(box, array,
        sides)`` returns what to ``wait()`` for (:class:`granframe.parallel.BoxHalo`).
    """

    def __init__(self, cells, length, ghost: int, grid, xp=numpy, owned=None):
        cells, length = tuple(cells), tuple(length)
        k = len(cells)
        if not 2 <= k <= min(3, grid.dimension):
            check.reject("Box", "cells", list(cells), f"must give the cells along 2 space "
                         f"axes (x, y){' or 3 (x, y, z)' if grid.dimension == 3 else ''}, at "
                         f"most the velocity dimension {grid.dimension}")
        if len(length) != k:
            check.reject("Box", "length", list(length), f"must give a length for each of the "
                         f"{k} axes of cells = {list(cells)}")
        owned = tuple((0, n) for n in cells) if owned is None else tuple(
            (int(a), int(b)) for a, b in owned)
        if len(owned) != k or not all(0 <= a < b <= n for (a, b), n in zip(owned, cells)):
            check.reject("Box", "owned", owned, f"must be (start, stop) along each of the {k} "
                         f"axes with 0 <= start < stop <= cells ({list(cells)})")
        sizes = tuple(b - a for a, b in owned)
        if min(sizes) < ghost:
            check.reject("Box", "owned", owned, f"must hold at least {ghost} cells along "
                         f"every axis (the ghost width: a block fills its neighbours' ghosts)")
        self.cells, self.length, self.ghost = cells, tuple(float(v) for v in length), ghost
        self.start, self.stop = tuple(a for a, _ in owned), tuple(b for _, b in owned)
        self.sizes = sizes
        self.touches = tuple((a == 0, b == n) for (a, b), n in zip(owned, cells))
        self.grid, self.xp = grid, xp
        self.shape = tuple(n + 2 * ghost for n in sizes) + tuple(grid.shape)
        self.axes = AXIS_NAMES[:k]
        self.sides = tuple(Side(a, end) for a in range(k) for end in (0, 1))
        self.neighbours = None

    @property
    def dimension(self) -> int:
        """The number of space axes."""
        return len(self.cells)

    # -- geometry ---------------------------------------------------------------------------
    @property
    def spacing(self) -> tuple:
        """The cell widths ell_a / cells_a along every axis."""
        return tuple(ell / n for ell, n in zip(self.length, self.cells))

    @property
    def cell_volume(self) -> float:
        """dx dy (dz): the measure of one cell."""
        return float(numpy.prod(self.spacing))

    def edges(self, axis: int = 0) -> numpy.ndarray:
        """The cells + 1 global cell edges along ``axis``."""
        return numpy.linspace(0.0, self.length[axis], self.cells[axis] + 1)

    def centres(self, axis: int = 0) -> numpy.ndarray:
        """The global cell centres (j + 1/2) dx_a along ``axis``."""
        return (numpy.arange(self.cells[axis]) + 0.5) * self.spacing[axis]

    def coordinates(self) -> dict:
        """The cell centres along every space axis, by the axis's name (:attr:`axes`)."""
        return {name: self.centres(a) for a, name in enumerate(self.axes)}

    @property
    def owned(self) -> tuple:
        """The owned block as a tuple of slices of the global cells."""
        return tuple(slice(a, b) for a, b in zip(self.start, self.stop))

    @property
    def owned_cells(self) -> int:
        return int(numpy.prod(self.sizes))

    # -- the block --------------------------------------------------------------------------
    def empty(self):
        """A block array (ghosts unset)."""
        return self.xp.zeros(self.shape)

    def interior(self, array):
        """The owned cells of ``array`` (a view), shape (n_x, n_y, *grid.shape)."""
        g = self.ghost
        return array[tuple(slice(g, g + n) for n in self.sizes)]

    def from_cells(self, f):
        """A block array holding the owned cells ``f``, (n_x n_y, *grid.shape) in C order
        (x slowest) or (n_x, n_y, *grid.shape)."""
        array = self.empty()
        self.interior(array)[...] = self.xp.asarray(f).reshape(
            self.sizes + tuple(self.grid.shape))
        return array

    def to_cells(self, array):
        """The owned cells of a block array as one array (n_x n_y, *grid.shape), x slowest,
        a copy."""
        return self.xp.ascontiguousarray(self.interior(array)).reshape(
            (self.owned_cells,) + tuple(self.grid.shape))

    def along(self, array, axis: int):
        """``array`` with ``axis`` first and the other space axes cut to their owned cells
        (a view): (n_axis + 2 ghost, owned cells of the others..., *grid.shape), what the
        reconstruction reads along ``axis`` and where its ghost strips lie."""
        g = self.ghost
        cut = tuple(slice(None) if a == axis else slice(g, g + n)
                    for a, n in enumerate(self.sizes))
        return self.xp.moveaxis(array[cut], axis, 0)

    # -- ghost cells ------------------------------------------------------------------------
    def exchange(self, array, walls, t: float = 0.0) -> None:
        """Fill the ghost strips of ``array`` along every axis (the class notes); ``walls``
        the boundaries of :attr:`sides` in that order, acting at time ``t``.

        The strips that other processes hold are posted first
        (:meth:`granframe.parallel.BoxHalo.start`), the local ones filled while they
        travel, and the exchange completed last."""
        g, d, xp = self.ghost, self.grid.dimension, self.xp
        if g == 0:
            return
        remote, local = [], []
        for axis, (low, high) in enumerate(self.touches):
            lower, upper = self.sides[2 * axis], self.sides[2 * axis + 1]
            periodic = walls[2 * axis].periodic
            whole = periodic and low and high
            local.append(whole)
            remote += [side for side, touches in ((lower, low), (upper, high))
                       if not whole and (periodic or not touches)]
        pending = self._neighbours().start(self, array, remote) if remote else None
        for axis, n in enumerate(self.sizes):
            view = self.along(array, axis)
            lower, upper = self.sides[2 * axis], self.sides[2 * axis + 1]
            left, right = walls[2 * axis], walls[2 * axis + 1]
            low, high = self.touches[axis]
            if local[axis]:
                view[:g] = view[n:n + g]
                view[g + n:] = view[g:2 * g]
                continue
            if low and not left.periodic:
                inside = lower.to_wall(view[g:2 * g], d, xp)
                ghosts = left.ghosts(inside, self.grid, xp, t=t, side=lower)
                view[:g] = xp.flip(lower.from_wall(ghosts, d, xp), axis=0)
            if high and not right.periodic:
                inside = upper.to_wall(xp.flip(view[n:n + g], axis=0), d, xp)
                view[g + n:] = upper.from_wall(right.ghosts(inside, self.grid, xp, t=t,
                                                            side=upper), d, xp)
        if pending is not None:
            pending.wait()

    def _neighbours(self):
        if self.neighbours is None:
            raise RuntimeError(f"Box: the block {list(zip(self.start, self.stop))} of "
                               f"{list(self.cells)} cells has a side that another process "
                               "owns, and no neighbours to fill its ghost cells")
        return self.neighbours
