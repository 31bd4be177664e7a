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

    @property
    def intended_mass(self):
        return None


def _gauss(edges):
    """Gauss-Legendre points (cells, CELL_POINTS) of each cell and the weights (sum 1)."""
    nodes, weights = numpy.polynomial.legendre.leggauss(CELL_POINTS)
    left, right = numpy.asarray(edges[:-1]), numpy.asarray(edges[1:])
    x = 0.5 * (left + right)[:, None] + 0.5 * (right - left)[:, None] * nodes[None, :]
    return x, 0.5 * weights


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
    mode : int
        k >= 1, the number of periods on the interval.
    component : int
        The velocity component the ``velocity`` mode perturbs: 1 (along x, a longitudinal
        mode, the default) to d (2 or 3: transverse, a shear mode).
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
    mode: int = attrs.field(default=1, converter=check.to_int, validator=check.integer(1))
    component: int = attrs.field(default=1, converter=check.to_int,
                                 validator=check.integer(1, 3))

    @component.validator
    def _check_component(self, attribute, value):
        if value != 1 and self.field != "velocity":
            check.reject("SinusoidalMode", "component", value, f"applies to the velocity "
                         f"mode only (field = 'velocity'), not to the {self.field}")

    @amplitude.validator
    def _check_amplitude(self, attribute, value):
        if self.field in ("density", "temperature") and not abs(value) < 1.0:
            check.reject("SinusoidalMode", "amplitude", value,
                         f"must be in (-1, 1) for the {self.field}, which must stay positive")

    def profile(self, x, length: float = 1.0) -> dict:
        """rho, the velocity (its perturbed component) and T at the points x of an interval
        of length ``length``."""
        wave = self.amplitude * numpy.sin(2.0 * math.pi * self.mode * numpy.asarray(x) / length)
        base = {"density": self.density, "velocity": self.velocity,
                "temperature": self.temperature}
        values = {k: numpy.full(numpy.shape(x), v) for k, v in base.items()}
        values[self.field] = (base[self.field] + wave if self.field == "velocity"
                              else base[self.field] * (1.0 + wave))
        return values

    def sample_cells(self, grid, edges):
        edges = numpy.asarray(edges, dtype=float)
        cells = len(edges) - 1
        if 2 * self.mode > cells:
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

    def _values(self, function, x, mesh, shape):
        """function(x, *mesh) as a real array of ``shape``; refused when the call fails, the
        result does not broadcast to ``shape``, or it is complex beyond round-off
        (:data:`~granframe.model.initial.IMAGINARY_TOLERANCE`), as for ``callable``."""
        try:
            raw = numpy.asarray(function(x, *mesh))
            values = numpy.asarray(raw.real if raw.dtype.kind == "c" else raw, dtype=float)
            values = numpy.broadcast_to(values, shape)
        except check.USER_CODE_FAILURES as exc:  # the user's function, with what it was given
            check.reject("SpaceFunction", "function", self.function,
                         f"must map x and the {len(mesh)} velocity components (broadcastable "
                         f"arrays, x of shape {x.shape}) to f0 of shape {shape}"
                         + (f" with params {self.params}" if self.params else "")
                         + f"; calling it raised {check.raised(exc)}")
        check_real(raw, values, "SpaceFunction", self.function)
        return values


def cell_edges(space):
    """The cell edges 0 = x_0 < ... < x_n = ell of a :class:`~granframe.run.description.Space`."""
    return numpy.linspace(0.0, space.length, space.cells + 1)


def initial_cells(description):
    """f0 of a space run as cell averages (cells, *grid.shape), and the intended mass of each
    cell (None where unknown): a :class:`SpaceCondition`'s :meth:`~SpaceCondition.sample_cells`,
    or a space-homogeneous condition repeated in every cell, refused by
    :func:`check_cells` when its moments leave floating-point range."""
    grid, space = description.grid, description.space
    initial = description.build("initial")
    owner = f"initial condition {type(initial).__name__}"
    try:
        if isinstance(initial, SpaceCondition):
            f, masses = initial.sample_cells(grid, cell_edges(space))
        else:
            cell = initial.sample(grid)
            f = numpy.broadcast_to(cell, (space.cells,) + cell.shape)
            masses = [initial.intended_mass] * space.cells
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
