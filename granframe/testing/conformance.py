"""Conformance kit: the checks every implementation of a family must pass.

Each family has check functions, which raise :class:`AssertionError` with a message
saying what is wrong, and a pytest test class running them, which a plugin author
subclasses (the way ``zarr.testing.StoreTests`` is subclassed by a store)::

    from granframe.testing.conformance import RestitutionLawTests

    class TestExponentialDecay(RestitutionLawTests):
        factory = ExponentialDecay
        examples = [{"minimum": 0.4}, {"minimum": 0.0, "scale": 3.0}]

``factory`` builds the implementation from each parameter dict of ``examples`` (for
collision operators the dicts are the options after grid, kernel, restitution and
backend). The grids are small (2D N = 16, 3D N = 8; N = 32 in 2D where an exact rate is
compared), so that a family's suite runs in seconds. The kit needs pytest and Hypothesis
(the ``test`` extra).
"""

from __future__ import annotations

import itertools
import math

import hypothesis
import numpy

from granframe import contract_checks
from granframe.abc import (AdaptiveIntegrator, ArrayBackend, CollisionKernel,
                           CollisionOperator, Communicator, Equation, InitialCondition,
                           Pending, Quadrature, RestitutionLaw, SurfaceQuadrature,
                           TimeIntegrator)
from granframe.testing import strategies

#: Small grids of the operator and backend checks: (dimension, N, support radius) and the
#: temperature of a Maxwellian resolved on it.
SMALL_GRIDS = ((2, 16, 1.5, 0.5), (3, 8, 1.5, 1.0))


def _require(condition, message: str) -> None:
    if not condition:
        raise AssertionError(message)


def _contract(family: str, product) -> None:
    try:
        contract_checks.check_product(family, product)
    except contract_checks.ContractViolation as exc:
        raise AssertionError(f"{type(product).__name__}: {exc}") from None


# -- restitution laws ----------------------------------------------------------------------

def check_restitution_law(law) -> None:
    """Values finite, in [0, 1] and of the input's shape at zero, small and large speeds;
    element-wise (a vectorised call equals calls one speed at a time); ``is_constant``
    true to the values; negative speeds refused with a ValueError."""
    _require(isinstance(law, RestitutionLaw), f"{law!r} is not a granframe.RestitutionLaw")
    _contract("restitution_laws", law)
    speeds = contract_checks.SPEEDS
    together = numpy.asarray(law(speeds))
    alone = numpy.array([numpy.asarray(law(numpy.array([s])))[0] for s in speeds])
    _require(numpy.array_equal(together, alone),
             f"{type(law).__name__}: a vectorised call differs from calls one speed at a "
             f"time: {together!r} against {alone!r}")
    try:
        law(numpy.array([-1.0]))
    except ValueError:
        pass
    else:
        raise AssertionError(f"{type(law).__name__}: a negative speed was not refused")


# -- collision kernels ---------------------------------------------------------------------

def check_collision_kernel(kernel) -> None:
    """The contract's value checks, B = C s b phi, the isotropy and Maxwell flags, the
    angular integral, the speed-exponent bound, the maximum and the Maxwellian mean of
    the speed part."""
    _require(isinstance(kernel, CollisionKernel), f"{kernel!r} is not a granframe.CollisionKernel")
    _contract("collision_kernels", kernel)
    name = type(kernel).__name__
    speeds, cosines = contract_checks.SPEEDS, contract_checks.COSINES[::20]
    for d in (2, 3):
        full = kernel(speeds[:, None], cosines[None, :], 1.0, dimension=d)
        parts = (kernel.prefactor(d) * kernel.speed_part(speeds)[:, None]
                 * kernel.angular_part(cosines)[None, :])
        _require(numpy.allclose(full, parts, rtol=1e-14, atol=0.0),
                 f"{name}: B(|g|, cos theta) differs from C s(|g|) b(cos theta)")
        b_mean = kernel.angular_integral(d) / (2 * math.pi ** (d / 2) / math.gamma(d / 2))
        b = kernel.angular_part(contract_checks.COSINES)
        _require(b.min() * (1 - 1e-12) <= b_mean <= b.max() * (1 + 1e-12),
                 f"{name}: angular_integral({d}) / |S^{d - 1}| = {b_mean!r} is not a mean of b")
        mean = kernel.mean_speed_part(d, 0.7)
        reference = CollisionKernel.mean_speed_part(kernel, d, 0.7)
        _require(math.isclose(mean, reference, rel_tol=1e-6),
                 f"{name}: mean_speed_part({d}, 0.7) = {mean!r}, the Maxwellian mean of "
                 f"speed_part is {reference!r}")
    s = kernel.speed_part(speeds)
    _require(not kernel.is_maxwellian or numpy.ptp(s) == 0.0,
             f"{name}: is_maxwellian is True but speed_part is not constant")
    largest = kernel.largest_speed_part(10.0)
    _require(largest >= numpy.max(s[speeds <= 10.0]) * (1 - 1e-12),
             f"{name}: largest_speed_part(10) = {largest!r} is below speed_part at a "
             "speed <= 10")
    lam = kernel.speed_exponent
    large = numpy.logspace(0, 6, 61)
    ratio = kernel.speed_part(large) / large ** lam
    _require(ratio[-1] <= 1.01 * numpy.max(ratio[:31]),
             f"{name}: speed_part grows faster than |g|^speed_exponent = |g|^{lam:g} "
             f"(s(r)/r^lambda from {ratio[30]:.3g} at r = 1e3 to {ratio[-1]:.3g} at 1e6)")
    if kernel.energy_exponent == 0.0:
        _require(kernel.energy_factor(2.0) == 1.0,
                 f"{name}: energy_factor(E) must be 1 when energy_exponent is 0")


# -- quadratures ---------------------------------------------------------------------------

def _monomials(dimension: int, degree: int):
    for exponents in itertools.product(range(degree + 1), repeat=dimension):
        if sum(exponents) <= degree:
            yield exponents


def check_quadrature(rule) -> None:
    """The contract's value checks and the declared exactness: every polynomial of
    total degree <= ``degree`` integrated to round-off (monomials on [0, R] or on
    S^{d-1})."""
    from granframe.velocity.quadratures import monomial_sphere_integral

    _require(isinstance(rule, Quadrature), f"{rule!r} is not a granframe.Quadrature")
    _contract("quadratures", rule)
    name, degree = type(rule).__name__, rule.degree
    _require(isinstance(degree, int) and degree >= 0,
             f"{name}: degree must be an integer >= 0, got {degree!r}")
    if isinstance(rule, SurfaceQuadrature):
        nodes, weights = rule.nodes(), rule.weights()
        for exponents in _monomials(rule.dimension, degree):
            value = float(weights @ numpy.prod(nodes ** numpy.array(exponents), axis=1))
            exact = monomial_sphere_integral(exponents)
            _require(abs(value - exact) <= 1e-12 * 4 * math.pi,
                     f"{name}: declared degree {degree}, but the monomial with exponents "
                     f"{exponents} integrates to {value!r}, not {exact!r}")
        return
    radius = 1.5
    nodes, weights = rule.rule(radius)
    for k in range(degree + 1):
        value, exact = float(weights @ nodes ** k), radius ** (k + 1) / (k + 1)
        _require(abs(value - exact) <= 1e-12 * exact,
                 f"{name}: declared degree {degree}, but rho^{k} on [0, {radius}] integrates "
                 f"to {value!r}, not {exact!r}")


