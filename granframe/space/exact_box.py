r"""The steady state of a collisionless gas in a rectangle with four diffuse walls, on the
nodes of a velocity grid (docs/space.md, "Two dimensions", "The collisionless box").

The derivation. Without collisions f(x, v_j) is constant along the straight lines of
every node v_j. Trace the line of a point x of [0, a] x [0, b] backwards, x - v_j tau,
tau > 0: it leaves the rectangle through one wall w at the point s (the coordinate along
w), where the gas leaving w is that wall's diffuse emission. A diffuse wall at T_w moving
along itself at U_w (full accommodation) emits on the nodes leaving it, c^+_w(v_j) > 0
(c^+_w the speed of v_j along the inward normal n_w, the node -L counted at L/2 as in
:func:`granframe.space.transport.upwind_speeds`),

.. math:: f(s, v_j) = \sigma_w(s)\,\hat M_w(v_j),\qquad
          \hat M_w = \frac{M_w}{h^d\sum_k c^+_w(v_k) M_w(v_k)},\quad
          M_w(v) = e^{-|v - U_w|^2 / (2 T_w)},

with sigma_w(s) the mass flux that arrives at s (zero net mass through the wall),

.. math:: \sigma_w(s) = h^d \sum_{v_j\cdot n_w < 0} |v_j\cdot n_w|\, f(s, v_j)
          = h^d \sum_{v_j\cdot n_w < 0} |v_j\cdot n_w|\,
            \sigma_{w'}(s')\,\hat M_{w'}(v_j),

(w', s') where the line of v_j through s leaves backwards. So the four emitted fluxes
solve sigma = K sigma, K a positive linear operator whose kernel is made of the "view
factors" of the nodes: which wall, and where, each node sees from each point of a wall.
Its transpose conserves the flux, the integral of |w| K sigma over the walls being that of
sigma (a parallel beam keeps its flux: |v.n_w| ds on one wall is |v.n_w'| ds' on the
other), so 1 is an eigenvalue and sigma its positive (Perron) eigenfunction, fixed up to
its scale by the mass. Then, at every point, f(x, v_j) = sigma_w'(s') M_w'(v_j) along the
backward line, which is the exact steady state on the grid's nodes; the nodes that do not
move in the plane (v_1 = v_2 = 0: in 3D every v_3) keep what they hold initially
(``rest``). The nodes v_1 = -L or v_2 = -L, which the transport moves both ways at L/2,
are left out of the lines (set to zero): they hold exp(-L^2 / (2 T_w)) of the mass, 1e-9
and below on a grid that fits the walls.

Solved here by panels: sigma_w piecewise constant on ``panels`` equal panels of every
wall, the entries of K by the midpoints of ``samples`` sub-panels of each panel traced back
(the flux of each node through each panel's sub-points to the panels they see), sigma
the Perron vector of the panel matrix (its eigenvector of the largest real eigenvalue,
which is 1 up to the sampling, :attr:`FreeMolecularBox.root`); then f at the points of a
fine grid traced back the same way.
sigma has jumps where a wall point sees a corner; the panel solution converges to it in
L^1 at first order in 1/panels.
"""

from __future__ import annotations

import numpy
import scipy.sparse.linalg

from granframe import validators as check

#: the walls in :attr:`~granframe.space.domain.Box.sides` order: (axis of the wall's
#: normal, end 0 or 1)
WALLS = ((0, 0), (0, 1), (1, 0), (1, 1))


def _emissions(grid, walls):
    """hat M_w on the nodes (the grid's shape) for each wall: (T_w, U_w) with U_w along the
    wall (+v_2 for the walls of x, +v_1 for those of y, the lab frame of a wall's own
    frame, :class:`~granframe.abc.Side`), normalised by its leaving flux."""
    from granframe.space.transport import upwind_speeds

    d, h = grid.dimension, grid.cell_volume
    points = numpy.asarray(grid.points(), dtype=float)
    mesh = numpy.meshgrid(*([points] * d), indexing="ij")
    out = []
    for (axis, end), (temperature, velocity) in zip(WALLS, walls):
        shift = [0.0] * d
        shift[1 - axis] = velocity
        maxwellian = numpy.exp(-sum((m - u) ** 2 for m, u in zip(mesh, shift))
                               / (2.0 * temperature))
        positive, negative = (numpy.broadcast_to(c, grid.shape)
                              for c in upwind_speeds(grid, numpy, axis))
        leaving = positive if end == 0 else -negative
        out.append(maxwellian * (leaving > 0) / float((leaving * maxwellian).sum() * h))
    return out


