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

import attrs
import numpy
from scipy import special

from granframe import abc as contracts
from granframe import validators as check
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
        speed = max(abs(u) for u in self.velocity)
        gap = grid.half_width - speed
        if gap <= 0:
            check.reject("Diffuse", "velocity", list(self.velocity),
                         f"must lie inside the velocity box: |u_w| < L = {grid.half_width:g}")
        _check_resolved("Diffuse", self.temperature, grid)
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


def _normal_sign(side) -> float:
    """+1 for the left wall, -1 for the right one: the normal velocity in the wall's own
    frame is the lab velocity along +x times this (:attr:`granframe.abc.Side.normal_sign`).
    The sides of the interval only: a space run's walls are at the ends of x."""
    try:
        named = contracts.Side.named(side)
    except ValueError:
        named = None
    if named is None or named.axis != 0:
        check.reject("Vibrating", "side", side, "must be 'left' (the wall at x = 0) or "
                     "'right' (the wall at x = ell)")
    return named.normal_sign


def _half_range_flux_error(grid, temperature: float, u: float) -> float:
    r"""Relative error of the grid's half-range flux of exp(-|v_1 - u|^2 / (2T)) against
    its exact value, sum_v c^+ M dv_1 / int_{v_1 > 0} v_1 M dv_1 - 1 (the node -L counted as
    +L at the speed c^+ = L/2). Both are scaled by exp(u^2 / (2T)), so that neither
    underflows for u << -sqrt(T):

    .. math:: \int_0^\infty v e^{-(v^2 - 2 v u)/(2T)} dv
              = T \left(1 + \sqrt{\pi/2}\, s\, \mathrm{erfcx}(-s/\sqrt{2})\right),
              \quad s = u/\sqrt{T}.
    """
    positive, _ = upwind_speeds(grid, numpy)
    speed = numpy.abs(grid.points()).reshape(positive.shape)
    discrete = float(numpy.sum(positive * numpy.exp(-(speed * speed - 2.0 * speed * u)
                                                    / (2.0 * temperature)))) * grid.spacing
    s = u / math.sqrt(temperature)
    exact = temperature * (1.0 + math.sqrt(0.5 * math.pi) * s
                           * float(special.erfcx(-s / math.sqrt(2.0))))
    return discrete / exact - 1.0


#: the fewest time steps in a period of a vibrating wall (:meth:`Vibrating.check_time_step`):
#: its phase advances by at most 45 degrees a step, and the stages of the transport's two
#: half steps take its velocity at least 48 times a period
STEPS_PER_PERIOD = 8


