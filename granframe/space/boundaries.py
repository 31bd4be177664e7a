r"""The ends of the interval: periodic, specular and diffuse (Maxwell) walls, vibrating
walls and open ends (:class:`Reservoir`).

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

A vibrating wall (:class:`Vibrating`) is a fully diffuse wall that moves along x with the lab
velocity U(t) = A omega cos(omega t) in the small-amplitude approximation: it stays at its
place and sends back the half-range Maxwellian moving with its normal velocity
u_n(t) = +U(t) (left wall) or -U(t) (right wall, seen in its own frame), normalised the same
way, so that its discrete mass flux is zero at every t.

Every wall runs inside a time step, on the device with a GPU backend: its constant arrays are
made once per wall, grid and array namespace (:func:`_constants`), its emission never copies
a device array to the host.
"""

from __future__ import annotations

import functools
import math
from typing import ClassVar

import attrs
import numpy

from granframe import abc as contracts
from granframe.abc import Side
from granframe import validators as check
from granframe.space import vibration
from granframe.space.transport import reflect, upwind_speeds



@attrs.frozen
class Periodic(contracts.Boundary):
    """The two ends are one: x = ell continues at x = 0 (both ends must be periodic)."""

    periodic = True
    scale_free = True

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        raise TypeError("Periodic: the ghost cells of a periodic interval are filled from the "
                        "other end (granframe.space.domain.Domain.exchange)")

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        raise TypeError("Periodic: a periodic interval has no wall to emit from")


@attrs.frozen
class Specular(contracts.Boundary):
    """Specular reflection f(x_w, v) = f(x_w, R v), R: v_1 -> -v_1: a wall that conserves
    mass, momentum parallel to it and energy exactly (on the nodes, to round-off)."""

    scale_free = True

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        """The mirror images f(-x, R v) of the cells next to the wall (method of images)."""
        return reflect(inside, grid.dimension, xp)

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        """f_in(R v): the same at every t and on both sides."""
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


def _check_resolved(owner: str, temperature: float, grid) -> None:
    """Refuse a wall Maxwellian the nodes do not resolve: sqrt(T_w) >= h / 2 (the relative
    error of the half-range flux sum_{k >= 1} k h exp(-k^2 h^2 / (2 T_w)) h against its exact
    value T_w is 46 % there, 9 % at sqrt(T_w) = h, and grows to 1 as T_w -> 0)."""
    h = grid.spacing
    if temperature < 0.25 * h * h:
        check.reject(owner, "temperature", temperature,
                     f"must be >= h^2 / 4 = {0.25 * h * h:.4g} (a thermal speed sqrt(T_w) of at "
                     f"least half the node spacing h = {h:.4g}): a colder wall Maxwellian falls "
                     "on the nodes next to its centre and its discrete wall flux sum c^+ M_w dv "
                     "is off by 46 % or more; refine the grid (n_modes) or warm the wall")


def _check_fits(owner: str, velocity, speed: float, temperature: float, grid,
                names: tuple) -> None:
    """Refuse a Maxwellian of ``temperature`` drifting at ``speed`` (shown as ``velocity``)
    that does not fit the grid: inside the box, below 1e-8 of its peak on its faces, and
    resolved by the nodes (:func:`_check_resolved`). ``names``: the velocity's symbol, how
    the message calls the velocity, and what the Maxwellian belongs to."""
    symbol, called, kind = names
    gap = grid.half_width - speed
    if gap <= 0:
        check.reject(owner, "velocity", velocity,
                     f"must lie inside the velocity box: |{symbol}| < L = {grid.half_width:g}")
    _check_resolved(owner, temperature, grid)
    if math.exp(-gap * gap / (2.0 * temperature)) > 1e-8:
        shown = format(velocity, "g") if isinstance(velocity, float) else velocity
        check.reject(owner, "temperature", temperature,
                     f"with {called} {shown} gives a {kind} Maxwellian that "
                     f"does not fit the velocity box [-{grid.half_width:g}, "
                     f"{grid.half_width:g}]^{grid.dimension} (above 1e-8 of its peak on its "
                     f"faces): lower it below {gap * gap / (2 * math.log(1e8)):.4g} "
                     "or widen the grid (support_radius)")


