r"""Initial data f0(x, v) of space-inhomogeneous runs, as cell averages.

Each condition gives, for the cell edges x_0 < ... < x_n of [0, ell], the average of f0
over every cell at every velocity node (:meth:`SpaceCondition.sample_cells`):

- :class:`RiemannProblem`: Maxwellians of (rho, u, T) left and right of x = a ell, each
  cell the exact mixture by the share of it on each side;
- :class:`SinusoidalMode`: a uniform Maxwellian with rho, u_1 or T times
  1 + A sin(2 pi k x / ell), averaged by Gauss-Legendre quadrature (6 points per cell:
  exact to degree 11, so the initial averages do not limit any reconstruction's order);
- :class:`SpaceFunction`: any f0(x, v_1, ..., v_d) given as a ``module:function``, the
  same quadrature.

On a rectangle each gives the averages over the cells [x_{i-1}, x_i] x [y_{j-1}, y_j]
(:meth:`SpaceCondition.sample_box`): a condition along x alone is the same in every row
of cells along y (a Riemann problem with its interface across x, a mode along x);
:class:`SinusoidalMode` takes a wave vector (k_x, k_y), :class:`SpaceFunction` is
f0(x, y, v_1, ..., v_d), both averaged by the tensor Gauss-Legendre rule (6 x 6 points),
and :class:`QuadrantProblem` is the two-dimensional Riemann problem of four Maxwellian
quadrants, each cell the exact mixture by the share of it in each quadrant.

Any space-homogeneous initial condition (``maxwellian``, ``bkw``, ...) is uniform in x.
As :class:`~granframe.abc.InitialCondition` each gives ``sample(grid)``, the average of f0
over the interval (the distribution of the whole gas).
"""

from __future__ import annotations

import functools
import inspect
import math

import attrs
import numpy

from granframe import abc as contracts
from granframe import validators as check
from granframe.model.initial import check_real, resolve_callable

#: Gauss-Legendre points per cell of the averages
CELL_POINTS = 6

#: Range of the densities, temperatures and |velocities| of the states: the Maxwellian's
#: peak rho (2 pi T)^(-d/2), its square (in Q(f, f)) and its fourth moments stay finite
#: in float64.
STATE_RANGE = (1e-50, 1e50)

#: Range of the largest value of f0 in each cell: Q(f, f), quadratic in f, and the fourth
#: moments of f0 stay finite in float64.
PEAK_RANGE = (1e-100, 1e100)


def _finite(value) -> bool:
    """A finite real number (not bool), an integer beyond float range excluded."""
    try:
        return check.is_real(value) and math.isfinite(float(value))
    except OverflowError:
        return False


def _speed(value) -> bool:
    """A finite real number of magnitude at most the upper end of :data:`STATE_RANGE`."""
    return _finite(value) and abs(float(value)) <= STATE_RANGE[1]


def _velocity(value, owner, name):
    """A velocity given as u_1 (a number) or all d components, as a tuple."""
    if _speed(value):
        return (float(value),)
    if isinstance(value, (list, tuple)) and 1 <= len(value) <= 3 and all(map(_speed, value)):
        return tuple(float(v) for v in value)
    check.reject(owner, name, value, "must be u_1 (a finite number) or the d components of u, "
                 f"each of magnitude <= {STATE_RANGE[1]:g}")


def _full(velocity, grid, owner, name):
    d = grid.dimension
    if len(velocity) not in (1, d):
        check.reject(owner, name, list(velocity), f"must be u_1 or {d} components on a {d}D grid")
    return tuple(velocity) + (0.0,) * (d - len(velocity))


