"""The contracts of a space run: the reconstruction of cell averages at the faces, the
sides of the domain and the boundaries there, and the levels of the hierarchy of collision
models.

:mod:`granframe.space` implements them (:mod:`granframe.space.reconstruction`,
:mod:`granframe.space.boundaries`, :mod:`granframe.space.hierarchy`). Imported from
:mod:`granframe.abc`.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import attrs
import numpy

from granframe import validators as check

#: the names of the space axes, as the store names its cell coordinates
AXIS_NAMES = ("x", "y", "z")
#: the names of the two ends of each space axis, lower then upper: x, y, z
SIDE_NAMES = (("left", "right"), ("bottom", "top"), ("back", "front"))


@attrs.frozen(eq=False)
class Side:
    r"""One side of the space domain: a space axis and one of its ends.

    ``axis`` 0 is x, 1 is y, 2 is z; ``end`` 0 is the lower end (x = 0), 1 the upper end
    (x = ell). The names (:data:`SIDE_NAMES`, :attr:`name`) are those of the description's
    walls: ``left``/``right`` along x, ``bottom``/``top`` along y, ``back``/``front`` along z.

    A :class:`Boundary` sees its side in its own frame: the wall at the lower end of axis
    0 with the domain beyond it, the velocities that leave it into the domain those with
    v_1 > 0. A side equals its name (``Side(0, 1) == "right"``). :meth:`to_wall` maps f
    from the lab onto that frame, exactly on the velocity nodes: the normal velocity
    component v_{a+1} of axis a is brought to the first place (the velocity axes 1 and
    a + 1 exchanged, a symmetry of the cubic grid) and, at the upper end, reversed by
    :func:`reflect_nodes` (v_1 -> -v_1, the permutation i -> (N - i) mod N);
    :meth:`from_wall` is its inverse. Along x at the lower end both are the identity.
    """

    axis: int = attrs.field(default=0)
    end: int = attrs.field(default=0)

    @axis.validator
    def _check_axis(self, attribute, value):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 3:
            check.reject("Side", "axis", value, "must be 0 (x), 1 (y) or 2 (z)")

    @end.validator
    def _check_end(self, attribute, value):
        if value not in (0, 1) or isinstance(value, bool):
            check.reject("Side", "end", value, "must be 0 (the lower end) or 1 (the upper "
                         "end)")

    @classmethod
    def named(cls, name) -> "Side":
        """The side of a wall name (:data:`SIDE_NAMES`), or ``name`` itself if a Side."""
        if isinstance(name, Side):
            return name
        for axis, ends in enumerate(SIDE_NAMES):
            if name in ends:
                return cls(axis, ends.index(name))
        known = ", ".join(repr(n) for ends in SIDE_NAMES for n in ends)
        check.reject("Side", "side", name, f"must be one of {known}")

    @property
    def name(self) -> str:
        return SIDE_NAMES[self.axis][self.end]

    def __str__(self) -> str:
        return self.name

    def __eq__(self, other) -> bool:
        """Equal to the same side, and to its name: a wall written against names
        (``side == "right"``) reads a Side as it read the name."""
        if isinstance(other, Side):
            return (self.axis, self.end) == (other.axis, other.end)
        if isinstance(other, str):
            return other == self.name
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self.name)

    @property
    def normal_sign(self) -> float:
        """+1 at the lower end, -1 at the upper one: the velocity along the inward normal
        is the lab velocity along the axis times this."""
        return 1.0 if self.end == 0 else -1.0

    def to_wall(self, f, dimension: int, xp):
        """f (..., *grid.shape) of the lab in the wall's own frame (the class notes)."""
        first = f.ndim - dimension
        if self.axis:
            f = xp.swapaxes(f, first, first + self.axis)
        return reflect_nodes(f, dimension, xp) if self.end else f

    def from_wall(self, f, dimension: int, xp):
        """f (..., *grid.shape) of the wall's own frame back in the lab (:meth:`to_wall`
        undone)."""
        first = f.ndim - dimension
        if self.end:
            f = reflect_nodes(f, dimension, xp)
        return xp.swapaxes(f, first, first + self.axis) if self.axis else f


def reflect_nodes(f, dimension: int, xp=numpy):
    """f(R v) with R: v_1 -> -v_1, exactly on the nodes: i -> (N - i) mod N along the v_1
    axis (axis ``-dimension``) of f (..., *grid.shape)."""
    axis = f.ndim - dimension
    return xp.roll(xp.flip(f, axis=axis), 1, axis=axis)



class Reconstruction(abc.ABC):
    r"""Face values of cell averages along axis 0, for the finite-volume transport in x.

    Cell j holds the average f_j of f over [x_{j-1/2}, x_{j+1/2}]. A reconstruction gives
    at each face x_{j-1/2} the value reconstructed from the cell on its left (f^-) and from
    the cell on its right (f^+); the transport takes the upwind one,
    F_{j-1/2} = c^+ f^-_{j-1/2} + c^- f^+_{j-1/2} with c the speed of each velocity node
    (:mod:`granframe.space.transport`).
    """

    #: cells each side that the face values of the outermost faces read beyond the interior
    ghost: ClassVar[int]
    #: formal order of accuracy on smooth data
    order: ClassVar[int]
    #: largest Courant number max|c| dt/dx of one transport sub-step (three-stage SSP
    #: Runge-Kutta) for which the scheme is stable (and TVD, for the limited ones)
    cfl: ClassVar[float]

    @abc.abstractmethod
    def faces(self, f, xp):
        """Face values of the cell averages ``f`` of shape (n + 2 ghost, ...).

        Returns ``(minus, plus)``, each of shape (n + 1, ...): entry i is at the face
        between cells ghost + i - 1 and ghost + i (the n interior cells are
        ``f[ghost:ghost + n]``); ``minus`` reconstructed from the left cell, ``plus``
        from the right one. Every operation is element-wise over the trailing axes
        (the velocity nodes), in the array namespace ``xp``.
        """