# -- initial conditions --------------------------------------------------------------------

def check_initial_condition(condition) -> None:
    """f0 on a 2D and a 3D grid: of the grid's shape, finite, >= 0, not zero, and of the
    ``intended_mass`` (when known) to 1 %."""
    from granframe.velocity.grid import VelocityGrid

    _require(isinstance(condition, InitialCondition),
             f"{condition!r} is not a granframe.InitialCondition")
    name = type(condition).__name__
    for d, n in ((2, 48), (3, 24)):
        grid = VelocityGrid(d, n, 4.0)
        f = numpy.asarray(condition.sample(grid))
        _require(f.shape == grid.shape, f"{name}: sample() has shape {f.shape}, the grid "
                                        f"{grid.shape}")
        _require(numpy.all(numpy.isfinite(f)) and f.min() >= 0.0 and f.max() > 0.0,
                 f"{name}: f0 must be finite, >= 0 and not zero on the {d}D grid")
        mass = condition.intended_mass
        if mass is not None:
            _require(math.isclose(grid.mass(f), mass, rel_tol=1e-2),
                     f"{name}: the {d}D grid mass {grid.mass(f)!r} differs from "
                     f"intended_mass {mass!r}")


# -- time integrators ----------------------------------------------------------------------

class LinearTestEquation(Equation):
    r"""df/dt = a f + cos(t) + c f, with N(t, f) = a f + cos(t) and L f = c f.

    The solution from f(0) = f0 is f(t) = (f0 - p(0)) e^{(a+c)t} + p(t), with
    p(t) = (-(a+c) cos t + sin t) / ((a+c)^2 + 1): it checks that a scheme evaluates
    N at the stage times and propagates L exactly or to its order.
    """

    def __init__(self, rate: float = -1.0, linear_rate: float = -0.5):
        self.rate, self.linear_rate = rate, linear_rate

    def nonlinear(self, t, f):
        return self.rate * f + math.cos(t)

    def linear(self, f):
        return self.linear_rate * f

    def propagate(self, f, dt):
        return math.exp(dt * self.linear_rate) * f

    def solution(self, t, f0):
        lam = self.rate + self.linear_rate

        def particular(s):
            return (-lam * math.cos(s) + math.sin(s)) / (lam * lam + 1.0)

        return (f0 - particular(0.0)) * math.exp(lam * t) + particular(t)


def _integrate(integrator, equation, f0, dt, final_time=1.0):
    f = f0.copy()
    steps = round(final_time / dt)
    for i in range(steps):
        f = integrator.step(equation, i * dt, f, dt)
    return f


def check_integrator_order(integrator) -> None:
    """The declared ``order`` p observed on :class:`LinearTestEquation` (global error at
    t = 1 falling by at least 2^(p - 0.3) as dt halves); ``step`` leaves its input alone;
    an adaptive scheme's error estimate is O(dt^(q+1)) with q its ``embedded_order``."""
    _require(isinstance(integrator, TimeIntegrator),
             f"{integrator!r} is not a granframe.TimeIntegrator")
    name, order = type(integrator).__name__, integrator.order
    equation = LinearTestEquation()
    f0 = numpy.array([1.0, -0.5, 2.0])
    copy = f0.copy()
    integrator.step(equation, 0.0, f0, 0.1)
    _require(numpy.array_equal(f0, copy), f"{name}: step() modified its input f")
    exact = equation.solution(1.0, f0)
    errors = [float(numpy.max(numpy.abs(_integrate(integrator, equation, f0, dt) - exact)))
              for dt in (0.1, 0.05)]
    observed = math.log2(errors[0] / errors[1]) if errors[1] > 0 else math.inf
    _require(observed >= order - 0.3,
             f"{name}: declared order {order}, observed {observed:.2f} on a linear test "
             f"equation (errors {errors[0]:.3g} at dt = 0.1, {errors[1]:.3g} at 0.05)")
    if isinstance(integrator, AdaptiveIntegrator):
        estimates = [float(numpy.max(numpy.abs(integrator.attempt(equation, 0.0, f0, dt)[1])))
                     for dt in (0.1, 0.05)]
        observed = math.log2(estimates[0] / estimates[1])
        q = integrator.embedded_order
        _require(observed >= q + 1 - 0.3,
                 f"{name}: embedded order {q}, but the error estimate falls as "
                 f"dt^{observed:.2f} (expected dt^{q + 1})")


# -- collision operators -------------------------------------------------------------------

def _default_arguments(dimension, n, support, kernel="maxwell", kernel_params=None,
                       law=("constant", {"value": 0.5})):
    from granframe.registry import default_registries
    from granframe.velocity.grid import VelocityGrid

    registries = default_registries()
    grid = VelocityGrid(dimension, n, support)
    return (grid, registries.create("collision_kernels", kernel, **(kernel_params or {})),
            registries.create("restitution_laws", law[0], **law[1]),
            registries.create("array_backends", "numpy"))


def _anisotropic(cos_theta):
    return 1.0 + 0.4 * cos_theta


#: Kernels and laws the operator checks run over: (kernel name, parameters, law).
OPERATOR_CASES = (
    ("maxwell", {}, ("constant", {"value": 0.5})),
    ("vhs", {"exponent": 0.5, "angular": _anisotropic, "energy_exponent": 0.5},
     ("tanh", {"asymptotic_value": 0.2, "centre": 1.0, "width": 0.5})),
)


def _build(factory, options, *arguments):
    operator = factory(*arguments, **options)
    _require(isinstance(operator, CollisionOperator),
             f"{factory!r} built {operator!r}, not a granframe.CollisionOperator")
    return operator


def _host(operator, f):
    backend = operator.backend
    return backend.to_numpy(operator(backend.asarray(f)))


def check_mass_of(operator, f) -> None:
    """Q(f) finite, of f's shape and of zero mass to round-off (1e-12 of int |Q|)."""
    grid = operator.grid
    q = _host(operator, f)
    _require(q.shape == grid.shape and numpy.all(numpy.isfinite(q)),
             f"Q(f) must be finite of shape {grid.shape}")
    share = abs(grid.mass(q)) / (numpy.sum(numpy.abs(q)) * grid.cell_volume)
    _require(share <= 1e-12, f"mass of Q(f) is {share:.3g} of int |Q| ({grid.dimension}D), "
                             "not round-off")


def check_operator_mass(factory, options) -> None:
    """Q(f) finite, of f's shape, and of zero mass to round-off, on small 2D and 3D grids,
    for Maxwell molecules and an anisotropic energy-dependent VHS kernel with a
    speed-dependent restitution law."""
    for (d, n, support, temperature), (kernel, params, law) in itertools.product(
            SMALL_GRIDS, OPERATOR_CASES):
        operator = _build(factory, options, *_default_arguments(d, n, support, kernel,
                                                                 params, law))
        grid = operator.grid
        check_mass_of(operator, grid.maxwellian(temperature=temperature)
                      + grid.maxwellian(0.5, [0.3] * d, 0.5 * temperature))


def check_operator_mass_on_generated(factory, options, max_examples: int = 5) -> None:
    """:func:`check_mass_of` on ``max_examples`` distributions drawn by
    :func:`granframe.testing.strategies.distributions` on the small 2D grid (the
    anisotropic energy-dependent kernel, a speed-dependent law); reproducible draws."""
    operator = _build(factory, options, *_default_arguments(2, 16, 1.5, *OPERATOR_CASES[1]))

    @hypothesis.settings(max_examples=max_examples, deadline=None, derandomize=True,
                         database=None)
    @hypothesis.given(strategies.distributions(operator.grid))
    def conserves_mass(f):
        check_mass_of(operator, f)

    conserves_mass()