def _state(value, owner, name):
    """A hydrodynamic state {density, velocity, temperature}, rho and T in
    :data:`STATE_RANGE`."""
    if not isinstance(value, dict):
        check.reject(owner, name, value, "must be a table {density, velocity, temperature}",
                     error=TypeError)
    unknown = set(value) - {"density", "velocity", "temperature"}
    if unknown:
        check.reject(owner, f"{name}.{sorted(unknown)[0]}", value[sorted(unknown)[0]],
                     "is not a state variable (density, velocity, temperature)")
    state = {"density": value.get("density", 1.0), "velocity": value.get("velocity", 0.0),
             "temperature": value.get("temperature", 1.0)}
    for key in ("density", "temperature"):
        if not (_finite(state[key])
                and STATE_RANGE[0] <= float(state[key]) <= STATE_RANGE[1]):
            check.reject(owner, f"{name}.{key}", state[key], f"must be a finite number in "
                         f"[{STATE_RANGE[0]:g}, {STATE_RANGE[1]:g}]")
        state[key] = float(state[key])
    state["velocity"] = list(_velocity(state["velocity"], owner, f"{name}.velocity"))
    return state


class SpaceCondition(contracts.InitialCondition):
    """Initial data that depends on x: :meth:`sample_cells` gives the cell averages."""

    def sample_cells(self, grid, edges):
        """(f0 cell averages (cells, *grid.shape), the intended mass of each cell or None)."""
        raise NotImplementedError

    def sample(self, grid):
        """The average of f0 over the interval (the mean of 64 equal cells)."""
        f, _ = self.sample_cells(grid, numpy.linspace(0.0, 1.0, 65))
        return f.mean(axis=0)

    def sample_box(self, grid, edges):
        """(f0 cell averages (Cx, Cy, *grid.shape), the intended mass of each cell
        (Cx, Cy) or None) on the rectangle of cell ``edges`` (along x, along y): by default
        the data along x (:meth:`sample_cells`) in every row of cells along y."""
        f, mass = self.sample_cells(grid, edges[0])
        rows = len(edges[1]) - 1
        f = numpy.broadcast_to(f[:, None], (f.shape[0], rows) + f.shape[1:])
        return f, None if mass is None else numpy.repeat(numpy.asarray(mass)[:, None], rows,
                                                         axis=1)

    @property
    def intended_mass(self):
        return None


def _gauss(edges):
    """Gauss-Legendre points (cells, CELL_POINTS) of each cell and the weights (sum 1)."""
    nodes, weights = numpy.polynomial.legendre.leggauss(CELL_POINTS)
    left, right = numpy.asarray(edges[:-1]), numpy.asarray(edges[1:])
    x = 0.5 * (left + right)[:, None] + 0.5 * (right - left)[:, None] * nodes[None, :]
    return x, 0.5 * weights


def _box_points(edges):
    """The tensor Gauss-Legendre rule of the cells of a rectangle: for each of the
    CELL_POINTS^2 points, its x (Cx, 1) and y (1, Cy) in every cell and its weight (the
    weights sum to 1)."""
    (x, wx), (y, wy) = _gauss(edges[0]), _gauss(edges[1])
    return [(x[:, p][:, None], y[:, q][None, :], wx[p] * wy[q])
            for p in range(CELL_POINTS) for q in range(CELL_POINTS)]


def _maxwellians(grid, density, velocity, temperature):
    """rho (2 pi T)^(-d/2) exp(-|v - u|^2 / (2 T)) on the nodes for arrays of states:
    ``density`` and ``temperature`` of one shape S, ``velocity`` a list of d arrays
    broadcasting to S; the result (*S, *grid.shape)."""
    d = grid.dimension
    tail = (1,) * d
    shape = numpy.shape(density)
    lead = (1,) * len(shape)
    square = sum((c.reshape(lead + c.shape)
                  - numpy.broadcast_to(u, shape).reshape(shape + tail)) ** 2
                 for c, u in zip(grid.mesh(), velocity))
    t = numpy.reshape(temperature, shape + tail)
    return numpy.reshape(density, shape + tail) * (2.0 * math.pi * t) ** (-d / 2) \
        * numpy.exp(-square / (2.0 * t))


