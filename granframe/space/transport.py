r"""Free transport d_t f + v_1 d_x f = 0 by conservative finite volumes on blocks of cells.

The interval [0, ell] is cut into ``cells`` cells of width dx = ell / cells; the cells a
process owns are held as contiguous blocks of ``block_cells`` cells, each with ``ghost``
ghost cells on each side (:class:`~granframe.space.domain.Domain`). Cell j holds the average of f
over its cell at every velocity node. One sub-step of length tau is three-stage SSP
Runge-Kutta (Shu & Osher, J. Comput. Phys. 77 (1988) 439-471) of

.. math:: \frac{d f_j}{dt} = -\frac{F_{j+1/2} - F_{j-1/2}}{\Delta x},\qquad
          F_{j-1/2} = c^+ f^-_{j-1/2} + c^- f^+_{j-1/2},

with c^± = max(±c, 0)·(±1) the upwind split of the transport speed c of each velocity node
and f^∓ the face values of the :class:`~granframe.abc.Reconstruction` (from the cell on the
left, on the right). Before each stage the domain fills the ghost cells
(:meth:`~granframe.space.domain.Domain.exchange`): between blocks from the neighbouring
block, at the ends from the other end (periodic) or by the
:class:`~granframe.abc.Boundary` of the wall, which also sets the flux through the wall
itself (:meth:`~granframe.abc.Boundary.emit`). The walls act at the time of the stage
(t, t + tau, t + tau/2 for the three stages) and know their side.

The velocity nodes. The grid is periodic on [-L, L): v_1 takes the values -L + i h,
i = 0 .. N - 1. The node i = 0 stands for both -L and +L: half of what it holds moves
each way, c^+ = L/2 and c^- = -L/2 (net speed 0), so that the speeds are symmetric:
c^±_i = max/min(v_1, 0) for i ≥ 1, max(c^+) = L - h. The reflection v_1 -> -v_1 is the
permutation i -> (N - i) mod N of the nodes
(:func:`~granframe.space.domain.reflect`); it fixes i = 0 and the
nodes v_1 = 0 (i = N/2), maps c^+ onto -c^- exactly (c(Rv) = -c(v) in floating point,
since the nodes are symmetric about 0), and so maps the velocities that enter the domain
at a wall one to one onto those that leave it; at i = 0 the half moving into the wall
onto the half moving out. The nodes v_1 = 0 carry no flux and are never transported.
"""

from __future__ import annotations

import numpy

from granframe.space.domain import Box, Domain, reflect

__all__ = ["BoxTransport", "Transport", "box_step_limit", "reflect", "step_limit",
           "transport_speeds", "upwind_speeds", "wall_weights"]


def transport_speeds(grid, xp=numpy, axis: int = 0):
    """The net transport speed c = c^+ + c^- of each node of v_{axis+1}
    (:func:`upwind_speeds`), shaped to broadcast over f: v_{axis+1}, and 0 at the node -L."""
    positive, negative = upwind_speeds(grid, xp, axis)
    return positive + negative


def upwind_speeds(grid, xp=numpy, axis: int = 0):
    """(c^+, c^-) of each node of the velocity component v_{axis+1}, the one that carries f
    along space axis ``axis``, shaped to broadcast over f (N, 1, ..., 1 for x):
    max(v, 0) and min(v, 0), except at the node -L, which stands for both -L and +L: half
    of what it holds moves each way, c^+ = L/2 and c^- = -L/2 (see the module notes)."""
    points = numpy.array(grid.points(), dtype=float)
    positive, negative = numpy.maximum(points, 0.0), numpy.minimum(points, 0.0)
    positive[0] = negative[0] = 0.5 * grid.half_width
    negative[0] = -negative[0]
    shape = tuple(-1 if j == axis else 1 for j in range(grid.dimension))
    return xp.asarray(positive.reshape(shape)), xp.asarray(negative.reshape(shape))