def check_operator_energy_dissipation(factory, options) -> None:
    """int Q(f) |v|^2 dv equals the exact rate of Maxwell molecules with constant e
    (:func:`granframe.model.exact.maxwell_energy_dissipation`) to 5e-5 on a resolved 2D
    grid (N = 32, where the spectral operators reach 1e-5)."""
    from granframe.model.exact import maxwell_energy_dissipation

    for e in (0.0, 0.5):
        grid, kernel, law, backend = _default_arguments(2, 32, 3.0, law=("constant", {"value": e}))
        operator = _build(factory, options, grid, kernel, law, backend)
        f = grid.maxwellian(velocity=[0.1, -0.05], temperature=0.6)
        rate = float(numpy.sum(_host(operator, f) * grid.speed_squared())) * grid.cell_volume
        exact = maxwell_energy_dissipation(grid, f, e, kernel)
        _require(math.isclose(rate, exact, rel_tol=5e-5),
                 f"energy dissipation {rate!r}, exact {exact!r} (Maxwell molecules, e = {e})")


def check_operator_against_direct(factory, options) -> None:
    """Q(f) within 1e-3 (2D) and 2e-2 (3D) of max |Q| of the registered
    ``direct_spectral`` operator on the small grids."""
    from granframe.registry import default_registries

    direct = default_registries().get("collision_operators", "direct_spectral").factory
    for (d, n, support, temperature), tolerance in zip(SMALL_GRIDS, (1e-3, 2e-2)):
        for kernel, params, law in OPERATOR_CASES:
            arguments = _default_arguments(d, n, support, kernel, params, law)
            f = arguments[0].maxwellian(velocity=[0.1] * d, temperature=temperature)
            q = _host(_build(factory, options, *arguments), f)
            reference = _host(direct(*arguments), f)
            error = numpy.max(numpy.abs(q - reference)) / numpy.max(numpy.abs(reference))
            _require(error <= tolerance, f"Q(f) differs from direct_spectral by {error:.3g} "
                                         f"of max |Q| ({d}D, {kernel}; allowed {tolerance:g})")


def check_operator_batching(factory, options) -> None:
    """Q of a stack of 3 distributions (leading axis) equals 3 separate calls to 1e-12."""
    for d, n, support, temperature in SMALL_GRIDS:
        for kernel, params, law in OPERATOR_CASES:
            arguments = _default_arguments(d, n, support, kernel, params, law)
            grid = arguments[0]
            operator = _build(factory, options, *arguments)
            fs = numpy.stack([grid.maxwellian(1.0, [0.1 * i] * d, temperature * (1 + 0.2 * i))
                              for i in range(3)])
            separate = numpy.stack([_host(operator, f) for f in fs])
            try:
                together = _host(operator, fs)
            except Exception as exc:   # any failure of a batched call is the finding
                raise AssertionError(f"Q of a stack of {len(fs)} distributions of shape "
                                     f"{fs.shape} failed ({d}D, {kernel}): {exc!r}") from exc
            scale = numpy.max(numpy.abs(separate))
            error = numpy.max(numpy.abs(together - separate)) / scale
            _require(together.shape == fs.shape and error <= 1e-12,
                     f"Q of a stack of {len(fs)} differs from separate calls by {error:.3g} "
                     f"of max |Q| ({d}D, {kernel})")


class _OutOfRange(RestitutionLaw):
    """e = 1.5 at every speed (not a restitution coefficient)."""

    def _evaluate(self, speed):
        return numpy.full_like(speed, 1.5)


class _Scalar(RestitutionLaw):
    """A scalar e whatever the speeds' shape."""

    def _evaluate(self, speed):
        return 0.5


def check_operator_refuses_bad_restitution(factory, options) -> None:
    """An operator must refuse (ValueError or TypeError) a restitution law with values
    outside [0, 1] or not of the speeds' shape."""
    grid, kernel, _, backend = _default_arguments(2, 16, 1.5)
    for law in (_OutOfRange(), _Scalar()):
        try:
            factory(grid, kernel, law, backend, **options)
        except (ValueError, TypeError):
            continue
        raise AssertionError(f"the operator accepted the restitution law {law.__doc__}")


# -- array backends ------------------------------------------------------------------------

def check_backend_transforms(backend) -> None:
    """fftn/ifftn/rfftn/irfftn against :mod:`numpy.fft` to 1e-12, and :meth:`real_fft`
    (unnormalised, in float64 and float32) against numpy's rfftn and irfftn times the
    number of points."""
    _require(isinstance(backend, ArrayBackend), f"{backend!r} is not a granframe.ArrayBackend")
    name = type(backend).__name__
    rng = numpy.random.default_rng(0)
    for shape, axes in (((16, 16), (0, 1)), ((8, 8, 8), (0, 1, 2)), ((3, 8, 8), (1, 2))):
        x = rng.standard_normal(shape)
        z = x + 1j * rng.standard_normal(shape)
        spectrum = numpy.fft.rfftn(x, axes=axes)
        sizes = tuple(shape[a] for a in axes)
        pairs = {"fftn": (backend.fftn(backend.asarray(z), axes=axes), numpy.fft.fftn(z, axes=axes)),
                 "ifftn": (backend.ifftn(backend.asarray(z), axes=axes),
                           numpy.fft.ifftn(z, axes=axes)),
                 "rfftn": (backend.rfftn(backend.asarray(x), axes=axes), spectrum),
                 "irfftn": (backend.irfftn(backend.asarray(spectrum), s=sizes, axes=axes), x)}
        for what, (got, expected) in pairs.items():
            got = backend.to_numpy(got)
            _require(got.shape == expected.shape and numpy.allclose(got, expected, rtol=0,
                                                                    atol=1e-12 * abs(expected).max()),
                     f"{name}.{what} differs from numpy.fft.{what} over axes {axes} of {shape}")
        for precision, tolerance in (("float64", 1e-12), ("float32", 1e-5)):
            plan = backend.real_fft(shape, axes, precision=precision)
            plan.real[...] = backend.asarray(x)
            forward = backend.to_numpy(plan.forward())
            _require(numpy.allclose(forward, spectrum, rtol=0, atol=tolerance * abs(spectrum).max()),
                     f"{name}.real_fft({precision}).forward differs from numpy.fft.rfftn")
            plan.spectrum[...] = backend.asarray(spectrum)
            inverse = backend.to_numpy(plan.inverse())
            expected = x * numpy.prod(sizes)
            _require(inverse.shape == x.shape and numpy.allclose(
                inverse, expected, rtol=0, atol=tolerance * abs(expected).max()),
                f"{name}.real_fft({precision}).inverse differs from numpy.fft.irfftn times "
                f"the number of points (RealFFT.inverse is unnormalised)")
            _require(inverse.dtype == numpy.dtype(precision),
                     f"{name}.real_fft({precision}).inverse returned dtype {inverse.dtype}")