def _trace(px, py, v1, v2, lengths):
    """Where the lines through the points (px, py) leave the rectangle backwards along
    -(v1, v2): the wall index (:data:`WALLS`) and the coordinate along it (y on the walls
    of x, x on those of y)."""
    a, b = lengths
    big = numpy.inf
    tx = px / v1 if v1 > 0 else (a - px) / -v1 if v1 < 0 else numpy.full_like(px, big)
    ty = py / v2 if v2 > 0 else (b - py) / -v2 if v2 < 0 else numpy.full_like(py, big)
    tx, ty = numpy.broadcast_to(tx, px.shape), numpy.broadcast_to(ty, py.shape)
    by_x = tx <= ty
    wall = numpy.where(by_x, 0 if v1 > 0 else 1, 2 if v2 > 0 else 3)
    coordinate = numpy.where(by_x, py - v2 * numpy.minimum(tx, 1e300),
                             px - v1 * numpy.minimum(ty, 1e300))
    return wall, coordinate


class FreeMolecularBox:
    r"""The steady state of a collisionless gas in [0, a] x [0, b] with four diffuse walls on
    the nodes of a velocity grid (see the module notes for the derivation).

    Parameters
    ----------
    grid : VelocityGrid
        2D or 3D velocities (the transport moves v_1 and v_2).
    lengths : (float, float)
        a and b.
    walls : sequence of four (T_w, U_w)
        The walls left, right, bottom, top: temperature and velocity along the wall
        (+v_2 on the walls of x, +v_1 on the walls of y).
    mass : float
        The mass in the rectangle, int int h^d sum_j f dx dy.
    rest : array_like
        f at the nodes that do not move (the grid's shape; the values at v_1 = v_2 = 0
        are kept, the rest ignored): a run's initial data there.
    panels : int
        Panels of each wall.
    samples : int
        Sub-panels of each panel traced back for the entries of K.
    """

    def __init__(self, grid, lengths, walls, mass: float, rest, panels: int = 256,
                 samples: int = 8):
        owner = "FreeMolecularBox"
        if grid.dimension not in (2, 3):
            check.reject(owner, "grid", grid, "must have 2 or 3 velocity dimensions")
        walls = [tuple(float(x) for x in w) for w in walls]
        if len(walls) != 4 or any(len(w) != 2 or not w[0] > 0 for w in walls):
            check.reject(owner, "walls", walls, "must be four (T_w > 0, U_w) pairs: left, "
                         "right, bottom, top")
        for name, value in (("panels", panels), ("samples", samples)):
            if not check.is_integer(value) or value < 1:
                check.reject(owner, name, value, "must be an integer >= 1")
        self.grid, self.lengths = grid, (float(lengths[0]), float(lengths[1]))
        self.panels, self.samples = int(panels), int(samples)
        self.emission = _emissions(grid, walls)
        points = numpy.asarray(grid.points(), dtype=float)
        n = grid.n_modes
        index = numpy.indices(grid.shape)
        #: the nodes the lines carry: both in-plane components inside (-L, L), not both 0
        self.moving = ((index[0] > 0) & (index[1] > 0)
                       & ((index[0] != n // 2) | (index[1] != n // 2)))
        self.resting = (index[0] == n // 2) & (index[1] == n // 2)
        self.nodes = [(tuple(j), points[j[0]], points[j[1]])
                      for j in numpy.argwhere(self.moving)]
        self.rest = numpy.where(self.resting, numpy.asarray(rest, dtype=float), 0.0)
        self.sigma = self._solve()
        moving_mass = float(mass) - grid.cell_volume * self.rest.sum() * numpy.prod(
            self.lengths)
        self.sigma *= moving_mass / self._mass()

    def _wall_length(self, wall: int) -> float:
        return self.lengths[1] if WALLS[wall][0] == 0 else self.lengths[0]

    def _wall_points(self, wall: int):
        """(x, y) of the midpoints of the ``samples`` sub-panels of every panel of ``wall``."""
        axis, end = WALLS[wall]
        count = self.panels * self.samples
        along = (numpy.arange(count) + 0.5) / count * self._wall_length(wall)
        fixed = numpy.full_like(along, 0.0 if end == 0 else self.lengths[axis])
        return (fixed, along) if axis == 0 else (along, fixed)

    def _panel(self, wall, coordinate):
        """The global panel index of wall coordinates."""
        length = numpy.where(numpy.asarray(wall) < 2, self.lengths[1], self.lengths[0])
        local = numpy.clip((coordinate / length * self.panels).astype(int), 0,
                           self.panels - 1)
        return wall * self.panels + local

    def _solve(self):
        """sigma on the panels of the four walls: the Perron vector of the panel matrix K,
        normalised to a unit total flux sum |panel| sigma."""
        m, q, h = self.panels, self.samples, self.grid.cell_volume
        K = numpy.zeros((4 * m, 4 * m))
        for wall, (axis, end) in enumerate(WALLS):
            px, py = self._wall_points(wall)
            rows = wall * m + numpy.arange(m * q) // q
            for j, v1, v2 in self.nodes:
                normal = (v1, v2)[axis] * (1 if end == 0 else -1)
                if normal >= 0:
                    continue                                 # the node leaves this wall
                seen, coordinate = _trace(px, py, v1, v2, self.lengths)
                columns = self._panel(seen, coordinate)
                weights = -normal * h * numpy.take(
                    [e[j] for e in self.emission], seen) / q
                numpy.add.at(K, (rows, columns), weights)
        widths = numpy.repeat([self._wall_length(w) / m for w in range(4)], m)
        root, vector = scipy.sparse.linalg.eigs(K, k=1, which="LR", v0=numpy.ones(4 * m))
        #: the Perron root of the panel matrix: 1 up to the sampling of its entries
        self.root = float(root[0].real)
        vector = numpy.abs(vector[:, 0].real)
        return (vector / (widths @ vector)).reshape(4, m)

    def f_at(self, px, py):
        """f at the points (px, py) (arrays of one shape P) on every node: (*P, *grid)."""
        out = numpy.zeros(px.shape + tuple(self.grid.shape))
        for j, v1, v2 in self.nodes:
            seen, coordinate = _trace(px, py, v1, v2, self.lengths)
            panel = self._panel(seen, coordinate)
            emitted = numpy.take([e[j] for e in self.emission], seen)
            out[(Ellipsis,) + j] = self.sigma.reshape(-1)[panel] * emitted
        return out + self.rest

    def cell_averages(self, counts, per_cell: int):
        """The averages of f over the cells of a C_x x C_y grid, (C_x, C_y, *grid.shape), by
        the midpoint rule on ``per_cell`` x ``per_cell`` points of every cell."""
        cx, cy = counts
        a, b = self.lengths
        x = (numpy.arange(cx * per_cell) + 0.5) * a / (cx * per_cell)
        y = (numpy.arange(cy * per_cell) + 0.5) * b / (cy * per_cell)
        out = numpy.empty((cx, cy) + tuple(self.grid.shape))
        for i in range(cx):                  # a column of cells at a time: bounded memory
            px, py = numpy.meshgrid(x[i * per_cell:(i + 1) * per_cell], y, indexing="ij")
            values = self.f_at(px, py)
            out[i] = values.reshape((per_cell, cy, per_cell) + values.shape[2:]).mean(
                axis=(0, 2))
        return out

    def _mass(self) -> float:
        """int int h^d sum_j f dx dy of the moving nodes, by the flux of each wall panel
        times the time of flight of its lines (a parallel beam of flux F per unit length
        of wall that crosses for a time tau fills the area |v.n| tau per unit length with
        F / |v.n| mass per unit area and speed), on ``samples`` sub-points of each panel."""
        m, q, h = self.panels, self.samples, self.grid.cell_volume
        total = 0.0
        for wall, (axis, end) in enumerate(WALLS):
            length = self._wall_length(wall)
            px, py = self._wall_points(wall)
            sigma = numpy.repeat(self.sigma[wall], q)
            for j, v1, v2 in self.nodes:
                normal = (v1, v2)[axis] * (1 if end == 0 else -1)
                if normal <= 0:
                    continue                                 # not emitted by this wall
                flight = _flight(px, py, v1, v2, self.lengths)
                total += h * normal * self.emission[wall][j] * float(
                    (sigma * flight).sum()) * length / (m * q)
        return total


def _flight(px, py, v1, v2, lengths):
    """The time the lines of (v1, v2) from the wall points (px, py) take to cross."""
    a, b = lengths
    tx = (a - px) / v1 if v1 > 0 else px / -v1 if v1 < 0 else numpy.full_like(px, numpy.inf)
    ty = (b - py) / v2 if v2 > 0 else py / -v2 if v2 < 0 else numpy.full_like(py, numpy.inf)
    return numpy.minimum(tx, ty)