def step_limit(grid, dx: float, cfl: float) -> float:
    r"""The transport's CFL limit on a run's time step: each half step dt/2 (the Strang
    splitting's transport sub-step, :class:`~granframe.space.collisions.SplitStep`) moves
    the fastest node, max|c| = L - h (module notes), at most ``cfl`` cells of width dx,

    .. math:: \Delta t \le \frac{2\,\mathrm{cfl}\,\Delta x}{L - h}

    (Courant, Friedrichs & Lewy, Math. Ann. 100 (1928) 32; ``cfl`` the reconstruction's
    SSP RK3 limit: 1 upwind, 1/2 MUSCL and WENO5)."""
    return 2.0 * cfl * dx / (grid.half_width - grid.spacing)


def wall_weights(grid, axis: int = 0):
    r"""The weights w (d + 2, *grid.shape) of the wall totals sum_v w F Delta v of a face
    flux F = c^+ f^- + c^- f^+ across space axis ``axis``: 1 (mass), v_1 .. v_d
    (momentum) and |v|^2/2 (energy), times Delta v = h^d.

    The node -L counts as in the recorded fields (:mod:`granframe.velocity.moments`): the
    normal component v_{axis+1} = 0 there in the momentum (its content moves half each way
    and carries no net normal velocity) and L^2 in the energy. With these weights the
    fluxes through the faces are those of the cells' mass, momentum and energy, so the
    change of the totals over a step equals what the walls let in, to round-off, wherever
    nothing else acts. Through a wall at rest, sum_v v_1 F Delta v = int v_1^2 f dv is the
    normal momentum flux (the pressure P_11 + rho u_1^2 on the face) and
    sum_v v_t F Delta v = int v_1 v_t f dv the tangential one (P_1t + rho u_1 u_t).
    """
    mesh = [numpy.broadcast_to(m, grid.shape) for m in grid.mesh()]
    mesh[axis] = numpy.where(mesh[axis] == -grid.half_width, 0.0, mesh[axis])
    return numpy.stack([numpy.ones(grid.shape), *mesh,
                        0.5 * grid.speed_squared()]) * grid.cell_volume


class _SSPTransport:
    """The three-stage SSP Runge-Kutta sub-step of a transport whose :meth:`rate` gives
    the rate of the owned cells and the fluxes into the domain through its walls."""

    def advance(self, array, tau: float, t: float = 0.0) -> None:
        """Transport the owned cells of ``array`` from time t over a time tau, in place
        (SSPRK3; the stages at t, t + tau, t + tau/2)."""
        if tau == 0.0:
            return
        inner = self.domain.interior(array)
        start = inner.copy()
        k1, w1 = self.rate(array, t)
        inner[...] = start + tau * k1
        k2, w2 = self.rate(array, t + tau)
        inner[...] = start + (0.25 * tau) * (k1 + k2)
        k3, w3 = self.rate(array, t + 0.5 * tau)
        inner[...] = start + (tau / 6.0) * (k1 + k2 + 4.0 * k3)
        self.wall_totals += (tau / 6.0) * (w1 + w2 + 4.0 * w3)

    def _faces(self, f):
        """(f^-, f^+) along axis 0 of ``f``: the backend's
        :meth:`~granframe.abc.ArrayBackend.faces`, or the reconstruction's own."""
        if self._backend is None:
            return self.reconstruction.faces(f, self.xp)
        return self._backend.faces(self.reconstruction, f)

    def take_wall_totals(self):
        """The (wall, [mass, p_1 .. p_d, energy]) entered since the last call, on the
        device, and reset them."""
        totals, self.wall_totals = self.wall_totals, self.xp.zeros(self.wall_totals.shape)
        return totals