def check_backend_elementwise(backend) -> None:
    """``separable_product`` and ``lowrank_accumulate`` against :func:`numpy.einsum` to
    1e-12, with and without the leading axis of distributions."""
    name = type(backend).__name__
    rng = numpy.random.default_rng(1)

    def c(*shape):
        return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)

    xp, host = backend.asarray, backend.to_numpy
    batch, groups, rows, cols, rank = 6, 3, 8, 5, 2
    head, tail = c(batch, rows), c(batch, cols)
    heads, tails = c(batch, rows, rank), c(batch, rank, cols)
    for lead in ((), (2,)):
        spectrum = c(*lead, rows, cols)
        out = xp(numpy.zeros(lead + (batch, rows, cols), dtype=complex))
        got = host(backend.separable_product(out, xp(spectrum), xp(head), xp(tail)))
        expected = numpy.einsum("...ij,bi,bj->...bij", spectrum, head, tail)
        _require(numpy.allclose(got, expected, rtol=1e-12, atol=1e-12),
                 f"{name}.separable_product differs from einsum (leading shape {lead})")
        acc0, values = c(*lead, groups, rows, cols), c(*lead, batch, rows, cols)
        weights = numpy.einsum("bit,btj->bij", heads, tails) * values
        expected = acc0 + weights.reshape(lead + (groups, -1, rows, cols)).sum(axis=-3)
        got = host(backend.lowrank_accumulate(xp(acc0.copy()), xp(heads), xp(tails),
                                              xp(values.copy())))
        _require(numpy.allclose(got, expected, rtol=1e-12, atol=1e-12),
                 f"{name}.lowrank_accumulate differs from einsum (leading shape {lead})")


def check_backend_parity(backend, factory, options=None) -> None:
    """Q(f) of the operator ``factory`` on ``backend`` equals that on the NumPy backend
    to 1e-12 of max |Q| on the small grids."""
    name = type(backend).__name__
    for d, n, support, temperature in SMALL_GRIDS:
        for kernel, params, law in OPERATOR_CASES:
            grid, kernel_, law_, numpy_backend = _default_arguments(d, n, support, kernel,
                                                                    params, law)
            f = grid.maxwellian(velocity=[0.1] * d, temperature=temperature)
            reference = _host(_build(factory, options or {}, grid, kernel_, law_,
                                     numpy_backend), f)
            got = _host(_build(factory, options or {}, grid, kernel_, law_, backend), f)
            error = numpy.max(numpy.abs(got - reference)) / numpy.max(numpy.abs(reference))
            _require(error <= 1e-12, f"{name}: Q(f) differs from the NumPy backend's by "
                                     f"{error:.3g} of max |Q| ({d}D, {kernel})")


# -- reconstructions -----------------------------------------------------------------------

#: Cells of the order check: the L1 order is observed between these two resolutions.
ORDER_CELLS = (40, 80)


def _faces(reconstruction, f):
    """(minus, plus) of ``f`` as NumPy arrays, of shape (len(f) - 2 ghost + 1, ...) each."""
    name, g = type(reconstruction).__name__, reconstruction.ghost
    minus, plus = (numpy.asarray(a) for a in reconstruction.faces(f, numpy))
    expected = (f.shape[0] - 2 * g + 1,) + f.shape[1:]
    _require(minus.shape == expected and plus.shape == expected,
             f"{name}: faces() of an input of shape {f.shape} (ghost = {g}) returned shapes "
             f"{minus.shape} and {plus.shape}, expected {expected} each")
    return minus, plus


def _sine_averages(cells: int, ghost: int):
    """Averages of sin(2 pi x + 0.4) over the cells of width 1/cells of [0, 1] with ``ghost``
    periodic ghost cells each side, and the exact values at the n + 1 faces."""
    edges = numpy.arange(-ghost, cells + ghost + 1) / cells
    phase = 2.0 * math.pi * edges + 0.4
    averages = (numpy.cos(phase[:-1]) - numpy.cos(phase[1:])) * cells / (2.0 * math.pi)
    return averages, numpy.sin(phase[ghost:cells + ghost + 1])


def _rough_data(rng, cells: int):
    """Positive data with a smooth part, a jump and an extremum, shape (cells, 3, 2)."""
    x = (numpy.arange(cells) + 0.5) / cells
    smooth = 1.0 + 0.5 * numpy.sin(2.0 * math.pi * x) + (x > 0.6)
    return smooth[:, None, None] * rng.uniform(0.5, 1.5, (1, 3, 2))


def check_reconstruction(reconstruction) -> None:
    """The class constants, the faces' shapes, constants, broadcasting over the trailing
    axes, the declared order, the symmetries and extreme data
    (:func:`check_reconstruction_basics`, :func:`check_reconstruction_order`,
    :func:`check_reconstruction_symmetries`, :func:`check_reconstruction_extremes`)."""
    check_reconstruction_basics(reconstruction)
    check_reconstruction_order(reconstruction)
    check_reconstruction_symmetries(reconstruction)
    check_reconstruction_extremes(reconstruction)


def check_reconstruction_basics(reconstruction) -> None:
    """``ghost`` an integer >= 0, ``order`` an integer >= 1, ``cfl`` in (0, 1], all class
    attributes; faces() of an input (n + 2 ghost, ...) of shape (n + 1, ...) each, for no,
    one and two trailing axes; constants 0, 0.7 and 3 reproduced to 4 ulp; a stack of
    columns (trailing axes, a non-contiguous view as the transport passes) reconstructed as
    each column alone, to 1e-14; the input left unchanged."""
    from granframe.abc import Reconstruction

    _require(isinstance(reconstruction, Reconstruction),
             f"{reconstruction!r} is not a granframe.abc.Reconstruction")
    _contract("reconstructions", reconstruction)
    kind, name = type(reconstruction), type(reconstruction).__name__
    for attribute in ("ghost", "order", "cfl"):
        _require(attribute in dir(kind) and not isinstance(getattr(kind, attribute), property),
                 f"{name}: '{attribute}' must be a class attribute (the core reads it before "
                 "building the cells)")
    g, order, cfl = kind.ghost, kind.order, kind.cfl
    _require(isinstance(g, int) and not isinstance(g, bool) and g >= 0,
             f"{name}: ghost must be an integer >= 0, got {g!r}")
    _require(isinstance(order, int) and not isinstance(order, bool) and order >= 1,
             f"{name}: order must be an integer >= 1, got {order!r}")
    _require(isinstance(cfl, (int, float)) and 0.0 < cfl <= 1.0,
             f"{name}: cfl must lie in (0, 1], got {cfl!r}")
    rng = numpy.random.default_rng(2)
    n = 12
    for value in (0.0, 0.7, 3.0):
        for trailing in ((), (3,), (3, 2)):
            f = numpy.full((n + 2 * g,) + trailing, value)
            for side, faces in zip(("minus", "plus"), _faces(reconstruction, f)):
                error = float(numpy.max(numpy.abs(faces - value)))
                _require(error <= 4 * numpy.finfo(float).eps * value,
                         f"{name}: the constant {value} is reconstructed as {side} values "
                         f"off by up to {error:.3g}")
    f = numpy.ascontiguousarray(numpy.swapaxes(_rough_data(rng, n + 2 * g), 0, 1))
    copy = f.copy()
    stacked = _faces(reconstruction, numpy.swapaxes(f, 0, 1))   # a view, as the transport's
    _require(numpy.array_equal(f, copy), f"{name}: faces() modified its input")
    scale = numpy.max(numpy.abs(f))
    for i, k in itertools.product(range(3), range(2)):
        column = _faces(reconstruction, numpy.ascontiguousarray(f[i, :, k]))
        for side, whole, alone in zip(("minus", "plus"), stacked, column):
            error = float(numpy.max(numpy.abs(whole[:, i, k] - alone))) / scale
            _require(error <= 1e-14,
                     f"{name}: the {side} values of column ({i}, {k}) of a stack of shape "
                     f"{f.shape[1:2] + f.shape[:1] + f.shape[2:]} differ from those of the "
                     f"column alone by {error:.3g} of max |f|: faces() must act element-wise "
                     "over the trailing axes")


