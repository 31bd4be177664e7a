"""The conformance checks of collision operators: mass conservation (also on generated
distributions), the exact energy dissipation of Maxwell molecules, agreement with the
direct operator, batching and the refusal of invalid restitution laws; and the small
grids, kernels and laws an operator is built on for them (the backend checks build on
them too).
"""

from __future__ import annotations

import itertools
import math

import hypothesis
import numpy

from granframe.abc import CollisionOperator, RestitutionLaw
from granframe.testing import strategies
from granframe.testing.conformance.common import require


#: Small grids of the operator and backend checks: (dimension, N, support radius) and the
#: temperature of a Maxwellian resolved on it.
SMALL_GRIDS = ((2, 16, 1.5, 0.5), (3, 8, 1.5, 1.0))


def default_arguments(dimension, n, support, kernel="maxwell", kernel_params=None,
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


def build_operator(factory, options, *arguments):
    operator = factory(*arguments, **options)
    require(isinstance(operator, CollisionOperator),
            f"{factory!r} built {operator!r}, not a granframe.CollisionOperator")
    return operator


def on_host(operator, f):
    backend = operator.backend
    return backend.to_numpy(operator(backend.asarray(f)))


def check_mass_of(operator, f) -> None:
    """Q(f) finite, of f's shape and of zero mass to round-off (1e-12 of int |Q|)."""
    grid = operator.grid
    q = on_host(operator, f)
    require(q.shape == grid.shape and numpy.all(numpy.isfinite(q)),
            f"Q(f) must be finite of shape {grid.shape}")
    share = abs(grid.mass(q)) / (numpy.sum(numpy.abs(q)) * grid.cell_volume)
    require(share <= 1e-12, f"mass of Q(f) is {share:.3g} of int |Q| ({grid.dimension}D), "
                            "not round-off")


def check_operator_mass(factory, options) -> None:
    """Q(f) finite, of f's shape, and of zero mass to round-off, on small 2D and 3D grids,
    for Maxwell molecules and an anisotropic energy-dependent VHS kernel with a
    speed-dependent restitution law."""
    for (d, n, support, temperature), (kernel, params, law) in itertools.product(
            SMALL_GRIDS, OPERATOR_CASES):
        operator = build_operator(factory, options, *default_arguments(d, n, support, kernel,
                                                                        params, law))
        grid = operator.grid
        check_mass_of(operator, grid.maxwellian(temperature=temperature)
                      + grid.maxwellian(0.5, [0.3] * d, 0.5 * temperature))


def check_operator_mass_on_generated(factory, options, max_examples: int = 5) -> None:
    """:func:`check_mass_of` on ``max_examples`` distributions drawn by
    :func:`granframe.testing.strategies.distributions` on the small 2D grid (the
    anisotropic energy-dependent kernel, a speed-dependent law); reproducible draws."""
    operator = build_operator(factory, options, *default_arguments(2, 16, 1.5, *OPERATOR_CASES[1]))

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
        grid, kernel, law, backend = default_arguments(2, 32, 3.0, law=("constant", {"value": e}))
        operator = build_operator(factory, options, grid, kernel, law, backend)
        f = grid.maxwellian(velocity=[0.1, -0.05], temperature=0.6)
        rate = float(numpy.sum(on_host(operator, f) * grid.speed_squared())) * grid.cell_volume
        exact = maxwell_energy_dissipation(grid, f, e, kernel)
        require(math.isclose(rate, exact, rel_tol=5e-5),
                f"energy dissipation {rate!r}, exact {exact!r} (Maxwell molecules, e = {e})")


def check_operator_against_direct(factory, options) -> None:
    """Q(f) within 1e-3 (2D) and 2e-2 (3D) of max |Q| of the registered
    ``direct_spectral`` operator on the small grids."""
    from granframe.registry import default_registries

    direct = default_registries().get("collision_operators", "direct_spectral").factory
    for (d, n, support, temperature), tolerance in zip(SMALL_GRIDS, (1e-3, 2e-2)):
        for kernel, params, law in OPERATOR_CASES:
            arguments = default_arguments(d, n, support, kernel, params, law)
            f = arguments[0].maxwellian(velocity=[0.1] * d, temperature=temperature)
            q = on_host(build_operator(factory, options, *arguments), f)
            reference = on_host(direct(*arguments), f)
            error = numpy.max(numpy.abs(q - reference)) / numpy.max(numpy.abs(reference))
            require(error <= tolerance, f"Q(f) differs from direct_spectral by {error:.3g} "
                                        f"of max |Q| ({d}D, {kernel}; allowed {tolerance:g})")


def check_operator_batching(factory, options) -> None:
    """Q of a stack of 3 distributions (leading axis) equals 3 separate calls to 1e-12."""
    for d, n, support, temperature in SMALL_GRIDS:
        for kernel, params, law in OPERATOR_CASES:
            arguments = default_arguments(d, n, support, kernel, params, law)
            grid = arguments[0]
            operator = build_operator(factory, options, *arguments)
            fs = numpy.stack([grid.maxwellian(1.0, [0.1 * i] * d, temperature * (1 + 0.2 * i))
                              for i in range(3)])
            separate = numpy.stack([on_host(operator, f) for f in fs])
            try:
                together = on_host(operator, fs)
            except Exception as exc:   # any failure of a batched call is the finding
                raise AssertionError(f"Q of a stack of {len(fs)} distributions of shape "
                                     f"{fs.shape} failed ({d}D, {kernel}): {exc!r}") from exc
            scale = numpy.max(numpy.abs(separate))
            error = numpy.max(numpy.abs(together - separate)) / scale
            require(together.shape == fs.shape and error <= 1e-12,
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
    grid, kernel, _, backend = default_arguments(2, 16, 1.5)
    for law in (_OutOfRange(), _Scalar()):
        try:
            factory(grid, kernel, law, backend, **options)
        except (ValueError, TypeError):
            continue
        raise AssertionError(f"the operator accepted the restitution law {law.__doc__}")