@attrs.frozen
class RiemannProblem(SpaceCondition):
    """Maxwellians of the states ``left`` and ``right`` on each side of x = interface ell.

    Parameters
    ----------
    left, right : dict
        ``{density, velocity, temperature}``; velocity u_1 (a number) or all d components.
        The elastic Sod tube: left (1, 0, 1), right (0.125, 0, 0.8) (p = rho T = 0.1).
    interface : float
        Position of the discontinuity as a fraction of the length, in (0, 1).
    """

    left: dict = attrs.field(converter=lambda v: _state(v, "RiemannProblem", "left"))
    right: dict = attrs.field(converter=lambda v: _state(v, "RiemannProblem", "right"))
    interface: float = attrs.field(default=0.5, converter=check.to_float,
                                   validator=check.real(0.0, 1.0, lower_open=True,
                                                        upper_open=True))

    def sample_cells(self, grid, edges):
        edges = numpy.asarray(edges, dtype=float)
        owner = "RiemannProblem"
        states = [grid.maxwellian(s["density"], _full(s["velocity"], grid, owner, side),
                              s["temperature"])
                  for side, s in (("left.velocity", self.left), ("right.velocity", self.right))]
        x0 = self.interface * edges[-1]
        share = numpy.clip((x0 - edges[:-1]) / numpy.diff(edges), 0.0, 1.0)   # left of x0
        shape = (-1,) + (1,) * grid.dimension
        f = share.reshape(shape) * states[0] + (1.0 - share).reshape(shape) * states[1]
        mass = share * self.left["density"] + (1.0 - share) * self.right["density"]
        return f, mass


_FIELDS = ("density", "velocity", "temperature")


def _wave(value):
    """A mode number as an int, a wave vector [k_x, k_y] of integers as a tuple."""
    if isinstance(value, (list, tuple)) and len(value) == 2 and all(map(check.is_integer,
                                                                         value)):
        return tuple(int(v) for v in value)
    return check.to_int(value)


