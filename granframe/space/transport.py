r"""Free transport d_t f + v_1 d_x f = 0 by conservative finite volumes on blocks of cells.

The interval [0, ell] is cut into ``cells`` cells of width dx = ell / cells, held as
``blocks`` contiguous blocks of ``block_cells`` cells; each block owns its cells and
``ghost`` ghost cells on each side (:class:`CellBlocks`). Cell j holds the average of f
over its cell at every velocity node. One sub-step of length tau is three-stage SSP
Runge-Kutta (Shu & Osher, J. Comput. Phys. 77 (1988) 439-471) of

.. math:: \frac{d f_j}{dt} = -\frac{F_{j+1/2} - F_{j-1/2}}{\Delta x},\qquad
          F_{j-1/2} = c^+ f^-_{j-1/2} + c^- f^+_{j-1/2},

with c^± = max(±c, 0)·(±1) the upwind split of the transport speed c of each velocity node
and f^∓ the face values of the :class:`~granframe.abc.Reconstruction` (from the cell on the
left, on the right). Before each stage the ghost cells are filled: between blocks from
the neighbouring block, at the ends from the other end (periodic) or by the
:class:`~granframe.abc.Boundary` of the wall, which also sets the flux through the wall
itself (:meth:`~granframe.abc.Boundary.emit`).

The velocity nodes. The grid is periodic on [-L, L): v_1 takes the values -L + i h,
i = 0 .. N - 1. The node i = 0 stands for both -L and +L: half of what it holds moves
each way, c^+ = L/2 and c^- = -L/2 (net speed 0), so that the speeds are symmetric:
c^±_i = max/min(v_1, 0) for i ≥ 1, max(c^+) = L - h. The reflection v_1 -> -v_1 is the
permutation i -> (N - i) mod N of the nodes (:func:`reflect`); it fixes i = 0 and the
nodes v_1 = 0 (i = N/2), maps c^+ onto -c^- exactly (c(Rv) = -c(v) in floating point,
since the nodes are symmetric about 0), and so maps the velocities that enter the domain
at a wall one to one onto those that leave it; at i = 0 the half moving into the wall
onto the half moving out. The nodes v_1 = 0 carry no flux and are never transported.
"""

from __future__ import annotations

import numpy

from granframe.backends import to_host


def transport_speeds(grid, xp=numpy):
    """The net transport speed c = c^+ + c^- of each v_1 node (:func:`upwind_speeds`),
    shaped to broadcast over f (N, 1, ..., 1): v_1, and 0 at the node -L."""
    positive, negative = upwind_speeds(grid, xp)
    return positive + negative


def upwind_speeds(grid, xp=numpy):
    """(c^+, c^-) of each v_1 node, shaped (N, 1, ..., 1): max(v_1, 0) and min(v_1, 0),
    except at the node -L, which stands for both -L and +L: half of what it holds moves
    each way, c^+ = L/2 and c^- = -L/2 (see the module notes)."""
    points = numpy.array(grid.points(), dtype=float)
    positive, negative = numpy.maximum(points, 0.0), numpy.minimum(points, 0.0)
    positive[0] = negative[0] = 0.5 * grid.half_width
    negative[0] = -negative[0]
    shape = (-1,) + (1,) * (grid.dimension - 1)
    return xp.asarray(positive.reshape(shape)), xp.asarray(negative.reshape(shape))


def reflect(f, dimension: int, xp=numpy):
    """f(R v) with R: v_1 -> -v_1, exactly on the nodes: i -> (N - i) mod N along the v_1
    axis (axis ``-dimension``)."""
    axis = f.ndim - dimension
    return xp.roll(xp.flip(f, axis=axis), 1, axis=axis)


class CellBlocks:
    """Cells held as contiguous blocks, each with its own ghost cells.

    ``array`` has shape (blocks, block_cells + 2 ghost, *grid.shape); block b owns the
    cells b·block_cells ... (b + 1)·block_cells - 1 in ``array[b, ghost:ghost +
    block_cells]``. Only :meth:`exchange` reads one block's cells into another block's
    ghosts: it is what a distribution over processes (MPI ranks, devices) replaces by
    messages (docs/space.md).
    """

    def __init__(self, cells: int, block_cells: int, ghost: int, grid, xp=numpy):
        self.cells, self.block_cells, self.ghost = cells, block_cells, ghost
        self.blocks = cells // block_cells
        self.grid, self.xp = grid, xp
        self.shape = (self.blocks, block_cells + 2 * ghost) + tuple(grid.shape)

    def empty(self):
        """A block array (ghosts unset)."""
        return self.xp.zeros(self.shape)

    def interior(self, array):
        """The cells of ``array`` (a view), shape (blocks, block_cells, *grid.shape)."""
        g = self.ghost
        return array[:, g:g + self.block_cells]

    def from_cells(self, f):
        """A block array holding the cells ``f`` (cells, *grid.shape)."""
        array = self.empty()
        self.interior(array)[...] = self.xp.asarray(f).reshape(
            (self.blocks, self.block_cells) + tuple(self.grid.shape))
        return array

    def to_cells(self, array):
        """The cells of a block array as one array (cells, *grid.shape) (a copy)."""
        return self.xp.ascontiguousarray(self.interior(array)).reshape(
            (self.cells,) + tuple(self.grid.shape))

    def exchange(self, array, left, right) -> None:
        """Fill every ghost cell: from the neighbouring block, or at the two ends from the
        other end (periodic ``left``) or the walls' :meth:`~granframe.abc.Boundary.ghosts`."""
        g, n, d = self.ghost, self.block_cells, self.grid.dimension
        if g == 0:
            return
        array[1:, :g] = array[:-1, n:n + g]
        array[:-1, g + n:] = array[1:, g:2 * g]
        if left.periodic:
            array[0, :g] = array[-1, n:n + g]
            array[-1, g + n:] = array[0, g:2 * g]
            return
        xp = self.xp
        ghosts = left.ghosts(array[0, g:2 * g], self.grid, xp)        # from the wall outwards
        array[0, :g] = xp.flip(ghosts, axis=0)
        inside = reflect(xp.flip(array[-1, n:n + g], axis=0), d, xp)  # right wall as a left one
        array[-1, g + n:] = reflect(right.ghosts(inside, self.grid, xp), d, xp)


