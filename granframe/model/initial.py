"""Initial data f0(v) on the velocity grid, and the check that it fits the grid.

Each initial condition is a frozen attrs class registered in the family
``initial_conditions``; :meth:`InitialCondition.sample` returns f0 on the grid
as a NumPy array, and :attr:`InitialCondition.intended_mass` the mass it
should carry when that is known, so that data cut off by the box is caught.
"""

from __future__ import annotations

import functools
import importlib
import math
from typing import Callable

import attrs
import numpy
import scipy.special

from granframe import validators as check
from granframe.abc import InitialCondition
from granframe.model.exact import bkw


def _velocity(instance, attribute, value):
    if value is None:
        return
    array = numpy.asarray(value, dtype=object)
    if array.ndim != 1 or len(array) not in (2, 3) or not all(
            check.is_real(x) and math.isfinite(float(x)) for x in array):
        check.reject(type(instance).__name__, attribute.name, value,
                     "must be None or a list of 2 or 3 finite real numbers")


def _tuple_or_none(value):
    if value is None or not isinstance(value, (list, tuple, numpy.ndarray)):
        return value   # the validator reports anything else
    return tuple(float(x) if check.is_real(x) else x for x in value)


def _check_dimension(owner, velocity, grid):
    if velocity is not None and len(velocity) != grid.dimension:
        check.reject(owner, "velocity", list(velocity),
                     f"must have {grid.dimension} components (the grid's dimension)")


@attrs.frozen
class Maxwellian(InitialCondition):
    """M(v) = rho (2 pi T)^{-d/2} exp(-|v - u|^2 / (2T)) (the review's eq. (maxw_init))."""

    density: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=check.real(0.0, math.inf, lower_open=True))
    velocity: tuple | None = attrs.field(default=None, converter=_tuple_or_none,
                                         validator=_velocity)
    temperature: float = attrs.field(default=1.0, converter=check.to_float,
                                     validator=check.real(0.0, math.inf, lower_open=True))

    def sample(self, grid):
        _check_dimension("Maxwellian", self.velocity, grid)
        return grid.maxwellian(self.density, self.velocity, self.temperature)

    @property
    def intended_mass(self):
        return self.density


@attrs.frozen
class Box(InitialCondition):
    """Flat profile rho / (2 w0)^d on the cube u + [-w0, w0]^d (the review's eq. (flat_init)).

    Its temperature is w0^2 / 3; the review's Test 1(c) takes w0 = 2 sqrt 6, T0 = 8.
    Each grid value is the cell average (the fraction of the cell
    [v_j - h/2, v_j + h/2]^d inside the cube times the height), so the grid mass is
    rho exactly and the discontinuity does not depend on where the grid points fall.

    With ``edge_width`` sigma > 0 the cube is convolved with a Gaussian of standard
    deviation sigma in each direction, a smooth profile with the same mass and centre,

        f0(v) = rho / (2 w0)^d prod_i [erf((v_i - u_i + w0) / (sqrt 2 sigma))
                                       - erf((v_i - u_i - w0) / (sqrt 2 sigma))] / 2,

    and temperature w0^2 / 3 + sigma^2; it is sampled at the grid points. A
    discontinuous f0 limits every spectral method to low-order accuracy (Gibbs
    ringing; docs/reproduction.md, Test 1); sigma of one or two cells restores
    spectral accuracy.
    """

    half_width: float = attrs.field(converter=check.to_float,
                                    validator=check.real(0.0, math.inf, lower_open=True))
    density: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=check.real(0.0, math.inf, lower_open=True))
    velocity: tuple | None = attrs.field(default=None, converter=_tuple_or_none,
                                         validator=_velocity)
    edge_width: float = attrs.field(default=0.0, converter=check.to_float,
                                    validator=check.real(0.0, math.inf))

    def sample(self, grid):
        _check_dimension("Box", self.velocity, grid)
        u = self.velocity or (0.0,) * grid.dimension
        h, w, sigma = grid.spacing, self.half_width, self.edge_width
        points = grid.points()
        factors = []
        for ui in u:
            if sigma > 0:
                scale = math.sqrt(2) * sigma
                factors.append((scipy.special.erf((points - ui + w) / scale)
                                - scipy.special.erf((points - ui - w) / scale)) / 2)
                continue
            overlap = (numpy.minimum(points + h / 2, ui + w)
                       - numpy.maximum(points - h / 2, ui - w)).clip(min=0.0)
            factors.append(overlap / h)
        f = functools.reduce(numpy.multiply.outer, factors)
        return self.density / (2 * w) ** grid.dimension * f

    @property
    def intended_mass(self):
        return self.density