@attrs.frozen
class SinusoidalMode(SpaceCondition):
    """A uniform Maxwellian (rho, u_1, T) with one of them times 1 + A sin(2 pi k x / ell)
    (the velocity: u_1 + A sin(...) along ``component``; a transverse component, u_2,
    makes a shear mode).

    Parameters
    ----------
    density, velocity, temperature : float
        The uniform state (velocity: u_1, along x); rho, T and |u_1| in
        :data:`STATE_RANGE`.
    field : str
        The perturbed field: 'density', 'velocity' or 'temperature'.
    amplitude : float
        A; |A| < 1 for the density and the temperature (positive fields).
    mode : int or list of two int
        k >= 1, the number of periods on the interval; on a rectangle also a wave vector
        [k_x, k_y] (integers, not both 0): the phase 2 pi (k_x x / L_x + k_y y / L_y), a
        plane wave of wave vector K = 2 pi (k_x / L_x, k_y / L_y) (one number: along x).
    component : int
        The velocity component the ``velocity`` mode perturbs: 1 (along x, a longitudinal
        mode, the default) to d (2 or 3: transverse, a shear mode). With a wave vector:
        1 along K (longitudinal), 2 along K rotated by +90 degrees in the plane
        (transverse, a shear mode in the plane), 3 along v_3.
    """

    density: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=check.real(*STATE_RANGE))
    velocity: float = attrs.field(default=0.0, converter=check.to_float,
                                  validator=check.real(-STATE_RANGE[1], STATE_RANGE[1]))
    temperature: float = attrs.field(default=1.0, converter=check.to_float,
                                     validator=check.real(*STATE_RANGE))
    field: str = attrs.field(default="density", validator=check.one_of(_FIELDS))
    amplitude: float = attrs.field(default=0.1, converter=check.to_float,
                                   validator=check.real(-STATE_RANGE[1], STATE_RANGE[1]))
    mode: int | tuple = attrs.field(default=1, converter=_wave)
    component: int = attrs.field(default=1, converter=check.to_int,
                                 validator=check.integer(1, 3))

    @component.validator
    def _check_component(self, attribute, value):
        if value != 1 and self.field != "velocity":
            check.reject("SinusoidalMode", "component", value, f"applies to the velocity "
                         f"mode only (field = 'velocity'), not to the {self.field}")

    @mode.validator
    def _check_mode(self, attribute, value):
        if isinstance(value, tuple):
            if value == (0, 0):
                check.reject("SinusoidalMode", "mode", list(value), "must be a wave vector "
                             "[k_x, k_y] of integers not both 0")
            return
        check.integer(1)(self, attribute, value)

    @property
    def wave(self) -> tuple:
        """(k_x, k_y): the periods along x and along y."""
        return self.mode if isinstance(self.mode, tuple) else (self.mode, 0)

    @amplitude.validator
    def _check_amplitude(self, attribute, value):
        if self.field in ("density", "temperature") and not abs(value) < 1.0:
            check.reject("SinusoidalMode", "amplitude", value,
                         f"must be in (-1, 1) for the {self.field}, which must stay positive")

    def profile(self, x, length: float = 1.0) -> dict:
        """rho, the velocity (its perturbed component) and T at the points x of an interval
        of length ``length``."""
        wave = self.amplitude * numpy.sin(2.0 * math.pi * self.wave[0] * numpy.asarray(x)
                                          / length)
        base = {"density": self.density, "velocity": self.velocity,
                "temperature": self.temperature}
        values = {k: numpy.full(numpy.shape(x), v) for k, v in base.items()}
        values[self.field] = (base[self.field] + wave if self.field == "velocity"
                              else base[self.field] * (1.0 + wave))
        return values

    def sample_cells(self, grid, edges):
        edges = numpy.asarray(edges, dtype=float)
        cells = len(edges) - 1
        along, across = self.wave
        if across or along < 1:
            check.reject("SinusoidalMode", "mode", list(self.mode), "must be one number k >= 1 "
                         "on an interval (a wave vector [k_x, k_y] needs a rectangle: "
                         "space.cells = [Cx, Cy])")
        if 2 * along > cells:
            check.reject("SinusoidalMode", "mode", self.mode,
                         f"must be <= cells / 2 = {cells / 2:g}: {cells} cells resolve at most "
                         f"{cells // 2} periods (2 cells a period); use more space.cells")
        x, weights = _gauss(edges)
        fields = self.profile(x, edges[-1] - edges[0])
        d = grid.dimension
        f = numpy.zeros((len(edges) - 1,) + tuple(grid.shape))
        if self.component > d:
            check.reject("SinusoidalMode", "component", self.component,
                         f"must be at most the grid's dimension d = {d}")
        for q, w in enumerate(weights):
            for cell in range(f.shape[0]):
                u = numpy.zeros(d)
                if self.component == 1:
                    u[0] = fields["velocity"][cell, q]
                else:
                    u[0] = self.velocity
                    u[self.component - 1] = fields["velocity"][cell, q] - self.velocity
                f[cell] += w * grid.maxwellian(fields["density"][cell, q], tuple(u),
                                               fields["temperature"][cell, q])
        return f, (fields["density"] * weights).sum(axis=1)

    def sample_box(self, grid, edges):
        """The cell averages on a rectangle: a mode along x as on the interval in every
        row (:meth:`SpaceCondition.sample_box`); a wave vector with k_y != 0 by the tensor
        Gauss-Legendre rule, the velocity perturbed along :attr:`component`'s direction
        (the class notes)."""
        kx, ky = self.wave
        if ky == 0 and kx > 0:
            return super().sample_box(grid, edges)
        (ex, ey), d = (numpy.asarray(e, dtype=float) for e in edges), grid.dimension
        for k, e, axis in ((kx, ex, "x"), (ky, ey, "y")):
            if 2 * abs(k) > len(e) - 1:
                check.reject("SinusoidalMode", "mode", list(self.wave), f"must have |k_{axis}|"
                             f" <= cells along {axis} / 2 = {(len(e) - 1) / 2:g} (2 cells a "
                             f"period); use more space.cells")
        if self.component > d:
            check.reject("SinusoidalMode", "component", self.component,
                         f"must be at most the grid's dimension d = {d}")
        lx, ly = ex[-1] - ex[0], ey[-1] - ey[0]
        normal = numpy.array([kx / lx, ky / ly])
        normal /= numpy.hypot(*normal)
        direction = numpy.zeros(d)
        if self.component == 1:
            direction[:2] = normal
        elif self.component == 2:
            direction[:2] = (-normal[1], normal[0])
        else:
            direction[2] = 1.0
        f = numpy.zeros((len(ex) - 1, len(ey) - 1) + tuple(grid.shape))
        mass = numpy.zeros(f.shape[:2])
        for x, y, w in _box_points((ex, ey)):
            wave = self.amplitude * numpy.sin(2.0 * math.pi * (kx * x / lx + ky * y / ly))
            rho = numpy.broadcast_to(self.density * (1.0 + wave if self.field == "density"
                                                     else 1.0), mass.shape)
            t = numpy.broadcast_to(self.temperature * (1.0 + wave if self.field ==
                                                       "temperature" else 1.0), mass.shape)
            u = [numpy.full(mass.shape, self.velocity if i == 0 else 0.0) for i in range(d)]
            if self.field == "velocity":
                u = [c + wave * e for c, e in zip(u, direction)]
            f += w * _maxwellians(grid, rho, u, t)
            mass += w * rho
        return f, mass