def _emitting_ghosts(wall, inside, grid, xp, t, side, leaving):
    r"""The ghost cells of a wall that emits what arrives (:class:`Diffuse`,
    :class:`Vibrating`), from the g cells next to it: a linear extension of the data
    through the wall, kept non-negative.

    With f_0, f_1, ... the cells from the wall inwards (the left wall's frame) and ghost
    cell -(k+1) the k-th outwards, k = 0 .. g - 1,

    .. math:: f_{-(k+1)} = \max\bigl((k + 2) f_0 - (k + 1) f_1,\; 0\bigr)
              \quad \text{(arriving nodes, } c^- < 0\text{)},

              f_{-(k+1)} = \max\bigl(2 f_w - f_k,\; 0\bigr),\quad
              f_w = \mathrm{emit}\bigl(\tfrac12 (f_{-1} + f_0)\bigr)
              \quad \text{(leaving nodes, } c^+ > 0\text{; the node -L, which moves both
              ways, is one of them)}:

    what arrives is extrapolated linearly from inside (its face value at the wall is
    (3 f_0 - f_1)/2 to second order, where an even extension f_{-1} = f_0 would give the
    limited slope 0 and the first-order value f_0), and what leaves is the odd extension
    about the wall's emission f_w of those arriving values, so that f_w lies halfway
    between f_{-1} and f_0, as a value on the face does (the ghost cell of a boundary value,
    R. J. LeVeque, Finite Volume Methods for Hyperbolic Problems, Cambridge University
    Press, 2002, ch. 7). The clipping at 0 keeps the ghosts non-negative, and with them
    the face values of a limited reconstruction and the positivity of the transport
    (:class:`~granframe.space.reconstruction.MUSCL`). The flux through the wall is set by
    :meth:`emit` on the reconstructed face value, not by the ghosts; they shape the face
    values of the cells next to the wall. With one ghost cell (a first-order
    reconstruction, which does not read it) f_{-1} is the emission of f_0 from f_0's
    arriving values. In a steady Couette flow the even extension and the emission of the
    cell averages made the shear stress P_12 of the cell next to the wall 0.85 of the bulk
    value at dx = 1.25 mean free paths (docs/space.md, "The cell next to a wall").
    """
    if inside.shape[0] < 2:
        return wall.emit(inside, grid, xp, t=t, side=side)
    first, slope = inside[0], inside[0] - inside[1]
    arriving = [xp.maximum(first + (k + 1.0) * slope, 0.0) for k in range(inside.shape[0])]
    value = wall.emit(0.5 * (arriving[0] + first), grid, xp, t=t, side=side)
    return xp.stack([xp.where(leaving, xp.maximum(2.0 * value - cell, 0.0), ghost)
                     for cell, ghost in zip(inside, arriving)])


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
        _check_fits("Diffuse", list(self.velocity), max(abs(u) for u in self.velocity),
                    self.temperature, grid, ("u_w", "wall velocity", "wall"))

    def maxwellian(self, grid, xp=numpy):
        """exp(-|v - u_w|^2 / (2 T_w)) on the nodes (unnormalised)."""
        d = grid.dimension
        shift = [0.0, *self.velocity] + [0.0] * (d - 1 - len(self.velocity))
        points = grid.points()
        exponent = sum(((points - shift[i]) ** 2).reshape(
            [-1 if j == i else 1 for j in range(d)]) for i in range(d))
        return xp.asarray(numpy.exp(-exponent / (2.0 * self.temperature)))

    def _host_constants(self, grid):
        """NumPy arrays: M_w / sum c^+ M_w dv at the nodes of c^+ > 0 (0 elsewhere), the
        arriving weights |c^-| dv, and the mask c^+ > 0 (see :func:`_constants`)."""
        positive, negative = upwind_speeds(grid, numpy)
        leaving = positive > 0
        m = self.maxwellian(grid, numpy) * leaving
        m = m / float((positive * m).sum() * grid.cell_volume)
        return m, -negative * grid.cell_volume, leaving

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        """The linear extension through the wall of :func:`_emitting_ghosts`."""
        return _emitting_ghosts(self, inside, grid, xp, t, side, _constants(self, grid, xp)[2])

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        """The emission of the module notes; the same at every t and on both sides (the
        wall velocity is tangential, which the reflection v_1 -> -v_1 keeps)."""
        emission, arriving, leaving = _constants(self, grid, xp)
        axes = tuple(range(incoming.ndim - grid.dimension, incoming.ndim))
        flux = (arriving * incoming).sum(axis=axes, keepdims=True)
        out = self.accommodation * flux * emission
        if self.accommodation < 1.0:
            out = out + (1.0 - self.accommodation) * reflect(incoming, grid.dimension, xp)
        return xp.where(leaving, out, incoming)