def check_reconstruction_order(reconstruction) -> None:
    """Consistency at the declared ``order`` p: on the cell averages of sin(2 pi x + 0.4),
    periodic, with n = 40 and 80 cells, the L1 error of the face values (both sides) against
    the point values at the faces falls by at least 2^(p - 0.3) (L1, so that limited schemes,
    which clip at extrema, are measured at their order)."""
    name, g, order = type(reconstruction).__name__, reconstruction.ghost, reconstruction.order
    errors = []
    for cells in ORDER_CELLS:
        averages, exact = _sine_averages(cells, g)
        minus, plus = _faces(reconstruction, averages)
        errors.append(float(numpy.sum(numpy.abs(minus - exact) + numpy.abs(plus - exact)))
                      / (2 * (cells + 1)))
    observed = math.log2(errors[0] / errors[1]) if errors[1] > 0 else math.inf
    _require(observed >= order - 0.3,
             f"{name}: declared order {order}, observed {observed:.2f} on the face values of "
             f"a sine (L1 errors {errors[0]:.3g} with {ORDER_CELLS[0]} cells, {errors[1]:.3g} "
             f"with {ORDER_CELLS[1]})")


def check_reconstruction_symmetries(reconstruction) -> None:
    """On positive data with a jump and an extremum: scale invariance (faces of lambda f
    are lambda times those of f, to 1e-13 of lambda max|f|, for lambda = 1e-12 and 1e6:
    distribution values span many decades), translation (the data shifted by one cell
    give the faces shifted by one, to 1e-14 of max|f|) and the mirror symmetry (reversing
    the cells gives the plus values reversed as minus values and the other way round, to
    1e-13 of max|f|)."""
    name, g = type(reconstruction).__name__, reconstruction.ghost
    data = _rough_data(numpy.random.default_rng(3), 16 + 2 * g + 1)
    f = data[:-1]
    scale = float(numpy.max(numpy.abs(data)))
    minus, plus = _faces(reconstruction, f)
    for factor in (1e-12, 1e6):
        for side, scaled, faces in zip(("minus", "plus"), _faces(reconstruction, factor * f),
                                       (minus, plus)):
            error = float(numpy.max(numpy.abs(scaled - factor * faces))) / (factor * scale)
            _require(error <= 1e-13,
                     f"{name}: the {side} values of {factor:g} f differ from {factor:g} times "
                     f"those of f by {error:.3g} of max|{factor:g} f|: a reconstruction must "
                     "be invariant under f -> lambda f (no absolute thresholds)")
    for side, shifted, faces in zip(("minus", "plus"), _faces(reconstruction, data[1:]),
                                    (minus, plus)):
        error = float(numpy.max(numpy.abs(shifted[:-1] - faces[1:]))) / scale
        _require(error <= 1e-14,
                 f"{name}: the data shifted by one cell give {side} values that differ from "
                 f"the shifted ones by {error:.3g} of max |f|")
    mirrored = _faces(reconstruction, f[::-1])
    for side, other, faces, original in (("minus", "plus", mirrored[0], plus),
                                         ("plus", "minus", mirrored[1], minus)):
        error = float(numpy.max(numpy.abs(faces - original[::-1]))) / scale
        _require(error <= 1e-13,
                 f"{name}: on the reversed cells the {side} values are not the {other} values "
                 f"reversed (off by {error:.3g} of max |f|): the scheme must treat both "
                 "directions alike")