class Transport(_SSPTransport):
    """The transport sub-step on the blocks of a :class:`~granframe.space.domain.Domain`
    (see the module notes).

    Parameters
    ----------
    domain : Domain
    reconstruction : Reconstruction
    left, right : Boundary
        The ends of the interval; both periodic, or two walls.
    backend : ArrayBackend, optional
        The run's backend, whose :meth:`~granframe.abc.ArrayBackend.faces` reconstructs
        (a fused kernel where it has one); without it the reconstruction's own, in the
        domain's namespace.
    """

    def __init__(self, domain: Domain, reconstruction, left, right, backend=None):
        self.domain, self.reconstruction = domain, reconstruction
        self._backend = backend
        self.left, self.right = left, right
        self.dx = domain.dx
        grid, xp = domain.grid, domain.xp
        self.grid, self.xp = grid, xp
        #: the space axis along which the cells lie, and the velocity component that carries f
        self.axis = axis = domain.sides[0].axis
        self.positive, self.negative = upwind_speeds(grid, xp, axis)
        self._weights = xp.asarray(wall_weights(grid, axis))
        #: the mass, momentum (d components) and energy that entered through each wall since
        #: the last :meth:`take_wall_totals`, (wall, [mass, p_1 .. p_d, energy]) on the device
        self.wall_totals = xp.zeros((2, grid.dimension + 2))

    @property
    def max_speed(self) -> float:
        """max |c| = L - h."""
        return float(self.grid.half_width - self.grid.spacing)

    def time_step_limit(self) -> float:
        """The largest sub-step tau with max|c| tau / dx <= the reconstruction's cfl: half
        the run's step limit (:func:`step_limit`)."""
        return 0.5 * step_limit(self.grid, self.dx, self.reconstruction.cfl)

    def rate(self, array, t: float):
        """-(F_{j+1/2} - F_{j-1/2}) / dx on the owned cells after filling the ghosts of
        ``array``, and the fluxes into the domain through the walls it touches
        ((wall, [mass, p_1 .. p_d, energy]) on the device, :func:`wall_weights`; zero where
        it touches none), at time t."""
        domain, xp, d = self.domain, self.xp, self.grid.dimension
        domain.exchange(array, self.left, self.right, t)
        minus, plus = self._faces(xp.swapaxes(array, 0, 1))
        flux = self.positive * minus + self.negative * plus     # (block_cells + 1, blocks, ...)
        walls = []
        lower, upper = domain.sides
        if domain.touches_left and not self.left.periodic:
            out = lower.from_wall(self.left.emit(lower.to_wall(plus[0, 0], d, xp), self.grid,
                                                 xp, t=t, side=lower), d, xp)
            flux[0, 0] = self.positive * out + self.negative * plus[0, 0]
            walls.append(self._moments(flux[0, 0]))
        else:
            walls.append(xp.zeros(d + 2))
        if domain.touches_right and not self.right.periodic:
            out = upper.from_wall(self.right.emit(upper.to_wall(minus[-1, -1], d, xp),
                                                  self.grid, xp, t=t, side=upper), d, xp)
            flux[-1, -1] = self.positive * minus[-1, -1] + self.negative * out
            walls.append(-self._moments(flux[-1, -1]))
        else:
            walls.append(xp.zeros(d + 2))
        rate = (flux[:-1] - flux[1:]) * (1.0 / self.dx)
        return xp.swapaxes(rate, 0, 1), xp.stack(walls)

    def _moments(self, face):
        """The mass, momentum and energy fluxes sum_v w F dv of a face flux F
        (:func:`wall_weights`), on the device."""
        return (self._weights * face).reshape(self._weights.shape[0], -1).sum(axis=1)


def box_step_limit(grid, spacing, cfl: float) -> float:
    r"""The transport's CFL limit on a run's time step in a box of cell widths ``spacing``
    (dx, dy[, dz]): each half step dt/2 of the unsplit transport
    (:class:`BoxTransport`) keeps

    .. math:: \frac{\Delta t}{2} \sum_a \frac{|c_a|}{\Delta x_a} \le \mathrm{cfl}
              \quad\text{at every node,}\qquad
              \Delta t \le \frac{2\,\mathrm{cfl}}{(L - h) \sum_a 1/\Delta x_a},

    the fastest node moving at L - h along every axis at once (a corner of the velocity
    box). One forward Euler stage of the unsplit scheme is the average, with weights
    w_a = (|c_a|/dx_a) / sum_b |c_b|/dx_b, of one-axis stages of length dt/w_a, whose
    Courant numbers are dt sum_b |c_b|/dx_b: each is positive (and the limited
    reconstructions TVD along its axis) when that is at most the reconstruction's ``cfl``
    (:func:`step_limit`), and so is their convex combination and the SSP Runge-Kutta
    method built of such stages (Gottlieb, Shu & Tadmor, SIAM Rev. 43 (2001) 89). On a
    square, dx = dy, it is half the one-dimensional limit of the same dx."""
    return 2.0 * cfl / ((grid.half_width - grid.spacing) * sum(1.0 / h for h in spacing))