@attrs.frozen
class Reservoir(contracts.Boundary):
    r"""An open end: beyond it a reservoir of Maxwellian gas at density n_r, velocity u_r
    along the end's axis (lab frame) and temperature T_r, as in the inflow boundaries of
    DSMC (G. A. Bird, *Molecular Gas Dynamics and the Direct Simulation of Gas Flows*,
    1994, section 12.2). What arrives at the end leaves the interval, and the reservoir
    sends in its own Maxwellian,

    .. math:: f_{out}(v) = M_r(v) = n_r (2\pi T_r)^{-d/2}
              \exp\bigl(-|v - u_n e_1|^2 / (2 T_r)\bigr),\quad c^+(v) > 0,

    in the end's own frame, u_n = u_r at the lower end and -u_r at the upper one
    (:attr:`~granframe.abc.Side.normal_sign`), as the grid holds it: sampled on the nodes
    and without its Nyquist modes (:meth:`VelocityGrid.project`, as an initial Maxwellian
    is; it rings below zero at the level of the grid's Nyquist coefficient,
    exp(-T_r (pi N / 2L)^2 / 2) relative, as f does inside). Mass, momentum and energy
    cross the end:
    the interval gains sum_v c^+ M_r dv and loses sum_v |c^-| f_in dv per unit time
    (the wall records of a run, ``wall_mass`` ..., count them). A gas at the reservoir's
    state next to the end is left exactly as it is: its face value is M_r on every node,
    so the flux through the end equals that through every face inside.

    Parameters
    ----------
    density : float
        n_r > 0.
    velocity : float
        u_r, the reservoir's velocity along the axis of the end, in the lab frame
        (positive towards increasing x); no tangential velocity.
    temperature : float
        T_r > 0.
    """

    open: ClassVar[bool] = True

    density: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=check.real(0.0, math.inf, lower_open=True))
    velocity: float = attrs.field(default=0.0, converter=check.to_float,
                                  validator=check.real(-math.inf, math.inf))
    temperature: float = attrs.field(default=1.0, converter=check.to_float,
                                     validator=check.real(0.0, math.inf, lower_open=True))

    def check(self, grid) -> None:
        """The reservoir's Maxwellian must fit the grid as a diffuse wall's must: inside the
        box, below 1e-8 of its peak on its faces, and resolved by the nodes,
        sqrt(T_r) >= h / 2."""
        _check_fits("Reservoir", self.velocity, abs(self.velocity), self.temperature, grid,
                    ("u_r", "velocity", "reservoir"))

    def _host_constants(self, grid):
        """NumPy arrays: M_r seen from a lower end and from an upper one, and the mask
        c^+ > 0 (see :func:`_constants`)."""
        positive, _ = upwind_speeds(grid, numpy)
        tangential = [0.0] * (grid.dimension - 1)
        lower, upper = (grid.project(grid.maxwellian(
            self.density, [sign * self.velocity, *tangential], self.temperature))
            for sign in (1.0, -1.0))
        return lower, upper, positive > 0

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        """The linear extension through the end of :func:`_emitting_ghosts`: what leaves
        extrapolated from inside, what enters the odd extension about M_r, non-negative
        (with one ghost cell M_r itself, clipped where it rings)."""
        ghosts = _emitting_ghosts(self, inside, grid, xp, t, side, _constants(self, grid, xp)[2])
        return xp.maximum(ghosts, 0.0)

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        """M_r at the entering nodes (c^+ > 0), whatever arrives; the same at every t."""
        lower, upper, leaving = _constants(self, grid, xp)
        reservoir = lower if Side.named(side).normal_sign > 0 else upper
        return xp.where(leaving, reservoir, incoming)


#: what a vibrating wall does to a particle it hits
REFLECTIONS = ("diffuse", "specular")


