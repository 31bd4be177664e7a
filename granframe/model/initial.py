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


def _covariance(value):
    """A nested list or array of real numbers as a tuple of tuples of floats (hashable, so
    the initial condition stays frozen); anything else passes to the validator."""
    try:
        array = numpy.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return value
    if array.ndim != 2 or isinstance(value, str):
        return value
    return tuple(tuple(float(x) for x in row) for row in array)


#: Largest asymmetry max |Sigma - Sigma^T| / max |Sigma| of a covariance accepted as
#: symmetric: the round-off of a matrix computed in float64, far below any data.
SYMMETRY_TOLERANCE = 1e-12


def _check_covariance(instance, attribute, value):
    owner = type(instance).__name__
    try:
        array = numpy.asarray(value, dtype=object)
    except ValueError:      # ragged rows
        array = numpy.empty(0, dtype=object)
    if (array.ndim != 2 or array.shape[0] != array.shape[1] or array.shape[0] not in (2, 3)
            or not all(check.is_real(x) and math.isfinite(float(x)) for x in array.flat)):
        check.reject(owner, attribute.name, value, "must be a 2 x 2 or 3 x 3 matrix (a list "
                     "of rows) of finite real numbers")
    matrix = array.astype(float)
    asymmetry = float(numpy.abs(matrix - matrix.T).max())
    if asymmetry > SYMMETRY_TOLERANCE * float(numpy.abs(matrix).max()):
        check.reject(owner, attribute.name, value,
                     f"must be symmetric (max |Sigma - Sigma^T| = {asymmetry:.3g})")
    smallest = float(numpy.linalg.eigvalsh(matrix).min())
    if not smallest > 0.0:
        check.reject(owner, attribute.name, value, "must be positive definite (a covariance); "
                     f"its smallest eigenvalue is {smallest:.6g}")
    if instance.velocity is not None and len(instance.velocity) != len(matrix):
        check.reject(owner, attribute.name, value, f"must be {len(instance.velocity)} x "
                     f"{len(instance.velocity)}, as the velocity has "
                     f"{len(instance.velocity)} components")


@attrs.frozen
class Gaussian(InitialCondition):
    """An anisotropic Gaussian of covariance Sigma (a component of :class:`GaussianMixture`):

        G(v) = rho (2 pi)^{-d/2} det(Sigma)^{-1/2} exp(-(v - u)^T Sigma^{-1} (v - u) / 2).

    Its pressure tensor is rho Sigma, its temperature tr(Sigma) / d and its heat flux 0;
    Sigma = T I is the Maxwellian of temperature T.

    Parameters
    ----------
    covariance : list of lists of float
        Sigma, a symmetric positive-definite d x d matrix (d = 2 or 3, the grid's
        dimension), given as a list of rows.
    density : float
        rho > 0.
    velocity : list of float, optional
        u (d components); 0 by default.
    """

    covariance: tuple = attrs.field(converter=_covariance)
    density: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=check.real(0.0, math.inf, lower_open=True))
    velocity: tuple | None = attrs.field(default=None, converter=_tuple_or_none,
                                         validator=_velocity)

    def __attrs_post_init__(self):     # after velocity, against which Sigma is checked
        _check_covariance(self, attrs.fields(Gaussian).covariance, self.covariance)

    def sample(self, grid):
        _check_dimension("Gaussian", self.velocity, grid)
        sigma = numpy.array(self.covariance)
        d = grid.dimension
        if sigma.shape != (d, d):
            check.reject("Gaussian", "covariance", [list(row) for row in self.covariance],
                         f"must be a {d} x {d} matrix (the grid's dimension is {d})")
        inverse = numpy.linalg.inv(sigma)
        u = self.velocity or (0.0,) * d
        c = [component - ui for component, ui in zip(grid.mesh(), u)]
        exponent = sum(inverse[i, j] * c[i] * c[j] for i in range(d) for j in range(d))
        norm = self.density / math.sqrt((2 * math.pi) ** d * numpy.linalg.det(sigma))
        return norm * numpy.exp(-0.5 * exponent)

    @property
    def intended_mass(self):
        return self.density


def _components(value):
    """Tables of a mixture as its components: a :class:`Gaussian` where the table gives a
    covariance, a :class:`Maxwellian` otherwise."""
    if not isinstance(value, (list, tuple)):
        return value
    components = []
    for index, c in enumerate(value):
        if isinstance(c, dict) and "covariance" in c:
            if "temperature" in c:
                check.reject("GaussianMixture", f"components[{index}].temperature",
                             c["temperature"], "must not be given together with a covariance: "
                             "a component has a temperature T (covariance T I) or a "
                             "covariance matrix, not both")
            c = check.from_table(Gaussian, c, "GaussianMixture")
        elif isinstance(c, dict):
            c = check.from_table(Maxwellian, c, "GaussianMixture")
        components.append(c)
    return tuple(components)


def _check_components(instance, attribute, value):
    if (not isinstance(value, tuple) or not value
            or not all(isinstance(c, (Maxwellian, Gaussian)) for c in value)):
        check.reject("GaussianMixture", "components", value,
                     "must be a non-empty list of Maxwellians (tables with density, "
                     "velocity, temperature) or Gaussians (tables with density, velocity, "
                     "covariance)", error=TypeError)