@attrs.frozen
class BKWProfile(InitialCondition):
    """The BKW solution of elastic Maxwell molecules at time ``time`` (mass 1, temperature 1)."""

    time: float = attrs.field(default=0.0, converter=check.to_float,
                              validator=check.real(0.0, math.inf))

    def sample(self, grid):
        return bkw(grid, self.time)[0]

    @property
    def intended_mass(self):
        return 1.0


def _components(value):
    if isinstance(value, (list, tuple)):
        return tuple(check.from_table(Maxwellian, c, "GaussianMixture") if isinstance(c, dict)
                     else c for c in value)
    return value


def _check_components(instance, attribute, value):
    if (not isinstance(value, tuple) or not value
            or not all(isinstance(c, Maxwellian) for c in value)):
        check.reject("GaussianMixture", "components", value,
                     "must be a non-empty list of Maxwellians (tables with density, "
                     "velocity, temperature)", error=TypeError)


@attrs.frozen
class GaussianMixture(InitialCondition):
    """Sum of Maxwellians, f0 = sum_i M_i (each given by density, velocity, temperature)."""

    components: tuple = attrs.field(converter=_components, validator=_check_components)

    def sample(self, grid):
        return sum(c.sample(grid) for c in self.components)

    @property
    def intended_mass(self):
        return sum(c.density for c in self.components)


def resolve_callable(owner: str, name: str, value) -> Callable:
    """A callable, or the callable named by a 'module:attribute' string."""
    if callable(value):
        return value
    if isinstance(value, str) and value.count(":") == 1:
        module_name, attribute = value.split(":")
        try:
            target = importlib.import_module(module_name)
            for part in attribute.split("."):
                target = getattr(target, part)
        except (ImportError, AttributeError) as exc:
            check.reject(owner, name, value, f"cannot be imported ({exc})")
        if callable(target):
            return target
    check.reject(owner, name, value, "must be a callable or a 'module:function' string",
                 error=TypeError)


def callable_reference(function) -> str | None:
    """'module:qualname' when that imports back to ``function``, else None (a lambda, a closure)."""
    module, qualname = getattr(function, "__module__", None), getattr(function, "__qualname__", "")
    if not module or "<" in qualname:
        return None
    try:
        return (f"{module}:{qualname}"
                if resolve_callable("", "", f"{module}:{qualname}") is function else None)
    except (ValueError, TypeError):
        return None


#: Largest imaginary part, relative to max |f0|, of a complex f0 accepted as real: round-off
#: of transforms or complex exponentials (about 4500 machine epsilons), far below any data.
IMAGINARY_TOLERANCE = 1e-12


def _function(instance, attribute, value):
    resolve_callable("FromCallable", attribute.name, value)


@attrs.frozen
class FromCallable(InitialCondition):
    """f0(v) = function(v_1, ..., v_d), any Python function vectorised over the grid's mesh.

    ``function`` is a callable or a 'module:function' string; only the string
    form (or a module-level function, stored as one) can be written to TOML and
    resumed from a store.
    """

    function: object = attrs.field(validator=_function)
    mass: float | None = attrs.field(
        default=None, converter=check.to_float,
        validator=check.optional_positive)

    def sample(self, grid):
        """f0 on the grid; refused when the function fails, or returns complex values
        whose imaginary part exceeds :data:`IMAGINARY_TOLERANCE` times max |f0| (a
        complex result with a round-off imaginary part, e.g. from transforms, is real data
        and keeps its real part)."""
        function = resolve_callable("FromCallable", "function", self.function)
        try:
            raw = numpy.asarray(function(*grid.mesh()))
            values = numpy.asarray(raw.real if raw.dtype.kind == "c" else raw, dtype=float)
        except Exception as exc:  # the user's function: report it with what it was given
            check.reject("FromCallable", "function", self.function,
                         f"must map the {grid.dimension} velocity components (broadcastable "
                         f"arrays) to f0; calling it raised {type(exc).__name__}: {exc}")
        if raw.dtype.kind == "c":
            imaginary = float(numpy.abs(raw.imag).max(initial=0.0))
            scale = float(numpy.abs(values).max(initial=0.0))
            if not imaginary <= IMAGINARY_TOLERANCE * scale:
                check.reject("FromCallable", "function", self.function,
                             f"must return real values; it returned complex values with "
                             f"max |imaginary part| = {imaginary:.3g} against max |real part| "
                             f"= {scale:.3g} (more than round-off: f0 is a real density)")
        try:
            return numpy.broadcast_to(values, grid.shape).copy()
        except ValueError:
            check.reject("FromCallable", "function", self.function,
                         f"must return an array broadcastable to the grid shape {grid.shape}; "
                         f"it returned shape {values.shape}")

    @property
    def intended_mass(self):
        return self.mass