def _fractions(value):
    """(a, b): two numbers in (0, 1), refused otherwise."""
    if (not isinstance(value, (list, tuple)) or len(value) != 2
            or not all(_finite(v) and 0.0 < float(v) < 1.0 for v in value)):
        check.reject("QuadrantProblem", "interface", value, "must be [a, b], two numbers in "
                     "(0, 1): the point where the quadrants meet, as fractions of L_x and L_y")
    return tuple(float(v) for v in value)


@attrs.frozen
class QuadrantProblem(SpaceCondition):
    r"""The two-dimensional Riemann problem: Maxwellians of four states in the quadrants
    about the point (a L_x, b L_y) of a rectangle, numbered as Lax & Liu number them
    (P. D. Lax & X.-D. Liu, SIAM J. Sci. Comput. 19 (1998) 319; R. Liska & B. Wendroff,
    SIAM J. Sci. Comput. 25 (2003) 995): 1 upper right (x > a, y > b), 2 upper left,
    3 lower left, 4 lower right. Each cell is the exact mixture by the share of its area
    in each quadrant.

    Parameters
    ----------
    upper_right, upper_left, lower_left, lower_right : dict
        ``{density, velocity, temperature}``; velocity u_1 (a number) or its first
        components (u_1, u_2), the others 0, or all d.
    interface : list of two float
        (a, b): the point where the quadrants meet, as fractions of L_x and L_y, in (0, 1).
    """

    upper_right: dict = attrs.field(converter=lambda v: _state(v, "QuadrantProblem",
                                                                "upper_right"))
    upper_left: dict = attrs.field(converter=lambda v: _state(v, "QuadrantProblem",
                                                               "upper_left"))
    lower_left: dict = attrs.field(converter=lambda v: _state(v, "QuadrantProblem",
                                                               "lower_left"))
    lower_right: dict = attrs.field(converter=lambda v: _state(v, "QuadrantProblem",
                                                                "lower_right"))
    interface: tuple = attrs.field(default=(0.5, 0.5), converter=_fractions)

    @property
    def states(self) -> dict:
        """The four states by quadrant name."""
        return {name: getattr(self, name) for name in
                ("upper_right", "upper_left", "lower_left", "lower_right")}

    def sample_cells(self, grid, edges):
        check.reject("QuadrantProblem", "space.cells", len(edges) - 1, "must be [Cx, Cy]: four "
                     "quadrants need a rectangle")

    def sample(self, grid):
        """The average of f0 over the rectangle (the mean of 8 x 8 equal cells)."""
        unit = numpy.linspace(0.0, 1.0, 9)
        return self.sample_box(grid, (unit, unit))[0].mean(axis=(0, 1))

    def sample_box(self, grid, edges):
        (ex, ey), owner = (numpy.asarray(e, dtype=float) for e in edges), "QuadrantProblem"
        shares = []
        for e, fraction in ((ex, self.interface[0]), (ey, self.interface[1])):
            point = e[0] + fraction * (e[-1] - e[0])
            below = numpy.clip((point - e[:-1]) / numpy.diff(e), 0.0, 1.0)
            shares.append((below, 1.0 - below))
        (left, right), (low, high) = shares
        weights = {"upper_right": right[:, None] * high[None, :],
                   "upper_left": left[:, None] * high[None, :],
                   "lower_left": left[:, None] * low[None, :],
                   "lower_right": right[:, None] * low[None, :]}
        f = numpy.zeros((len(ex) - 1, len(ey) - 1) + tuple(grid.shape))
        mass = numpy.zeros(f.shape[:2])
        tail = (1,) * grid.dimension
        for name, state in self.states.items():
            velocity = tuple(state["velocity"])
            if len(velocity) > grid.dimension:
                check.reject(owner, f"{name}.velocity", list(velocity), f"must have at most "
                             f"{grid.dimension} components on a {grid.dimension}D grid")
            velocity += (0.0,) * (grid.dimension - len(velocity))   # (u_1, u_2): u_3 = 0
            m = grid.maxwellian(state["density"], velocity, state["temperature"])
            f += weights[name].reshape(weights[name].shape + tail) * m
            mass += weights[name] * state["density"]
        return f, mass


