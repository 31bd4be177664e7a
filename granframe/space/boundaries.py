r"""The ends of the interval: periodic, specular and diffuse (Maxwell) walls.

Every boundary sees its wall as the left one (x = 0, the domain at x > 0, velocities
with v_1 > 0 leave the wall); :mod:`granframe.space.transport` maps the right wall onto it
by the exact reflection of the nodes. The flux through the wall is
F = c^+ out + c^- in with ``in`` the face value reconstructed from inside and ``out`` what
:meth:`emit` returns, c^± the upwind speeds of the nodes
(:func:`~granframe.space.transport.upwind_speeds`; the node -L moves both ways at L/2).

A diffuse wall with accommodation alpha (Maxwell 1879) sends back

.. math:: f_{out}(v) = (1 - \alpha) f_{in}(R v)
          + \alpha \frac{\Phi}{\sum_v c^+ M_w \Delta v} M_w(v),\quad
          \Phi = \sum_v |c^-| f_{in}(v) \Delta v,\quad c^+(v) > 0,

with M_w(v) = exp(-|v - u_w|^2 / (2 T_w)) and u_w tangential (no v_1 component). Since R
maps the nodes of c^- < 0 one to one onto those of c^+ > 0 with c^+(Rv) = -c^-(v), the discrete
mass flux sum_v c F Δv is zero to round-off: what arrives is sent back. Specular reflection
is alpha = 0.
"""

from __future__ import annotations

import functools
import math

import attrs
import numpy

from granframe import abc as contracts
from granframe import validators as check
from granframe.space.transport import reflect, upwind_speeds


@attrs.frozen
class Periodic(contracts.Boundary):
    """The two ends are one: x = ell continues at x = 0 (both ends must be periodic)."""

    periodic = True

    def ghosts(self, inside, grid, xp):
        raise TypeError("Periodic: the ghost cells of a periodic interval are filled from the "
                        "other end (granframe.space.transport.CellBlocks.exchange)")

    def emit(self, incoming, grid, xp):
        raise TypeError("Periodic: a periodic interval has no wall to emit from")


@attrs.frozen
class Specular(contracts.Boundary):
    """Specular reflection f(x_w, v) = f(x_w, R v), R: v_1 -> -v_1: a wall that conserves
    mass, momentum parallel to it and energy exactly (on the nodes, to round-off)."""

    def ghosts(self, inside, grid, xp):
        """The mirror images f(-x, R v) of the cells next to the wall (method of images)."""
        return reflect(inside, grid.dimension, xp)

    def emit(self, incoming, grid, xp):
        return reflect(incoming, grid.dimension, xp)


def _tangential(value):
    """The wall velocity as a list of the tangential components (v_2, ..., v_d); anything
    else, an integer beyond float range too, is left for the validator."""
    try:
        if check.is_real(value):
            return (float(value),)
        if isinstance(value, (list, tuple)) and all(check.is_real(v) for v in value):
            return tuple(float(v) for v in value)
    except OverflowError:
        pass
    return value


def _check_velocity(instance, attribute, value):
    if not (isinstance(value, tuple) and 1 <= len(value) <= 2
            and all(math.isfinite(v) for v in value)):
        check.reject("Diffuse", "velocity", value, "must be the finite tangential wall "
                     "velocity: a number (along v2) or a list of 1 (2D) or 2 (3D) numbers "
                     "(v2, v3)")


