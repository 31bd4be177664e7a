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
                           CollisionOperator, Equation, InitialCondition, Quadrature,
                           RestitutionLaw, SurfaceQuadrature, TimeIntegrator)
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