def _parameters(value):
    """The keyword arguments of a :class:`SpaceFunction`: a table of names to values."""
    if value is None:
        return {}
    if not isinstance(value, dict) or not all(isinstance(k, str) and k.isidentifier()
                                              for k in value):
        check.reject("SpaceFunction", "params", value, "must be a table of keyword "
                     "arguments of the function (names to values)", error=TypeError)
    return dict(value)


@attrs.frozen
class SpaceFunction(SpaceCondition):
    """f0(x, v_1, ..., v_d, **params) from a function, averaged over each cell by
    Gauss-Legendre quadrature.

    Parameters
    ----------
    function : callable or str
        A callable or a ``module:function`` string, vectorised over arrays of x and v
        broadcast against each other.
    params : dict
        Keyword arguments passed to every call (numbers, strings, lists, tables): one
        function serves a family of initial data, each run naming its own values
        (``initial = {name = "space_function", function = "mymod:f0", params = {k = 3}}``).
        A name the function does not take is refused naming it.
    """

    function: object = attrs.field()
    params: dict = attrs.field(factory=dict, converter=_parameters)

    @function.validator
    def _check_function(self, attribute, value):
        if isinstance(value, str):
            resolve_callable("SpaceFunction", "function", value)
        elif not callable(value):
            check.reject("SpaceFunction", "function", value, "must be a callable or a "
                         "'module:function' string", error=TypeError)

    def _resolved(self):
        """The function, its keyword arguments bound (refused naming a name it does not
        take)."""
        function = (resolve_callable("SpaceFunction", "function", self.function)
                    if isinstance(self.function, str) else self.function)
        if not self.params:
            return function
        try:
            signature = inspect.signature(function)
        except (TypeError, ValueError):     # no signature to check: the call will tell
            signature = None
        if signature is not None and not any(p.kind is p.VAR_KEYWORD
                                             for p in signature.parameters.values()):
            for name in self.params:
                taken = signature.parameters.get(name)
                if taken is None or taken.kind is taken.POSITIONAL_ONLY:
                    check.reject("SpaceFunction", f"params.{name}", self.params[name],
                                 f"is not a keyword argument of the function {self.function!r}"
                                 f" (it takes {list(signature.parameters)})")
        return functools.partial(function, **self.params)

    def sample_cells(self, grid, edges):
        function = self._resolved()
        edges = numpy.asarray(edges, dtype=float)
        x, weights = _gauss(edges)
        mesh = grid.mesh()
        d = grid.dimension
        f = numpy.zeros((len(edges) - 1,) + tuple(grid.shape))
        for q, w in enumerate(weights):
            xq = x[:, q].reshape((-1,) + (1,) * d)
            f += w * self._values(function, xq, mesh, f.shape)
        return f, None

    def sample_box(self, grid, edges):
        """The cell averages on a rectangle of f0(x, y, v_1, ..., v_d): the function takes
        x and y before the velocity components, by the tensor Gauss-Legendre rule."""
        function = self._resolved()
        mesh, d = grid.mesh(), grid.dimension
        tail = (1,) * d
        f = numpy.zeros((len(edges[0]) - 1, len(edges[1]) - 1) + tuple(grid.shape))
        for x, y, w in _box_points([numpy.asarray(e, dtype=float) for e in edges]):
            f += w * self._values(function, (x.reshape(x.shape + tail),
                                             y.reshape(y.shape + tail)), mesh, f.shape)
        return f, None

    def _values(self, function, x, mesh, shape):
        """function(x, *mesh) as a real array of ``shape``; refused when the call fails, the
        result does not broadcast to ``shape``, or it is complex beyond round-off
        (:data:`~granframe.model.initial.IMAGINARY_TOLERANCE`), as for ``callable``."""
        space = x if isinstance(x, tuple) else (x,)
        try:
            raw = numpy.asarray(function(*space, *mesh))
            values = numpy.asarray(raw.real if raw.dtype.kind == "c" else raw, dtype=float)
            values = numpy.broadcast_to(values, shape)
        except check.USER_CODE_FAILURES as exc:  # the user's function, with what it was given
            names = ("x", "y")[:len(space)]
            check.reject("SpaceFunction", "function", self.function,
                         f"must map {' and '.join(names)} and the {len(mesh)} velocity "
                         f"components (broadcastable arrays, {', '.join(names)} of shape "
                         f"{', '.join(str(a.shape) for a in space)}) to f0 of shape {shape}"
                         + (f" with params {self.params}" if self.params else "")
                         + f"; calling it raised {check.raised(exc)}")
        check_real(raw, values, "SpaceFunction", self.function)
        return values


