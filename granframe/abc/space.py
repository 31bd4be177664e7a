"""The contracts of a space run: the reconstruction of cell averages at the faces, the
boundaries at the ends of the interval, and the levels of the hierarchy of collision models.

:mod:`granframe.space` implements them (:mod:`granframe.space.reconstruction`,
:mod:`granframe.space.boundaries`, :mod:`granframe.space.hierarchy`). Imported from
:mod:`granframe.abc`.
"""

from __future__ import annotations

import abc
from typing import ClassVar



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
    the core maps the right wall to it by the exact reflection v_1 -> -v_1 of the velocity
    nodes (:func:`granframe.space.transport.reflect`), so that the velocities that leave
    the wall into the domain are always those with v_1 > 0.

    :meth:`ghosts` and :meth:`emit` are told the time ``t`` at which the wall acts (the
    stage time of the transport) and ``side``, which wall it is in the lab frame: "left"
    (x = 0) or "right" (x = ell). A wall that moves along x with lab velocity U has the
    normal velocity +U in its own frame on the left and -U on the right (the reflection
    reverses v_1). Both run inside a time step, on the device with a GPU backend: they
    must not copy device arrays to the host (no ``float()`` of an array, no branching on
    array values) and should keep their constant arrays per grid and array namespace
    rather than copy them from the host on every call.
    """

    #: the two ends are one (a periodic interval): both must be periodic, and the core
    #: fills the ghost cells from the other end; :meth:`ghosts` and :meth:`emit` are unused
    periodic: ClassVar[bool] = False

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

    @abc.abstractmethod
    def ghosts(self, inside, grid, xp, *, t: float = 0.0, side: str = "left"):
        """Ghost cells beyond the wall from the cells next to it, at time ``t``.

        ``inside``: the first g cells from the wall inwards, shape (g, *grid.shape), in
        the wall's own frame (the right wall's reflected). Returns g ghost cells, ordered
        from the wall outwards, of the same shape. They feed the reconstruction of the
        faces near the wall; the flux through the wall itself is set by :meth:`emit`.
        ``side``: "left" or "right", the wall in the lab frame.
        """

    @abc.abstractmethod
    def emit(self, incoming, grid, xp, *, t: float = 0.0, side: str = "left"):
        """The face values at the wall at time ``t``.

        ``incoming``: f at the wall reconstructed from inside, shape (*grid.shape), in the
        wall's own frame (the right wall's reflected); the values at v_1 < 0 (moving into
        the wall) are what arrives. Returns the values at the wall for every node: those
        at v_1 > 0 are what the wall sends into the domain (the others are not used). Zero
        net mass flux means sum_{v_1 > 0} v_1 out = sum_{v_1 < 0} |v_1| incoming on the
        grid, at every t. ``side``: "left" or "right", the wall in the lab frame.
        """