class Transport:
    """The transport sub-step on :class:`CellBlocks` (see the module notes).

    Parameters
    ----------
    blocks : CellBlocks
    reconstruction : Reconstruction
    left, right : Boundary
        The ends of the interval; both periodic, or two walls.
    length : float
        ell, the length of the interval.
    """

    def __init__(self, blocks: CellBlocks, reconstruction, left, right, length: float):
        self.blocks, self.reconstruction = blocks, reconstruction
        self.left, self.right = left, right
        self.dx = float(length) / blocks.cells
        grid, xp = blocks.grid, blocks.xp
        self.grid, self.xp = grid, xp
        self.positive, self.negative = upwind_speeds(grid, xp)
        # moments of a face flux: mass and energy int F dv, int F |v|^2/2 dv
        self._weights = xp.asarray(numpy.stack([numpy.ones(grid.shape),
                                                0.5 * grid.speed_squared()]) * grid.cell_volume)
        #: the mass and energy that entered through each wall over the last sub-steps,
        #: (wall, [mass, energy]); reset by :meth:`take_wall_totals`
        self.wall_totals = numpy.zeros((2, 2))

    @property
    def max_speed(self) -> float:
        """max |c| = L - h."""
        return float(self.grid.half_width - self.grid.spacing)

    def time_step_limit(self) -> float:
        """The largest sub-step tau with max|c| tau / dx <= the reconstruction's cfl."""
        return self.reconstruction.cfl * self.dx / self.max_speed

    def _rate(self, array):
        """-(F_{j+1/2} - F_{j-1/2}) / dx on the cells, and the fluxes into the domain through
        the two walls (mass, energy), after filling the ghosts of ``array``."""
        blocks, xp, d = self.blocks, self.xp, self.grid.dimension
        blocks.exchange(array, self.left, self.right)
        minus, plus = self.reconstruction.faces(xp.swapaxes(array, 0, 1), xp)
        flux = self.positive * minus + self.negative * plus     # (block_cells + 1, blocks, ...)
        walls = numpy.zeros((2, 2))
        if not self.left.periodic:
            out = self.left.emit(plus[0, 0], self.grid, xp)
            flux[0, 0] = self.positive * out + self.negative * plus[0, 0]
            out = reflect(self.right.emit(reflect(minus[-1, -1], d, xp), self.grid, xp), d, xp)
            flux[-1, -1] = self.positive * minus[-1, -1] + self.negative * out
            walls[0] = self._moments(flux[0, 0])
            walls[1] = -self._moments(flux[-1, -1])
        rate = (flux[:-1] - flux[1:]) * (1.0 / self.dx)
        return xp.swapaxes(rate, 0, 1), walls

    def _moments(self, face):
        """(int F dv, int F |v|^2/2 dv) of a face flux, on the host."""
        return to_host((self._weights * face).reshape(2, -1).sum(axis=1))

    def advance(self, array, tau: float) -> None:
        """Transport the cells of ``array`` over a time tau, in place (SSPRK3)."""
        if tau == 0.0:
            return
        inner = self.blocks.interior(array)
        start = inner.copy()
        k1, w1 = self._rate(array)
        inner[...] = start + tau * k1
        k2, w2 = self._rate(array)
        inner[...] = start + (0.25 * tau) * (k1 + k2)
        k3, w3 = self._rate(array)
        inner[...] = start + (tau / 6.0) * (k1 + k2 + 4.0 * k3)
        self.wall_totals += (tau / 6.0) * (w1 + w2 + 4.0 * w3)

    def take_wall_totals(self):
        """The (wall, [mass, energy]) entered since the last call, and reset them."""
        totals, self.wall_totals = self.wall_totals, numpy.zeros((2, 2))
        return totals