class BoxTransport(_SSPTransport):
    r"""Free transport d_t f + v . grad_x f = 0 on the block of a :class:`~granframe.space.domain.Box`:
    finite volumes with the fluxes along every axis from the same state in each stage
    (unsplit, dimension by dimension),

    .. math:: \frac{d f_{ij}}{dt} = -\frac{F_{i+1/2,j} - F_{i-1/2,j}}{\Delta x}
              - \frac{G_{i,j+1/2} - G_{i,j-1/2}}{\Delta y},

    F the upwind flux of the module notes along x with the speeds of v_1, G along y with
    those of v_2, each from face values reconstructed along its own axis
    (:class:`~granframe.abc.Reconstruction`, MUSCL or WENO5 one axis at a time), stepped
    by the same three-stage SSP Runge-Kutta method as the line. The flux of a node is
    linear with a constant speed, c_1 f: the exact flux through the face x_{i+1/2} of
    cell (i, j) is c_1 times the average of f over that face, and the one-axis
    reconstruction of the cell averages (i + k, j) along x is the reconstruction of the
    averages in y over [y_{j-1/2}, y_{j+1/2}], whose value at x_{i+1/2} is that face
    average. So the dimension-by-dimension scheme keeps the one-axis order, 2 for MUSCL and
    5 for WENO5 on smooth data (it falls to 2 only for nonlinear fluxes, where the face
    average of the flux is not the flux of the face average: Zhang, Zhang & Shu, Commun.
    Comput. Phys. 9 (2011) 807); docs/space.md, "Two dimensions", measures both.
    The time step limit is :func:`box_step_limit`. Data that do not vary along an axis
    have zero flux differences along it exactly, so they step as on the line.

    The walls. Each side's wall sees the strip of face values next to it in its own frame
    (:class:`~granframe.abc.Side`): the wall at the bottom (y = 0) the nodes with v_2 > 0
    as leaving, its tangential velocity along v_1. At a corner two walls meet: the cell in
    the corner takes its x flux from the wall at its left or right and its y flux from the
    wall below or above it, each as on its own side; no flux crosses the corner point and
    no ghost cell at a corner is read (:class:`~granframe.space.domain.Box`).

    :attr:`wall_totals` (2 dimension, [mass, p_1 .. p_d, energy]): what entered through
    each side (:attr:`Box.sides <granframe.space.domain.Box.sides>` order: left, right,
    bottom, top), the face fluxes summed over the side's faces times their measure
    (dy along a side of x, dx along one of y): per unit length along z in two space
    dimensions.

    Parameters
    ----------
    domain : Box
    reconstruction : Reconstruction
    walls : sequence of Boundary
        The boundaries of the sides, in :attr:`Box.sides` order; periodic in pairs along
        an axis, or two walls.
    backend : ArrayBackend, optional
        As in :class:`Transport`.
    """

    def __init__(self, domain: Box, reconstruction, walls, backend=None):
        self._backend = backend
        walls = tuple(walls)
        if len(walls) != len(domain.sides):
            raise ValueError(f"BoxTransport: parameter 'walls' has {len(walls)} boundaries; "
                             f"must give one for each side ({', '.join(map(str, domain.sides))})")
        for axis in range(domain.dimension):
            if walls[2 * axis].periodic != walls[2 * axis + 1].periodic:
                raise ValueError(f"BoxTransport: the sides {domain.sides[2 * axis]} and "
                                 f"{domain.sides[2 * axis + 1]} must be both periodic or both "
                                 "walls")
        self.domain, self.reconstruction, self.walls = domain, reconstruction, walls
        grid, xp = domain.grid, domain.xp
        self.grid, self.xp = grid, xp
        self.spacing = domain.spacing
        self.speeds = [upwind_speeds(grid, xp, axis) for axis in range(domain.dimension)]
        self._weights = [xp.asarray(wall_weights(grid, axis))
                         for axis in range(domain.dimension)]
        #: what entered through each side since the last :meth:`take_wall_totals`
        self.wall_totals = xp.zeros((len(walls), grid.dimension + 2))

    @property
    def max_speed(self) -> float:
        """max |c_a| = L - h along every axis."""
        return float(self.grid.half_width - self.grid.spacing)

    def time_step_limit(self) -> float:
        """The largest sub-step tau: half the run's step limit (:func:`box_step_limit`)."""
        return 0.5 * box_step_limit(self.grid, self.spacing, self.reconstruction.cfl)

    def rate(self, array, t: float):
        """The rate of the owned cells (n_x, n_y, *grid.shape) after filling the ghosts of
        ``array``, and what enters through each side per unit time ((side, [mass,
        p_1 .. p_d, energy]) on the device, zero at a side the block does not touch or a
        periodic one), at time t."""
        domain, xp, d = self.domain, self.xp, self.grid.dimension
        domain.exchange(array, self.walls, t)
        rate, walls = None, []
        for axis, (positive, negative) in enumerate(self.speeds):
            lower, upper = domain.sides[2 * axis], domain.sides[2 * axis + 1]
            left, right = self.walls[2 * axis], self.walls[2 * axis + 1]
            low, high = domain.touches[axis]
            minus, plus = self._faces(domain.along(array, axis))
            measure = domain.cell_volume / self.spacing[axis]
            zero = xp.zeros(d + 2)
            ends = [None, None]           # the fluxes through the walls, from the face values
            if low and not left.periodic:
                out = lower.from_wall(left.emit(lower.to_wall(plus[0], d, xp), self.grid, xp,
                                                t=t, side=lower), d, xp)
                ends[0] = positive * out + negative * plus[0]
                walls.append(self._moments(ends[0], axis) * measure)
            else:
                walls.append(zero)
            if high and not right.periodic:
                out = upper.from_wall(right.emit(upper.to_wall(minus[-1], d, xp), self.grid,
                                                 xp, t=t, side=upper), d, xp)
                ends[1] = positive * minus[-1] + negative * out
                walls.append(-self._moments(ends[1], axis) * measure)
            else:
                walls.append(zero)
            # F = c+ f- + c- f+, in place in the face values (n_axis + 1, others..., *grid),
            # unless they are views of the state (the upwind reconstruction's)
            if _may_share(xp, minus, array) or _may_share(xp, minus, plus):
                minus, plus = minus.copy(), plus.copy()
            flux = xp.multiply(minus, positive, out=minus)
            flux += xp.multiply(plus, negative, out=plus)
            for index, end in zip((0, -1), ends):
                if end is not None:
                    flux[index] = end
            part = flux[:-1] - flux[1:]
            part *= 1.0 / self.spacing[axis]
            if rate is None:
                rate = xp.moveaxis(part, 0, axis)
            else:
                rate += xp.moveaxis(part, 0, axis)
        return rate, xp.stack(walls)

    def _moments(self, faces, axis: int):
        """The mass, momentum and energy fluxes sum_faces sum_v w F dv of the face fluxes
        F of one side (faces..., *grid.shape) (:func:`wall_weights` of ``axis``)."""
        weights = self._weights[axis]
        total = faces.reshape((-1,) + tuple(self.grid.shape)).sum(axis=0)
        return (weights * total).reshape(weights.shape[0], -1).sum(axis=1)


def _may_share(xp, a, b) -> bool:
    """Whether arrays ``a`` and ``b`` may overlap in memory (True where the namespace cannot
    tell)."""
    test = getattr(xp, "may_share_memory", None)
    return True if test is None else bool(test(a, b))