def cell_edges(space):
    """The cell edges 0 = x_0 < ... < x_n = ell of a :class:`~granframe.run.description.Space`;
    of a rectangle, a tuple of the edges along x and along y."""
    if space.dimension > 1:
        return tuple(numpy.linspace(0.0, ell, n + 1) for ell, n in zip(space.lengths,
                                                                         space.counts))
    return numpy.linspace(0.0, space.length, space.cells + 1)


def initial_cells(description):
    """f0 of a space run as cell averages (cells, *grid.shape), and the intended mass of each
    cell (None where unknown): a :class:`SpaceCondition`'s :meth:`~SpaceCondition.sample_cells`
    (on a rectangle :meth:`~SpaceCondition.sample_box`, its cells in C order, x slowest),
    or a space-homogeneous condition repeated in every cell, refused by
    :func:`check_cells` when its moments leave floating-point range."""
    grid, space = description.grid, description.space
    initial = description.build("initial")
    owner = f"initial condition {type(initial).__name__}"
    cells = math.prod(space.counts)
    try:
        if isinstance(initial, SpaceCondition) and space.dimension > 1:
            f, masses = initial.sample_box(grid, cell_edges(space))
            f = f.reshape((cells,) + f.shape[2:])
            masses = None if masses is None else numpy.ravel(masses)
        elif isinstance(initial, SpaceCondition):
            f, masses = initial.sample_cells(grid, cell_edges(space))
        else:
            cell = initial.sample(grid)
            f = numpy.broadcast_to(cell, (cells,) + cell.shape)
            masses = [initial.intended_mass] * cells
    except (OverflowError, ZeroDivisionError) as exc:
        check.reject(owner, "initial", description.initial.name, f"gives f0 beyond "
                     f"floating-point range on this grid ({exc}); bring its parameters "
                     "nearer to the grid's scales (support_radius, spacing h = "
                     f"{grid.spacing:.4g})")
    check_cells(grid, f, owner, description.initial.name)
    return f, [None] * len(f) if masses is None else list(masses)