@attrs.frozen
class Vibrating(contracts.Boundary):
    r"""A wall vibrating along its normal, in the limit of small amplitude at fixed speed:
    A -> 0 at fixed V = A omega (:mod:`granframe.space.vibration`; docs/space.md,
    "Vibrating walls").

    The wall at X(t) = A sin(omega t) sweeps a collisionless layer of thickness 2A; in the
    limit it is a boundary condition that does not depend on time. An arriving particle
    of normal speed a hits the wall at the rate of their relative speed, first at a phase
    theta of density p_a(theta) = (a + cos theta) / a where it is not hidden by the wall's
    earlier motion; a ``diffuse`` wall sends it back from its own frame with the
    flux-weighted Maxwellian at T_w (lab normal speed V cos theta + w), a ``specular`` one
    with the lab speed 2 V cos theta + a; a particle slower than the wall can follow is
    caught again (the escape slope S(theta)) and sent back again. On the grid, with
    c^+ > 0 the leaving nodes and c^- < 0 the arriving ones,

    .. math:: f_{out}(v_1, v_t) = M_t(v_t) \sum_j K_{ij}\, \Phi_j \quad	ext{(diffuse)},
              \qquad \Phi_j = \sum_{v_t} |c^-_j|\, f_{in}(v_{1j}, v_t)\, h^{d-1},

              f_{out}(v_1, v_t) = \sum_j K_{ij}\, |c^-_j|\, f_{in}(v_{1j}, v_t)
              \quad	ext{(specular)},

    with M_t the tangential Maxwellian at T_w normalised to sum h^(d-1) = 1 and the kernel
    K_{ij} of leaving node i and arriving node j normalised to sum_i c^+_i K_{ij} = 1, so
    that what arrives at every node leaves, to round-off. For the diffuse wall K_{ij} is
    the layer's escape flux density g(|v_{1i}| | |v_{1j}|) over the leaving speed; for
    the specular one each escape speed b of the phase rule is shared between the two
    leaving nodes around it with the shares that keep its flux and its energy flux b^2/2,
    so that the energy of each arriving node comes out as the layer's, to round-off (2 V^2
    per particle from every node with a >= 3V). The tangential velocity of a specular hit
    is kept.

    Parameters
    ----------
    speed : float
        V = A omega > 0, the wall's largest speed.
    temperature : float
        T_w > 0 of a diffuse wall, in granframe's temperature units.
    reflection : str
        "diffuse" (default) or "specular".
    """

    speed: float = attrs.field(converter=check.to_float,
                               validator=check.real(0.0, math.inf, lower_open=True))
    temperature: float = attrs.field(default=1.0, converter=check.to_float,
                                     validator=check.real(0.0, math.inf, lower_open=True))
    reflection: str = attrs.field(default="diffuse")

    @reflection.validator
    def _check_reflection(self, attribute, value):
        if value not in REFLECTIONS:
            check.reject("Vibrating", "reflection", value,
                         f"must be one of {', '.join(map(repr, REFLECTIONS))}")

    def check(self, grid) -> None:
        """The wall must fit the grid: its speed below L - h (a specular wall sends the
        fastest arriving nodes back up to 2V faster; what would leave beyond L is put on the
        node -L); a diffuse wall's Maxwellian resolved by the nodes, sqrt(T_w) >= h / 2 (as
        :class:`Diffuse`), and below 1e-8 of its peak on the faces of the box when the wall
        moves at V, (L - V)^2 / (2 T_w) >= ln 1e8."""
        h, L = grid.spacing, grid.half_width
        if self.speed >= L - h:
            check.reject("Vibrating", "speed", self.speed,
                         f"must be below L - h = {L - h:.4g}, the fastest node of the velocity "
                         "grid; lower it or widen the grid (support_radius)")
        if self.reflection == "specular":
            return
        _check_resolved("Vibrating", self.temperature, grid)
        gap = L - self.speed
        if math.exp(-gap * gap / (2.0 * self.temperature)) > 1e-8:
            check.reject("Vibrating", "temperature", self.temperature,
                         f"with speed {self.speed:g} gives a wall Maxwellian that does not fit "
                         f"the velocity box [-{L:g}, {L:g}] (above 1e-8 of its peak on its "
                         f"faces): lower it below {gap * gap / (2 * math.log(1e8)):.4g}, "
                         "lower the speed, or widen the grid (support_radius)")

    def _host_constants(self, grid):
        """NumPy arrays: the kernel K (N, N) along v_1 (zero outside the leaving rows and
        arriving columns), the arriving weights |c^-| (N, 1, ..., 1), the mask c^+ > 0,
        and the tangential Maxwellian M_t (1, N, ..., N) normalised to h^(d-1) sum = 1
        (ones for a specular wall, unused); see :func:`_constants`."""
        positive, negative = upwind_speeds(grid, numpy)
        plus, minus = positive.ravel(), -negative.ravel()
        speed = numpy.abs(grid.points())                        # the node -L moves at L
        out, into = numpy.nonzero(plus > 0)[0], numpy.nonzero(minus > 0)[0]
        layer = vibration.Layer(self.speed, self.temperature)
        kernel = numpy.zeros((grid.n_modes, grid.n_modes))
        if self.reflection == "diffuse":
            block = layer.diffuse_escape(speed[out], speed[into]) / speed[out][:, None]
            tangential = numpy.exp(-sum(c * c for c in grid.mesh()[1:])
                                   / (2.0 * self.temperature))
            tangential = tangential / (tangential.sum() * grid.spacing ** (grid.dimension - 1))
        else:
            block = self._shares(speed[out], *layer.specular_escape(speed[into]))
            block = block / plus[out][:, None]
            tangential = numpy.ones((1,) * grid.dimension)
        block = block / (plus[out][:, None] * block).sum(axis=0)
        kernel[numpy.ix_(out, into)] = block
        return kernel, minus.reshape(negative.shape), (plus > 0).reshape(positive.shape), \
            tangential

    @staticmethod
    def _shares(nodes, exits, weight):
        r"""The flux (len(nodes), arriving) each leaving node receives when the escape speeds
        ``exits`` (phases, arriving) with ``weight`` are shared between the two nodes
        b_i <= b < b_{i+1} around each, t b_i^2 + (1 - t) b_{i+1}^2 = b^2 (flux and energy
        flux kept). An escape slower than the slowest leaving node h (or faster than the
        fastest) has no such pair: it goes to that node, and the energy it gains there
        (h^2 - b^2)/2 is taken back within its arriving node's column by moving flux from
        the next nodes up down to h (:meth:`_keep_energy`), so that every arriving node
        leaves with the energy of its escapes, to round-off."""
        order = numpy.argsort(nodes)
        sorted_nodes = nodes[order]
        squares = sorted_nodes ** 2
        flat, w = exits.ravel(), weight.ravel()
        column = numpy.broadcast_to(numpy.arange(exits.shape[1]), exits.shape).ravel()
        i = numpy.clip(numpy.searchsorted(sorted_nodes, flat, side="right") - 1, 0,
                       nodes.size - 2)
        t = (squares[i + 1] - flat ** 2) / (squares[i + 1] - squares[i])
        t = numpy.clip(t, 0.0, 1.0)
        shares = numpy.zeros((nodes.size, exits.shape[1]))
        numpy.add.at(shares, (order[i], column), w * t)
        numpy.add.at(shares, (order[i + 1], column), w * (1.0 - t))
        energy = (0.5 * exits * exits * weight).sum(axis=0)
        for k in range(exits.shape[1]):
            shares[order, k] = Vibrating._keep_energy(shares[order, k], 0.5 * squares,
                                                      energy[k])
        return shares

    @staticmethod
    def _keep_energy(flux, energies, target):
        """``flux`` over nodes of increasing energy ``energies`` with its total kept and its
        energy sum(flux energies) brought to ``target``: an excess moved down to the first
        node from the nodes above it in turn, a deficit up to the last from the nodes below
        it; the flux stays non-negative (the target lies between the first and the last
        node's energy times the total)."""
        flux = flux.copy()
        excess = float(flux @ energies) - target
        scale = abs(target) + float(flux.sum() * energies[-1])
        if excess > 1e-15 * scale:
            low, sources = 0, range(1, flux.size)
        elif excess < -1e-15 * scale:
            low, sources = flux.size - 1, range(flux.size - 2, -1, -1)
        else:
            return flux
        for i in sources:
            step = abs(energies[i] - energies[low])
            moved = min(flux[i], abs(excess) / step)
            flux[i] -= moved
            flux[low] += moved
            excess -= numpy.sign(excess) * moved * step
            if abs(excess) <= 1e-15 * scale:
                break
        return flux

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        """The linear extension through the wall of :func:`_emitting_ghosts`."""
        return _emitting_ghosts(self, inside, grid, xp, t, side, _constants(self, grid, xp)[2])

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        """The emission of the class notes; the same at every t and on both sides (the
        limit averages over the phase, and a phase shift of half a period reverses U)."""
        kernel, arriving, leaving, tangential = _constants(self, grid, xp)
        d = grid.dimension
        normal = incoming.ndim - d
        weighted = arriving * incoming
        if self.reflection == "diffuse":
            flux = weighted.sum(axis=tuple(range(normal + 1, incoming.ndim))) \
                * grid.spacing ** (d - 1)
            out = (flux @ kernel.T).reshape(flux.shape + (1,) * (d - 1)) * tangential
        else:
            out = xp.moveaxis(xp.tensordot(kernel, weighted, axes=([1], [normal])), 0, normal)
        return xp.where(leaving, out, incoming)


@functools.lru_cache(maxsize=32)
def _constants(wall, grid, xp):
    """``wall._host_constants(grid)`` as arrays of the namespace ``xp``, made once per wall,
    grid and namespace: a wall called inside a time step on a GPU copies nothing from the
    host after its first call."""
    return tuple(xp.asarray(a) for a in wall._host_constants(grid))