def face_share(f) -> float:
    """max |f| on the faces of the box (the first and last point of each axis) / max |f|."""
    faces = max(float(numpy.abs(numpy.take(f, index, axis=axis)).max())
                for axis in range(f.ndim) for index in (0, -1))
    return faces / float(numpy.abs(f).max())


def check_fits(grid, f, condition: InitialCondition, edge_tolerance: float,
               mass_tolerance: float) -> None:
    """Refuse initial data that does not fit the grid.

    Refused: non-finite or negative values; zero mass; f on the faces of the
    box [-L, L]^d above ``edge_tolerance`` times max f (the data would wrap
    around the periodic box); and, when the intended mass is known, a grid
    mass h^d sum f off by more than ``mass_tolerance`` relative (mass outside
    the box, or data too narrow for the grid spacing).
    """
    owner = f"initial condition {type(condition).__name__}"
    if not numpy.all(numpy.isfinite(f)):
        check.reject(owner, "f0", "non-finite values", "must be finite everywhere on the grid")
    if f.min() < 0:
        check.reject(owner, "min f0", float(f.min()), "must be >= 0 (f0 is a density)")
    peak = float(f.max())
    if peak == 0.0:
        check.reject(owner, "max f0", 0.0, "must be > 0 (f0 carries no mass on the grid)")
    share = face_share(f)
    if share > edge_tolerance:
        check.reject(owner, "f0 on the faces of the box / max f0", share,
                     f"must be <= health.edge_tolerance = {edge_tolerance:g}: the data does not "
                     f"fit in [-L, L]^d with L = {grid.half_width:.6g}; enlarge the grid's "
                     "support_radius (or half_width)")
    intended = condition.intended_mass
    if intended is not None:
        error = abs(grid.mass(f) / intended - 1.0)
        if error > mass_tolerance:
            check.reject(owner, "relative mass error on the grid", error,
                         f"must be <= health.initial_mass_tolerance = {mass_tolerance:g} (grid "
                         f"mass {grid.mass(f):.10g}, intended {intended:.10g}): mass lies outside "
                         "the box, or the data is too narrow for the grid spacing "
                         f"h = {grid.spacing:.4g}")


def check_projection(grid, f, projected, condition: InitialCondition, tolerance: float,
                     kurtosis_tolerance: float) -> dict:
    """Refuse f0 that its Nyquist projection (:meth:`VelocityGrid.project`) changes.

    The operators evolve f0 without its modes |k_i| = N/2, so a run starts from
    ``projected``, not from ``f``. Refused: a relative change of the mass or the
    temperature above ``tolerance``, or of the kurtosis above ``kurtosis_tolerance``
    (:class:`granframe.run.description.Health`): the grid does not resolve f0, and the run
    would silently start from other data. Returns the moments before and after,
    name -> {"before", "after"}, which the run stores and reports
    (:func:`projection_note`).
    """
    owner = f"initial condition {type(condition).__name__}"
    moments = {}
    for name, moment, limit, field in (
            ("mass", grid.mass, tolerance, "projection_tolerance"),
            ("temperature", grid.temperature, tolerance, "projection_tolerance"),
            ("kurtosis", grid.kurtosis, kurtosis_tolerance, "projection_kurtosis_tolerance")):
        before, after = moment(f), moment(projected)
        moments[name] = {"before": before, "after": after}
        change = abs(after / before - 1.0)
        if not change <= limit:
            check.reject(owner, f"relative change of the {name} of f0 by the Nyquist projection",
                         change, f"must be <= health.{field} = {limit:g} ({name} {before:.6g} "
                         f"-> {after:.6g}): N = {grid.n_modes} modes do not resolve f0; use a "
                         f"larger n_modes (spacing h = {grid.spacing:.4g}), or a larger "
                         "support_radius if f0 is not negligible near the faces of the box, or "
                         f"raise health.{field} to accept it")
    return moments


#: relative change of a moment of f0 by the Nyquist projection that a run reports
NOTED_CHANGE = 1e-6


def projection_note(moments: dict) -> str | None:
    """A line on the moments of f0 that the projection changed by more than
    :data:`NOTED_CHANGE` (relative), or None."""
    changed = [f"{name} {m['before']:.6g} -> {m['after']:.6g} "
               f"({m['after'] / m['before'] - 1:+.2%})" for name, m in moments.items()
               if abs(m["after"] / m["before"] - 1) > NOTED_CHANGE]
    if not changed:
        return None
    return ("note: the run starts from f0 without its Nyquist modes (|k_i| = N/2, which the "
            "operators do not evolve), which changes " + ", ".join(changed)
            + "; a larger n_modes resolves f0 better")