def check_reconstruction_extremes(reconstruction) -> None:
    """Finite face values for data spanning 1e-300 .. 1 (a Gaussian tail, a jump from 1 to
    1e-300, zeros, the smallest subnormal)."""
    name, g = type(reconstruction).__name__, reconstruction.ghost
    cells = 40 + 2 * g
    tail = 10.0 ** -numpy.linspace(0.0, 300.0, cells)
    jump = numpy.where(numpy.arange(cells) < cells // 2, 1.0, 1e-300)
    sparse = tail * (numpy.arange(cells) % 3 == 0)
    sparse[1] = 5e-324
    f = numpy.stack([tail, tail[::-1], jump, sparse], axis=1)
    for side, faces in zip(("minus", "plus"), _faces(reconstruction, f)):
        bad = ~numpy.isfinite(faces)
        _require(not numpy.any(bad),
                 f"{name}: {side} values are not finite on data spanning 1e-300 .. 1 (columns "
                 f"{sorted(set(numpy.nonzero(bad)[1].tolist()))} of: a decaying tail, a "
                 "growing one, a jump from 1 to 1e-300, a sparse tail with zeros)")


# -- boundaries ----------------------------------------------------------------------------

#: Velocity grids of the boundary checks, (dimension, N, support radius): narrow and wide
#: boxes (a wall may refuse a box that its wall Maxwellian does not fit).
WALL_GRIDS = ((2, 16, 1.5), (2, 32, 5.0), (3, 8, 1.5), (3, 16, 5.0))
#: The walls a boundary is checked as: the left one (x = 0) and the right one (x = ell).
WALL_SIDES = ("left", "right")
#: The times at which a wall that declares no ``period`` is checked.
WALL_TIMES = (0.0, 0.37, 1.9, 11.3, 97.0)
#: The times per period at which a wall with a ``period`` is checked, k P / WALL_PHASES.
WALL_PHASES = 8


def _wall_grids(boundary):
    """The grids of :data:`WALL_GRIDS` that ``boundary.check`` accepts; a refusal must be a
    ValueError naming a parameter, and at least one grid must be accepted."""
    from granframe.velocity.grid import VelocityGrid

    name, accepted = type(boundary).__name__, []
    for d, n, support in WALL_GRIDS:
        grid = VelocityGrid(d, n, support)
        try:
            boundary.check(grid)
        except ValueError as exc:
            _require("parameter '" in str(exc),
                     f"{name}: check() refused the {d}D grid (N = {n}, L = "
                     f"{grid.half_width:g}) with a message naming no parameter: {exc}")
            continue
        except Exception as exc:   # any other error of check() is the finding
            raise AssertionError(f"{name}: check() on the {d}D grid (N = {n}, L = "
                                 f"{grid.half_width:g}) raised {exc!r}, not a ValueError "
                                 "naming a parameter") from exc
        accepted.append(grid)
    _require(accepted, f"{name}: check() refused every grid of the kit {WALL_GRIDS}")
    return accepted


def _wall_times(boundary):
    """k P / :data:`WALL_PHASES`, k = 0 .. WALL_PHASES - 1, for a wall with a period P;
    :data:`WALL_TIMES` for one without."""
    period = boundary.period
    if period is None:
        return WALL_TIMES
    return tuple(k * period / WALL_PHASES for k in range(WALL_PHASES))


def _instants(boundary):
    """Every (t, side) a wall is checked at: its times (:func:`_wall_times`) on both sides."""
    return [(t, side) for t in _wall_times(boundary) for side in WALL_SIDES]


def _at(t, side, grid) -> str:
    return f"({grid.dimension}D, t = {t:.6g}, {side} wall)"


def _incoming(grid, seed: int):
    """Random positive face values at the wall, shape grid.shape."""
    return numpy.random.default_rng(seed).uniform(0.1, 1.0, grid.shape)


def _emit(boundary, incoming, grid, t=0.0, side="left"):
    name = type(boundary).__name__
    out = numpy.asarray(boundary.emit(incoming, grid, numpy, t=t, side=side))
    _require(out.shape == grid.shape,
             f"{name}: emit() returned shape {out.shape}, the grid's is {grid.shape} "
             f"{_at(t, side, grid)}")
    _require(numpy.all(numpy.isfinite(out)),
             f"{name}: emit() returned non-finite values {_at(t, side, grid)}")
    return out


def check_boundary(boundary, linear: bool = True) -> None:
    """:func:`check_boundary_basics`, then for a wall :func:`check_wall_mass_flux`,
    :func:`check_wall_positivity`, :func:`check_wall_period` and, if ``linear``,
    :func:`check_wall_linearity`."""
    check_boundary_basics(boundary)
    if type(boundary).periodic:
        return
    check_wall_mass_flux(boundary)
    check_wall_positivity(boundary)
    check_wall_period(boundary)
    if linear:
        check_wall_linearity(boundary)


def check_boundary_basics(boundary) -> None:
    """``periodic`` a bool class attribute; ``period`` None or a finite float > 0;
    ``check(grid)`` passes or raises a ValueError naming a parameter on 2D and 3D grids
    (:data:`WALL_GRIDS`), and accepts one; for a wall on each accepted grid, on both sides
    and at its times (k P / 8 over its period P, or :data:`WALL_TIMES`): ``ghosts`` of
    g = 1, 2, 3 cells of shape (g, *grid.shape), finite; ``emit`` of the grid's shape,
    finite, leaving its input unchanged, its values at c^+ > 0 (what the wall sends) read
    only the arriving values (c^- < 0): changing the incoming values where c^- = 0 leaves
    them unchanged to 1e-14 (c^± the upwind speeds,
    :func:`granframe.space.transport.upwind_speeds`; the node -L is both)."""
    from granframe.abc import Boundary

    _require(isinstance(boundary, Boundary), f"{boundary!r} is not a granframe.abc.Boundary")
    _contract("boundaries", boundary)
    kind, name = type(boundary), type(boundary).__name__
    flag = getattr(kind, "periodic", None)
    _require(isinstance(flag, bool) and boundary.periodic is flag,
             f"{name}: 'periodic' must be a bool class attribute, got {flag!r}")
    period = boundary.period
    _require(period is None or (isinstance(period, float) and math.isfinite(period)
                                and period > 0.0),
             f"{name}: 'period' must be None or a finite float > 0, got {period!r}")
    grids = _wall_grids(boundary)
    if flag:
        return
    for grid in grids:
        positive, negative = _speeds(grid)
        for t, side in _instants(boundary):
            for g in (1, 2, 3):
                inside = numpy.random.default_rng(g).uniform(0.1, 1.0, (g,) + grid.shape)
                ghosts = numpy.asarray(boundary.ghosts(inside, grid, numpy, t=t, side=side))
                _require(ghosts.shape == inside.shape and numpy.all(numpy.isfinite(ghosts)),
                         f"{name}: ghosts() of {g} cells must be finite of shape "
                         f"{inside.shape}, got shape {ghosts.shape} {_at(t, side, grid)}")
            incoming = _incoming(grid, 4)
            copy = incoming.copy()
            out = _emit(boundary, incoming, grid, t, side)
            _require(numpy.array_equal(incoming, copy),
                     f"{name}: emit() modified its input {_at(t, side, grid)}")
            changed = numpy.where(negative == 0, _incoming(grid, 5), incoming)
            error = float(numpy.max(numpy.abs(_emit(boundary, changed, grid, t, side)
                                              - out)[positive > 0]))
            _require(error <= 1e-14 * numpy.max(numpy.abs(out)),
                     f"{name}: the emission (c^+ > 0) changed by {error:.3g} when only the "
                     f"incoming values at c^- = 0 changed {_at(t, side, grid)}: a wall sends "
                     "back what arrives (c^- < 0)")


def _speeds(grid):
    """The upwind speeds (c^+, c^-) broadcast to the grid's shape."""
    from granframe.space.transport import upwind_speeds

    return tuple(numpy.broadcast_to(c, grid.shape) for c in upwind_speeds(grid))


def _wall_flux(boundary, incoming, grid, t=0.0, side="left"):
    """F = c^+ out + c^- in at the wall at time t on ``side``, and c^-."""
    positive, negative = _speeds(grid)
    out = _emit(boundary, incoming, grid, t, side)
    return positive * out + negative * incoming, negative


def check_wall_mass_flux(boundary) -> None:
    """Zero net mass flux through the wall: sum_v F dv, F = c^+ out + c^- in with c^± the
    upwind speeds (:func:`granframe.space.transport.upwind_speeds`), is below 1e-13
    of the arriving flux sum_v |c^-| in dv, for three random positive ``in`` and a
    Maxwellian drifting into the wall, on every grid the wall accepts, on both sides and
    at the wall's times (k P / 8 over its period P, or :data:`WALL_TIMES`)."""
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        drifting = grid.maxwellian(1.0, [-0.5] + [0.2] * (grid.dimension - 1), 0.3)
        for incoming in (_incoming(grid, 6), _incoming(grid, 7), _incoming(grid, 8), drifting):
            for t, side in _instants(boundary):
                flux, negative = _wall_flux(boundary, incoming, grid, t, side)
                arriving = float(numpy.sum(-negative * incoming))
                net = float(numpy.sum(flux))
                _require(abs(net) <= 1e-13 * arriving,
                         f"{name}: net mass flux through the wall {net * grid.cell_volume:.3g} "
                         f"at t = {t:.6g} on the {side}, {abs(net) / arriving:.3g} of the "
                         f"arriving flux ({grid.dimension}D): the wall must send back what "
                         "arrives")


def check_wall_positivity(boundary) -> None:
    """Non-negative incoming values (random, with zeros, and values down to 1e-300) give a
    non-negative emission (c^+ > 0) and non-negative ghost cells, on both sides and at the
    wall's times."""
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        rng = numpy.random.default_rng(9)
        c = _speeds(grid)[0]
        for incoming in (rng.uniform(0.0, 1.0, grid.shape) * (rng.uniform(size=grid.shape) > 0.5),
                         10.0 ** -rng.uniform(0.0, 300.0, grid.shape)):
            for t, side in _instants(boundary):
                out = _emit(boundary, incoming, grid, t, side)
                _require(out[c > 0].min() >= 0.0,
                         f"{name}: emission {out[c > 0].min():.3g} < 0 from non-negative "
                         f"incoming values {_at(t, side, grid)}")
                ghosts = numpy.asarray(boundary.ghosts(incoming[None], grid, numpy, t=t,
                                                       side=side))
                _require(ghosts.min() >= 0.0,
                         f"{name}: ghost value {ghosts.min():.3g} < 0 from non-negative cells "
                         f"{_at(t, side, grid)}")


def check_wall_period(boundary) -> None:
    """A wall that declares a period P acts periodically: its emission at t + P equals that
    at t to 1e-12 of the largest emission, at its times k P / 8 on both sides (a wall
    without a period passes)."""
    period = boundary.period
    if period is None:
        return
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        c = _speeds(grid)[0]
        incoming = _incoming(grid, 12)
        for t, side in _instants(boundary):
            now = _emit(boundary, incoming, grid, t, side)
            later = _emit(boundary, incoming, grid, t + period, side)
            error = float(numpy.max(numpy.abs(later - now)[c > 0]))
            _require(error <= 1e-12 * numpy.max(numpy.abs(now[c > 0])),
                     f"{name}: the emission at t + period (period = {period:.6g}) differs "
                     f"from that at t by {error:.3g} {_at(t, side, grid)}: 'period' must be "
                     "the period of what the wall does, or None")


def check_wall_linearity(boundary) -> None:
    """The emission (c^+ > 0) is linear in the incoming values: emit(a x + b y) = a emit(x)
    + b emit(y) to 1e-13 of the largest emission, a = 0.3, b = 2.5 (every wall whose
    accommodation does not depend on what arrives), on both sides and at the wall's
    times."""
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        c = _speeds(grid)[0]
        x, y = _incoming(grid, 10), _incoming(grid, 11)
        for t, side in _instants(boundary):
            combined = _emit(boundary, 0.3 * x + 2.5 * y, grid, t, side)
            expected = (0.3 * _emit(boundary, x, grid, t, side)
                        + 2.5 * _emit(boundary, y, grid, t, side))
            error = float(numpy.max(numpy.abs(combined - expected)[c > 0]))
            _require(error <= 1e-13 * numpy.max(numpy.abs(expected[c > 0])),
                     f"{name}: emit(0.3 x + 2.5 y) differs from 0.3 emit(x) + 2.5 emit(y) by "
                     f"{error:.3g} {_at(t, side, grid)}; a wall that is not linear sets "
                     "'linear = False' in its BoundaryTests")


# -- collision models (levels of a space run's hierarchy) ---------------------------------

def _model_cells(grid):
    """Four cells: two Maxwellians of different mass, velocity and temperature, and two
    positive non-equilibrium distributions (products of Gaussians of unequal temperatures
    along v_1 and the other axes, one of them shifted)."""
    mesh = [numpy.broadcast_to(m, grid.shape) for m in grid.mesh()]

    def gaussian(rho, shift, t1, t2):
        exponent = (mesh[0] - shift) ** 2 / (2 * t1) + sum(m * m for m in mesh[1:]) / (2 * t2)
        norm = (2 * math.pi) ** (grid.dimension / 2) * math.sqrt(t1 * t2 ** (grid.dimension - 1))
        return rho * numpy.exp(-exponent) / norm

    return numpy.stack([gaussian(1.0, 0.0, 1.0, 1.0), gaussian(0.3, 0.4, 0.7, 0.7),
                        gaussian(0.8, 0.0, 1.4, 0.7), gaussian(0.5, -0.3, 0.6, 1.1)])


def check_collision_model(factory, options) -> None:
    """A level of the hierarchy (:class:`~granframe.abc.CollisionModel`) on four cells of a 2D
    Maxwell-molecule gas (N = 24, the fast operator with the conservative correction, as a
    run with a hierarchy has it, penalised ARS(2,2,2), eps = 0.1, one
    step of 0.02): of f's shape and finite; every cell's mass and momentum (the grid's own,
    node -L at -L) kept to 1e-12; elastic, its energy kept to 1e-12; with e = 0.8, no cell
    gains energy and the Maxwellian cells lose what the cooling rate of a Maxwellian gives,
    rho d (T' - T) of :class:`~granframe.space.hierarchy.CoolingRate`, within 5%."""
    from granframe.equations.conservative import ConservativeCorrection
    from granframe.registry import default_registries
    from granframe.space.collisions import CellCollisions
    from granframe.space.hierarchy import CoolingRate, HierarchyContext

    registries = default_registries()
    for restitution in (1.0, 0.8):
        grid, kernel, law, backend = _default_arguments(
            2, 24, 6.0, law=("constant", {"value": restitution}))
        operator = ConservativeCorrection(registries.create(
            "collision_operators", "fast_spectral", grid=grid, kernel=kernel, restitution=law,
            backend=backend), "maxwellian")
        equation = CellCollisions(operator, 0.0, 0.1)
        integrator = registries.create("time_integrators", "penalised_ars222")
        model = factory(HierarchyContext(equation, integrator, 1.0), **options)
        name = f"{type(model).__name__} (e = {restitution:g})"
        _require(isinstance(model, contract_checks.CONTRACTS["collision_models"]),
                 f"{factory!r} built {model!r}, not a granframe.abc.CollisionModel")
        f = _model_cells(grid)
        out = numpy.asarray(backend.to_numpy(model.advance(backend.asarray(f.copy()), 0.0,
                                                           0.02)))
        _require(out.shape == f.shape and numpy.all(numpy.isfinite(out)),
                 f"{name}: advance must return finite values of shape {f.shape}")
        for before, after, cell in zip(f, out, range(len(f))):
            mass = grid.mass(before)
            _require(abs(grid.mass(after) / mass - 1) <= 1e-12,
                     f"{name}: cell {cell} mass changed by "
                     f"{grid.mass(after) / mass - 1:.3g}")
            scale = mass * math.sqrt(grid.temperature(before))
            moved = numpy.abs(grid.momentum(after) - grid.momentum(before)).max() / scale
            _require(moved <= 1e-12, f"{name}: cell {cell} momentum changed by {moved:.3g} "
                                     "of rho sqrt(T)")
            energy, later = grid.kinetic_energy(before), grid.kinetic_energy(after)
            if restitution == 1.0:
                _require(abs(later / energy - 1) <= 1e-12,
                         f"{name}: elastic, cell {cell} energy changed by "
                         f"{later / energy - 1:.3g}")
            else:
                _require(later <= energy * (1 + 1e-12),
                         f"{name}: cell {cell} gained energy ({later / energy - 1:.3g})")
        if restitution < 1.0:
            cooling = CoolingRate(kernel, law, grid)
            for cell in (0, 1):
                rho, t = grid.mass(f[cell]), grid.temperature(f[cell])
                energy0 = grid.kinetic_energy(f[cell])
                expected = 0.5 * grid.dimension * rho * (
                    cooling.cooled(rho, t, energy0, 0.02, 0.1, 0.0) - t)
                change = grid.kinetic_energy(out[cell]) - energy0
                _require(abs(change / expected - 1) <= 0.05,
                         f"{name}: Maxwellian cell {cell} lost {-change:.4g} of energy, the "
                         f"cooling rate gives {-expected:.4g}")


# -- communicators --------------------------------------------------------------------------

def check_communicator(communicator) -> None:
    """The contract of :class:`granframe.abc.Communicator`, in one process or several
    (collective: every process of the communicator calls it, at once):

    - ``rank``, ``size`` and ``local_rank`` whole numbers, 0 <= rank, local_rank < size;
    - ``allgather`` of a float64 vector: shape (size, n), row r process r's vector;
      ``allgather_object``: a list of size values in rank order; ``bcast``: process 0's
      value (and that of the last process, as ``root``) in every process;
    - ``start``: a ring of messages as a halo posts them (contiguous views of one block
      array): each process sends two messages, tags 0 and 1, to the next process and
      receives two from the previous one, posted in the other order, into views of its
      own array; it returns a :class:`~granframe.abc.Pending` at once, and after
      ``wait`` each receive holds the message of its tag, unchanged by later writes to
      the sent arrays; nothing else of the array is written. With one process the ring is
      the process itself.
    """
    name = type(communicator).__name__
    _require(isinstance(communicator, Communicator),
             f"{communicator!r} is not a granframe.abc.Communicator")
    _contract("communicators", communicator)
    rank, size, local = communicator.rank, communicator.size, communicator.local_rank
    _require(all(isinstance(v, (int, numpy.integer)) and not isinstance(v, bool)
                 for v in (rank, size, local)),
             f"{name}: rank, size and local_rank must be whole numbers, got {rank!r}, "
             f"{size!r}, {local!r}")
    _require(size >= 1 and 0 <= rank < size and 0 <= local < size,
             f"{name}: rank = {rank} and local_rank = {local} must lie in [0, size = {size})")

    vector = numpy.array([rank, 0.5 * rank, -1.0, 1e300])
    gathered = numpy.asarray(communicator.allgather(vector))
    expected = numpy.array([[r, 0.5 * r, -1.0, 1e300] for r in range(size)])
    _require(gathered.shape == expected.shape and numpy.array_equal(gathered, expected),
             f"{name}: allgather of a vector of 4 floats must give each process's vector as "
             f"row rank of a ({size}, 4) array, got {gathered!r}")
    values = communicator.allgather_object({"rank": rank, "cells": (rank, rank + 1)})
    _require(list(values) == [{"rank": r, "cells": (r, r + 1)} for r in range(size)],
             f"{name}: allgather_object must give every process's value in rank order, "
             f"got {values!r}")
    for root in sorted({0, size - 1}):
        value = communicator.bcast({"from": rank, "data": [rank] * 3}, root=root)
        _require(value == {"from": root, "data": [root] * 3},
                 f"{name}: bcast(root={root}) must give process {root}'s value in every "
                 f"process, got {value!r} in process {rank}")

    after, before = (rank + 1) % size, (rank - 1) % size
    shape = (2, 9, 3, 4)                 # blocks, cells with ghosts, velocity nodes

    def sent(r):
        return 1000.0 * r + numpy.arange(numpy.prod(shape), dtype=float).reshape(shape)

    array = sent(rank)
    sends = [(after, 0, array[-1, 4:6]), (after, 1, array[0, 2:4])]
    into = numpy.full(shape, numpy.nan)
    receives = [(before, 1, into[0, 7:9]), (before, 0, into[-1, :2])]
    pending = communicator.start(sends, receives)
    _require(isinstance(pending, Pending),
             f"{name}: start must return a granframe.abc.Pending, got {pending!r}")
    pending.wait()
    array[...] = -1.0                    # the messages are complete: the buffers are free
    other = sent(before)
    _require(numpy.array_equal(into[-1, :2], other[-1, 4:6])
             and numpy.array_equal(into[0, 7:9], other[0, 2:4]),
             f"{name}: after wait each receive must hold the message of its tag from its "
             f"peer (matched by (peer, tag), not by the order of posting)")
    written = numpy.zeros(shape, dtype=bool)
    written[-1, :2] = written[0, 7:9] = True
    _require(bool(numpy.all(numpy.isnan(into[~written]))),
             f"{name}: start wrote outside the receive arrays")


# -- test classes to subclass --------------------------------------------------------------

class _FamilyTests:
    """Base of the test classes: ``factory`` and ``examples`` (a list of parameter dicts)."""

    factory = None
    examples: tuple = ({},)

    def _factory(self):
        factory = self.factory
        factory = getattr(factory, "__func__", factory)    # a function set as an attribute
        if factory is None:
            raise AssertionError(f"{type(self).__name__} must set 'factory'")
        return factory

    def implementations(self):
        """The implementation built from each example."""
        return [self._factory()(**params) for params in self.examples]


class RestitutionLawTests(_FamilyTests):
    """Conformance tests of a restitution law (:func:`check_restitution_law`)."""

    def test_restitution_law(self):
        for law in self.implementations():
            check_restitution_law(law)


class CollisionKernelTests(_FamilyTests):
    """Conformance tests of a collision kernel (:func:`check_collision_kernel`)."""

    def test_collision_kernel(self):
        for kernel in self.implementations():
            check_collision_kernel(kernel)


class QuadratureTests(_FamilyTests):
    """Conformance tests of a quadrature rule (:func:`check_quadrature`)."""

    def test_quadrature(self):
        for rule in self.implementations():
            check_quadrature(rule)


class InitialConditionTests(_FamilyTests):
    """Conformance tests of an initial condition (:func:`check_initial_condition`)."""

    def test_initial_condition(self):
        for condition in self.implementations():
            check_initial_condition(condition)


class TimeIntegratorTests(_FamilyTests):
    """Conformance tests of a time integrator (:func:`check_integrator_order`)."""

    def test_order(self):
        for integrator in self.implementations():
            check_integrator_order(integrator)


class CollisionOperatorTests(_FamilyTests):
    """Conformance tests of a collision operator; ``examples`` hold its options."""

    def test_mass(self):
        for options in self.examples:
            check_operator_mass(self._factory(), options)

    def test_mass_of_generated_distributions(self):
        for options in self.examples:
            check_operator_mass_on_generated(self._factory(), options)

    def test_energy_dissipation(self):
        for options in self.examples:
            check_operator_energy_dissipation(self._factory(), options)

    def test_against_direct(self):
        for options in self.examples:
            check_operator_against_direct(self._factory(), options)

    def test_batching(self):
        for options in self.examples:
            check_operator_batching(self._factory(), options)

    def test_refuses_bad_restitution(self):
        for options in self.examples:
            check_operator_refuses_bad_restitution(self._factory(), options)


class ArrayBackendTests(_FamilyTests):
    """Conformance tests of an array backend; ``operators`` lists the operator factories
    whose results must match the NumPy backend's (by default the registered ones)."""

    operators = None

    def _operators(self):
        from granframe.registry import default_registries

        if self.operators is not None:
            return list(self.operators)
        return [e.factory for e in default_registries().entries("collision_operators")]

    def test_transforms(self):
        for backend in self.implementations():
            check_backend_transforms(backend)

    def test_elementwise(self):
        for backend in self.implementations():
            check_backend_elementwise(backend)

    def test_operator_parity(self):
        for backend in self.implementations():
            for factory in self._operators():
                check_backend_parity(backend, factory)


class ReconstructionTests(_FamilyTests):
    """Conformance tests of a reconstruction (:func:`check_reconstruction` in parts)."""

    def test_basics(self):
        for reconstruction in self.implementations():
            check_reconstruction_basics(reconstruction)

    def test_order(self):
        for reconstruction in self.implementations():
            check_reconstruction_order(reconstruction)

    def test_symmetries(self):
        for reconstruction in self.implementations():
            check_reconstruction_symmetries(reconstruction)

    def test_extremes(self):
        for reconstruction in self.implementations():
            check_reconstruction_extremes(reconstruction)


class BoundaryTests(_FamilyTests):
    """Conformance tests of a boundary (:func:`check_boundary` in parts); a wall whose
    emission is not linear in what arrives sets ``linear = False``."""

    linear = True

    def test_basics(self):
        for boundary in self.implementations():
            check_boundary_basics(boundary)

    def test_mass_flux(self):
        for boundary in self.implementations():
            if not type(boundary).periodic:
                check_wall_mass_flux(boundary)

    def test_positivity(self):
        for boundary in self.implementations():
            if not type(boundary).periodic:
                check_wall_positivity(boundary)

    def test_period(self):
        for boundary in self.implementations():
            if not type(boundary).periodic:
                check_wall_period(boundary)

    def test_linearity(self):
        for boundary in self.implementations():
            if self.linear and not type(boundary).periodic:
                check_wall_linearity(boundary)