def check_cells(grid, f, owner: str, name: str) -> None:
    """Refuse cell averages ``f`` (cells, *grid.shape) whose arithmetic would leave
    floating-point range: in every cell max |f0| must lie in :data:`PEAK_RANGE` and the
    mass, the second and fourth central moments and the kurtosis must be finite and > 0
    (a cell too narrow for the grid spacing has no second moment). Messages name the
    initial condition ``name`` and the first such cell. Data with non-finite or negative
    values is left to the run's checks of f0, which refuse it naming the cell
    (:func:`~granframe.model.initial.check_fits`)."""
    if not numpy.all(numpy.isfinite(f)) or numpy.min(f) < 0:
        return
    if f.strides[0] == 0:       # one cell repeated (a space-homogeneous condition)
        f = f[:1]
    mesh = [numpy.broadcast_to(c, grid.shape).ravel() for c in grid.mesh()]
    with numpy.errstate(all="ignore"):
        for start in range(0, len(f), 256):     # 256 cells at a time bound the temporaries
            block = numpy.asarray(f[start:start + 256]).reshape(-1, mesh[0].size)
            peak = block.max(axis=1)
            bad = ~((peak >= PEAK_RANGE[0]) & (peak <= PEAK_RANGE[1]))
            if bad.any():
                cell = start + int(numpy.argmax(bad))
                check.reject(owner, f"max |f0| in cell {cell}", float(peak[cell - start]),
                             f"must lie in [{PEAK_RANGE[0]:g}, {PEAK_RANGE[1]:g}] so that "
                             f"Q(f, f) and the moments stay finite: the data of initial "
                             f"condition '{name}' is too large, too small, or too narrow for "
                             f"the grid spacing h = {grid.spacing:.4g} to be seen on the nodes")
            mass = grid.cell_volume * block.sum(axis=1)
            mean = [block @ c / (mass / grid.cell_volume) for c in mesh]
            r2 = sum((c[None, :] - u[:, None]) ** 2 for c, u in zip(mesh, mean))
            m2 = grid.cell_volume * (block * r2).sum(axis=1)
            m4 = grid.cell_volume * (block * r2 * r2).sum(axis=1)
            kurtosis = mass * m4 / m2 ** 2
            good = ((mass > 0.0) & (m2 > 0.0) & numpy.isfinite(mass) & numpy.isfinite(m4)
                    & numpy.isfinite(kurtosis) & (kurtosis > 0.0))
            if not good.all():
                cell = start + int(numpy.argmin(good))
                check.reject(owner, f"moments of f0 in cell {cell}",
                             {"mass": float(mass[cell - start]), "m2": float(m2[cell - start]),
                              "m4": float(m4[cell - start])},
                             f"must be finite and > 0 (with a finite kurtosis): the data of "
                             f"initial condition '{name}' is too narrow for the grid spacing "
                             f"h = {grid.spacing:.4g}, or too large for float64")