@attrs.frozen
class Vibrating(contracts.Boundary):
    r"""A fully diffuse wall at temperature T_w vibrating along x, in the small-amplitude
    approximation.

    In the lab frame the wall is at x_w + A sin(omega t) and moves with the velocity
    U(t) = A omega cos(omega t) along +x. It stays at x_w (its displacement, small against
    the mean free path and the cell, is dropped; its velocity is kept), and for
    c^+ > 0 it sends back, in its own frame (the domain at x > 0),

    .. math:: f_{out}(v) = \Phi\, \frac{M_{u}(v)}{\sum_v c^+ M_{u} \Delta v},\quad
              \Phi = \sum_v |c^-| f_{in}(v) \Delta v,\quad
              M_u(v) = e^{-(|v_1| - u)^2 / (2T_w)} e^{-|v_t|^2 / (2T_w)},

    with u = u_n(t) = +U(t) for the left wall and -U(t) for the right one (the reflection
    v_1 -> -v_1 that maps it onto a left wall reverses the normal), v_t = (v_2, ..., v_d),
    and |v_1| the speed with which a node leaves the wall (the node -L leaves at +L, with
    c^+ = L/2). The sum over the nodes of c^+ f_out Δv is Φ to round-off at every
    t: no mass is lost or made. The energy it injects per period into a given incoming f
    is :func:`granframe.space.exact.vibrating_wall_energy_per_period` (docs/space.md,
    "Moving and vibrating walls"). Kinetic theories of vibrated granular gases use this
    wall at a fixed place (e.g. V. Kumaran, J. Fluid Mech. 364 (1998) 163-185; the diffuse
    emission: J. C. Maxwell, Phil. Trans. R. Soc. 170 (1879) 231-256).

    Parameters
    ----------
    amplitude : float
        A >= 0, the amplitude of the wall's displacement A sin(omega t) along +x.
    frequency : float
        omega > 0, the angular frequency; the period is 2 pi / omega.
    temperature : float
        T_w > 0, in granframe's temperature units (T = int |v-u|^2 f / (d rho)).
    """

    amplitude: float = attrs.field(converter=check.to_float, validator=check.real(0.0, math.inf))
    frequency: float = attrs.field(converter=check.to_float,
                                   validator=check.real(0.0, math.inf, lower_open=True))
    temperature: float = attrs.field(default=1.0, converter=check.to_float,
                                     validator=check.real(0.0, math.inf, lower_open=True))

    @property
    def period(self) -> float:
        """2 pi / omega."""
        return 2.0 * math.pi / self.frequency

    def check_time_step(self, time_step: float) -> None:
        """Refuse a period shorter than :data:`STEPS_PER_PERIOD` steps: the wall velocity
        A omega cos(omega t) is taken at the transport stages of each step, and fewer
        steps alias it (a period of 6e-12 with dt = 3e-3 ran, its work sampled at the
        stages' phases)."""
        if self.period < STEPS_PER_PERIOD * time_step * (1 - 1e-12):
            check.reject("Vibrating", "frequency", self.frequency,
                         f"must give a period 2 pi / omega = {self.period:.4g} of at least "
                         f"{STEPS_PER_PERIOD} time steps (time_step = {time_step:g}): "
                         f"omega <= {2.0 * math.pi / (STEPS_PER_PERIOD * time_step):.4g}, "
                         "or a smaller time_step; the steps sample the wall's motion")

    @property
    def speed(self) -> float:
        """A omega, the largest wall speed."""
        return self.amplitude * self.frequency

    def normal_velocity(self, t: float = 0.0, side: str = "left") -> float:
        """u_n(t) = A omega cos(omega t) for the left wall, -A omega cos(omega t) for the
        right one: the wall's velocity along the normal into the domain."""
        return _normal_sign(side) * self.speed * math.cos(self.frequency * t)

    def check(self, grid) -> None:
        """The wall Maxwellian must fit the grid at every wall velocity |u| <= A omega:
        resolved by the nodes at rest, sqrt(T_w) >= h / 2 (as :class:`Diffuse`); below 1e-8
        of its peak on the faces of the box at u = A omega, (L - A omega)^2 / (2 T_w) >=
        ln 1e8; and resolved when the wall recedes fastest (u = -A omega), where the emission
        falls from v_1 = 0 over T_w / (A omega) once A omega > sqrt(T_w): its discrete
        half-range flux sum c^+ M_u dv_1 must be within 50 % of the exact one (46 % is the
        error of a wall at rest with sqrt(T_w) = h/2)."""
        h, L = grid.spacing, grid.half_width
        _check_resolved("Vibrating", self.temperature, grid)
        if math.exp(-L * L / (2.0 * self.temperature)) > 1e-8:
            check.reject("Vibrating", "temperature", self.temperature,
                         f"gives a wall Maxwellian that does not fit the velocity box "
                         f"[-{L:g}, {L:g}]^{grid.dimension} (above 1e-8 of its peak on its "
                         f"faces): lower it below {L * L / (2 * math.log(1e8)):.4g} or widen "
                         "the grid (support_radius)")
        gap = L - self.speed
        if not (gap > 0 and math.exp(-gap * gap / (2.0 * self.temperature)) <= 1e-8):
            largest = L - math.sqrt(2.0 * self.temperature * math.log(1e8))
            check.reject("Vibrating", "amplitude", self.amplitude,
                         f"with frequency {self.frequency:g} gives the wall speed A omega = "
                         f"{self.speed:.4g}, at which the wall Maxwellian (T_w = "
                         f"{self.temperature:g}) does not fit the velocity box [-{L:g}, {L:g}] "
                         f"(above 1e-8 of its peak on its faces): A omega must be <= "
                         f"{largest:.4g}; lower the amplitude or the frequency, or widen the "
                         "grid (support_radius)")
        error = _half_range_flux_error(grid, self.temperature, -self.speed)
        if abs(error) > 0.5:
            check.reject("Vibrating", "amplitude", self.amplitude,
                         f"with frequency {self.frequency:g} gives the wall speed A omega = "
                         f"{self.speed:.4g}, at which the receding wall's emission (falling "
                         f"from v_1 = 0 over about T_w / (A omega) = "
                         f"{self.temperature / self.speed:.3g}) is not resolved by the nodes "
                         f"(h = {h:.4g}): its discrete half-range flux is off by "
                         f"{100 * abs(error):.0f} % (at most 50 % allowed); lower the "
                         "amplitude or the frequency, refine the grid (n_modes) or warm the "
                         "wall")

    def _host_constants(self, grid):
        """NumPy arrays: the speed |v_1| with which each node leaves the wall, c^+ h, the mask
        c^+ > 0 (shape (N, 1, ..., 1)), the tangential Maxwellian exp(-|v_t|^2 / (2T_w))
        normalised to h^(d-1) sum = 1 (shape (1, N, ..., N)), and the arriving weights
        |c^-| dv (see :func:`_constants`)."""
        positive, negative = upwind_speeds(grid, numpy)
        speed = numpy.abs(grid.points()).reshape(positive.shape)       # the node -L leaves at +L
        tangential = numpy.exp(-sum(c * c for c in grid.mesh()[1:]) / (2.0 * self.temperature))
        tangential = tangential / (tangential.sum() * grid.spacing ** (grid.dimension - 1))
        return (speed, positive * grid.spacing, positive > 0, tangential,
                -negative * grid.cell_volume)

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        """The linear extension through the wall of :func:`_emitting_ghosts`, with the
        emission at time t."""
        return _emitting_ghosts(self, inside, grid, xp, t, side, _constants(self, grid, xp)[2])

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        """The emission of the class notes at time ``t`` (a Python float) on ``side``.

        Only the factor exp(-(|v_1| - u_n(t))^2 / (2 T_w)) on the N nodes of v_1 and its
        normalisation are computed per call, in ``xp`` from the cached node values; the
        normalisation stays a device scalar."""
        speed, weight, leaving, tangential, arriving = _constants(self, grid, xp)
        u = self.normal_velocity(t, side)
        normal = xp.exp((speed - u) ** 2 * (-0.5 / self.temperature)) * leaving
        normal = normal / (weight * normal).sum()
        axes = tuple(range(incoming.ndim - grid.dimension, incoming.ndim))
        flux = (arriving * incoming).sum(axis=axes, keepdims=True)
        return xp.where(leaving, flux * (normal * tangential), incoming)


@functools.lru_cache(maxsize=32)
def _constants(wall, grid, xp):
    """``wall._host_constants(grid)`` as arrays of the namespace ``xp``, made once per wall,
    grid and namespace: a wall called inside a time step on a GPU copies nothing from the
    host after its first call."""
    return tuple(xp.asarray(a) for a in wall._host_constants(grid))