@attrs.frozen
class GaussianMixture(InitialCondition):
    """Sum of Gaussians, f0 = sum_k G_k: Maxwellians (density, velocity, temperature) or
    anisotropic Gaussians (density, velocity, covariance; :class:`Gaussian`)."""

    components: tuple = attrs.field(converter=_components, validator=_check_components)

    def sample(self, grid):
        return sum(c.sample(grid) for c in self.components)

    @property
    def intended_mass(self):
        return sum(c.density for c in self.components)

    def exact_moments(self, dimension: int) -> dict:
        """Mass, momentum, pressure tensor and heat flux of f0 in R^d, in closed form.

        With rho_k, u_k, Sigma_k the density, velocity and covariance of component k
        (Sigma_k = T_k I for a Maxwellian), rho = sum_k rho_k, u = sum_k rho_k u_k / rho
        and d_k = u_k - u, the Gaussian moments E[z] = 0, E[z z^T] = Sigma_k,
        E[z_i z_j z_l] = 0 give

            P = sum_k rho_k (Sigma_k + d_k d_k^T),
            q = (1/2) sum_k rho_k (d_k (|d_k|^2 + tr Sigma_k) + 2 Sigma_k d_k).

        Returns
        -------
        dict
            ``mass`` (float), ``momentum`` (length d), ``pressure_tensor`` (d x d) and
            ``heat_flux`` (length d), NumPy arrays.
        """
        if dimension not in (2, 3):
            check.reject("GaussianMixture.exact_moments", "dimension", dimension, "must be 2 or 3")
        rho, u, sigma = [], [], []
        for c in self.components:
            velocity = (0.0,) * dimension if c.velocity is None else c.velocity
            covariance = (numpy.array(c.covariance) if isinstance(c, Gaussian)
                          else c.temperature * numpy.eye(dimension))
            if len(velocity) != dimension or covariance.shape != (dimension, dimension):
                check.reject("GaussianMixture.exact_moments", "dimension", dimension,
                             f"must be the dimension of the component {c!r}")
            rho.append(c.density)
            u.append(numpy.array(velocity))
            sigma.append(covariance)
        mass = sum(rho)
        momentum = sum(r * v for r, v in zip(rho, u))
        mean = momentum / mass
        pressure, flux = numpy.zeros((dimension, dimension)), numpy.zeros(dimension)
        for r, v, s in zip(rho, u, sigma):
            shift = v - mean
            pressure += r * (s + numpy.outer(shift, shift))
            flux += 0.5 * r * (shift * (shift @ shift + numpy.trace(s)) + 2.0 * s @ shift)
        return {"mass": mass, "momentum": momentum, "pressure_tensor": pressure,
                "heat_flux": flux}


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
        except check.USER_CODE_FAILURES as exc:     # the module's own code, run by its import
            check.reject(owner, name, value, f"cannot be imported: importing "
                         f"'{module_name}' raised {check.raised(exc)}")
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


def check_real(raw, values, owner: str, function) -> None:
    """Refuse the result ``raw`` of a user's f0 ``function`` when it is complex with an
    imaginary part above :data:`IMAGINARY_TOLERANCE` times max |``values``| (its real
    part); a round-off imaginary part, e.g. from transforms, is real data."""
    if raw.dtype.kind != "c":
        return
    imaginary = float(numpy.abs(raw.imag).max(initial=0.0))
    scale = float(numpy.abs(values).max(initial=0.0))
    if not imaginary <= IMAGINARY_TOLERANCE * scale:
        check.reject(owner, "function", function,
                     f"must return real values; it returned complex values with "
                     f"max |imaginary part| = {imaginary:.3g} against max |real part| "
                     f"= {scale:.3g} (more than round-off: f0 is a real density)")


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
        except check.USER_CODE_FAILURES as exc:  # the user's function, with what it was given
            check.reject("FromCallable", "function", self.function,
                         f"must map the {grid.dimension} velocity components (broadcastable "
                         f"arrays) to f0; calling it raised {check.raised(exc)}")
        check_real(raw, values, "FromCallable", self.function)
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
                     kurtosis_tolerance: float, positivity_tolerance: float = 1.0) -> dict:
    """Refuse f0 that its Nyquist projection (:meth:`VelocityGrid.project`) changes.

    The operators evolve f0 without its modes |k_i| = N/2, so a run starts from
    ``projected``, not from ``f``. Refused: a relative change of the mass or the
    temperature above ``tolerance``, or of the kurtosis above ``kurtosis_tolerance``
    (:class:`granframe.run.description.Health`): the grid does not resolve f0, and the run
    would silently start from other data. Returns the moments before and after,
    name -> {"before", "after"}, which the run stores and reports
    (:func:`projection_note`). Refused too: a negative mass share
    sum max(-f, 0) / sum |f| of ``projected`` above ``positivity_tolerance`` (the run's
    health limit ``health.positivity_tolerance``, which would stop it at its first step).
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
    total = float(numpy.abs(projected).sum())
    negative = float(numpy.maximum(-projected, 0.0).sum()) / total if total > 0 else 0.0
    if negative > positivity_tolerance:
        check.reject(owner, "negative mass share of f0 after the Nyquist projection", negative,
                     f"must be <= health.positivity_tolerance = {positivity_tolerance:g}, "
                     f"which the run checks after every step: N = {grid.n_modes} modes (spacing "
                     f"h = {grid.spacing:.4g}) do not resolve f0, whose projection rings below "
                     "zero; use a larger grid.n_modes, or a smaller grid.support_radius if f0 "
                     "is negligible well inside the faces of the box (h = 2L/N falls with it)")
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