class CollisionModel(abc.ABC):
    r"""One level of a space run's hierarchy of collision models (docs/space.md, "The
    hierarchy"): the collision step d_t f = Q(f, f)/eps + tau Delta_v f over dt, in the
    cells a run gives it.

    A factory is called as ``factory(context, **params)``, ``context`` holding the run's
    ``equation`` (:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`: the operator, the
    Knudsen number, the heat bath), its time ``integrator`` and ``temperature``, the mass
    weighted mean temperature of f0. The levels of a hierarchy are ordered from the
    cheapest to the full operator; the last must have ``full`` true.

    :meth:`advance` runs inside a step, on the device with a GPU backend (no transfer to
    the host), and must keep every cell's mass and momentum to round-off and change its
    energy only by the collisions' dissipation (and the heat bath's work), so that the
    interfaces between levels conserve what the transport carries across them.
    """

    #: the name it is registered under
    name: ClassVar[str]
    #: True for the full collision operator (the last level of every hierarchy)
    full: ClassVar[bool] = False

    @abc.abstractmethod
    def advance(self, f, t: float, dt: float):
        """f (cells, *grid.shape) after the collision step from t to t + dt, a new array
        or ``f`` updated in place. ``converged`` (boolean per cell, on the backend), when
        the model sets it, names the cells it left as they were (no equilibrium)."""


class Boundary(abc.ABC):
    r"""What happens at one end of the interval: a wall, or the link of a periodic interval.

    An implementation sees its wall as the left one, at x = 0 with the domain at x > 0:
    the core maps every side to it exactly on the velocity nodes (:meth:`Side.to_wall`:
    the normal velocity component first, reversed at an upper end), so that the velocities
    that leave the wall into the domain are always those with v_1 > 0, and its tangential
    components v_2 .. v_d are the lab's others, v_1 in the normal's place: (v_2, v_3) at
    the left and right, (v_1, v_3) at the bottom and top, (v_2, v_1) at the back and front.

    :meth:`ghosts` and :meth:`emit` are told the time ``t`` at which the wall acts (the
    stage time of the transport) and ``side``, which wall it is in the lab frame: a
    :class:`Side` (an axis and an end; its :attr:`~Side.name` "left" (x = 0) or "right"
    (x = ell) along x), or its name. A wall that moves along its axis with lab velocity U
    has the normal velocity U times :attr:`Side.normal_sign` in its own frame: +U on the
    left and -U on the right (the reflection reverses v_1). Both run inside a time step,
    on the device with a GPU backend: they must not copy device arrays to the host (no
    ``float()`` of an array, no branching on array values) and should keep their constant
    arrays per grid and array namespace rather than copy them from the host on every call.
    """

    #: the two ends are one (a periodic interval): both must be periodic, and the core
    #: fills the ghost cells from the other end; :meth:`ghosts` and :meth:`emit` are unused
    periodic: ClassVar[bool] = False

    #: an open end (a reservoir, :class:`granframe.space.boundaries.Reservoir`): mass,
    #: momentum and energy cross it, so the conformance kit does not ask it for a zero net
    #: mass flux or for an emission linear in what arrives
    open: ClassVar[bool] = False

    #: the period in t of what the wall does (:meth:`ghosts`, :meth:`emit`), a finite
    #: float > 0 for a wall that acts periodically in time (a property of its parameters,
    #: or a class attribute); None for one that does not depend on t, or not periodically.
    #: The conformance kit checks a wall at times spread over its period.
    period: float | None = None

    #: what the boundary does commutes with the scaling v -> omega v of the velocities
    #: (no temperature, speed or time of its own): a rescaled space run
    #: (:mod:`granframe.equations.rescaled`) admits only such boundaries
    scale_free: ClassVar[bool] = False

    def check(self, grid) -> None:
        """Refuse a velocity grid the boundary does not fit (a wall velocity of the wrong
        dimension), with a message naming the parameter."""

    def check_time_step(self, time_step: float) -> None:
        """Refuse a run's time step the boundary cannot be followed at (a wall moving
        faster than the steps sample its motion), with a message naming the parameter;
        every step is fine by default."""

    @abc.abstractmethod
    def ghosts(self, inside, grid, xp, *, t: float = 0.0, side: Side | str = "left"):
        """Ghost cells beyond the wall from the cells next to it, at time ``t``.

        ``inside``: the first g cells from the wall inwards, shape (g, *grid.shape), in
        the wall's own frame (the right wall's reflected). Returns g ghost cells, ordered
        from the wall outwards, of the same shape. They feed the reconstruction of the
        faces near the wall; the flux through the wall itself is set by :meth:`emit`.
        ``side``: the wall in the lab frame, a :class:`Side` or its name.
        """

    @abc.abstractmethod
    def emit(self, incoming, grid, xp, *, t: float = 0.0, side: Side | str = "left"):
        """The face values at the wall at time ``t``.

        ``incoming``: f at the wall reconstructed from inside, shape (*grid.shape), in the
        wall's own frame (the right wall's reflected); the values at v_1 < 0 (moving into
        the wall) are what arrives. Returns the values at the wall for every node: those
        at v_1 > 0 are what the wall sends into the domain (the others are not used). Zero
        net mass flux means sum_{v_1 > 0} v_1 out = sum_{v_1 < 0} |v_1| incoming on the
        grid, at every t. ``side``: the wall in the lab frame, a :class:`Side` or its name.
        """