@attrs.frozen
class Diffuse(contracts.Boundary):
    r"""A diffuse (Maxwell) wall at temperature T_w moving with tangential velocity u_w,
    accommodation coefficient alpha (1: fully diffuse, 0: specular); see the module notes.

    Parameters
    ----------
    temperature : float
        T_w > 0, in granframe's temperature units (T = int |v-u|^2 f / (d rho)).
    velocity : float or list
        u_w: a number (along v_2), or the components (v_2) in 2D, (v_2, v_3) in 3D.
    accommodation : float
        alpha in [0, 1].
    """

    temperature: float = attrs.field(default=1.0, converter=check.to_float,
                                     validator=check.real(0.0, math.inf, lower_open=True))
    velocity: tuple = attrs.field(default=0.0, converter=_tangential,
                                 validator=_check_velocity)
    accommodation: float = attrs.field(default=1.0, converter=check.to_float,
                                       validator=check.real(0.0, 1.0))

    def check(self, grid) -> None:
        """The wall velocity must have d - 1 components (one given number is along v_2)
        and lie inside the box, and the wall Maxwellian must fit the grid: below 1e-8 of
        its peak on the faces of the box, and resolved by the nodes, sqrt(T_w) >= h / 2
        (the relative error of the half-range flux sum_{k >= 1} k h exp(-k^2 h^2 / (2 T_w)) h
        against its exact value T_w is 46 % there, 9 % at sqrt(T_w) = h, and grows to 1 as
        T_w -> 0, where the emission 0/0 is NaN)."""
        d = grid.dimension
        if len(self.velocity) > d - 1:
            check.reject("Diffuse", "velocity", list(self.velocity),
                         f"must have at most {d - 1} tangential component(s) (v2"
                         f"{', v3' if d == 3 else ''}) on a {d}D velocity grid")
        speed = max(abs(u) for u in self.velocity)
        gap = grid.half_width - speed
        if gap <= 0:
            check.reject("Diffuse", "velocity", list(self.velocity),
                         f"must lie inside the velocity box: |u_w| < L = {grid.half_width:g}")
        if self.temperature < 0.25 * grid.spacing ** 2:
            check.reject("Diffuse", "temperature", self.temperature,
                         f"must be >= h^2 / 4 = {0.25 * grid.spacing ** 2:.4g} (a thermal speed "
                         f"sqrt(T_w) of at least half the node spacing h = {grid.spacing:.4g}): "
                         "a colder wall Maxwellian falls on the nodes next to its centre "
                         "and its discrete wall flux sum c^+ M_w dv is off by 46 % or more; "
                         "refine the grid (n_modes) or warm the wall")
        if math.exp(-gap * gap / (2.0 * self.temperature)) > 1e-8:
            check.reject("Diffuse", "temperature", self.temperature,
                         f"with wall velocity {list(self.velocity)} gives a wall Maxwellian that "
                         f"does not fit the velocity box [-{grid.half_width:g}, "
                         f"{grid.half_width:g}]^{d} (above 1e-8 of its peak on its faces): "
                         f"lower it below {gap * gap / (2 * math.log(1e8)):.4g} "
                         "or widen the grid (support_radius)")

    def maxwellian(self, grid, xp=numpy):
        """exp(-|v - u_w|^2 / (2 T_w)) on the nodes (unnormalised)."""
        d = grid.dimension
        shift = [0.0, *self.velocity] + [0.0] * (d - 1 - len(self.velocity))
        points = grid.points()
        exponent = sum(((points - shift[i]) ** 2).reshape(
            [-1 if j == i else 1 for j in range(d)]) for i in range(d))
        return xp.asarray(numpy.exp(-exponent / (2.0 * self.temperature)))

    def _emission(self, grid, xp):
        """M_w / sum c^+ M_w dv at the nodes of c^+ > 0, 0 elsewhere; and |c^-| dv."""
        emission, arriving = _emission(self, grid)
        return xp.asarray(emission), xp.asarray(arriving)

    def ghosts(self, inside, grid, xp):
        """The emission of each cell next to the wall from its own arriving values (the
        cells' values at c < 0 kept): a smooth extension for the reconstruction."""
        return self.emit(inside, grid, xp)

    def emit(self, incoming, grid, xp):
        d = grid.dimension
        emission, arriving = self._emission(grid, xp)
        axes = tuple(range(incoming.ndim - d, incoming.ndim))
        flux = (arriving * incoming).sum(axis=axes, keepdims=True)
        positive, _ = upwind_speeds(grid, xp)
        out = self.accommodation * flux * emission
        if self.accommodation < 1.0:
            out = out + (1.0 - self.accommodation) * reflect(incoming, d, xp)
        return xp.where(positive > 0, out, incoming)


@functools.lru_cache(maxsize=16)
def _emission(wall: Diffuse, grid):
    """:meth:`Diffuse._emission` as NumPy arrays, computed once per wall and grid."""
    positive, negative = upwind_speeds(grid, numpy)
    m = wall.maxwellian(grid, numpy) * (positive > 0)
    m = m / float((positive * m).sum() * grid.cell_volume)
    return m, numpy.broadcast_to(-negative * grid.cell_volume, grid.shape).copy()
