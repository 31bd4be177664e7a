"""Checks of what a registered factory builds against its family's contract.

The registry runs :func:`check_product` on every component it builds by name
(:meth:`granframe.registry.Entry.create`) and reports a failure as a
:class:`~granframe.errors.PluginError` naming the plugin and the implementation. Each
check is cheap (a few evaluations on fixed samples), so it runs on every build; the
conformance kit (:mod:`granframe.testing.conformance`) checks much more, once, in a
test suite.
"""

from __future__ import annotations

import numpy

from granframe import abc as contracts
from granframe.rules import sphere_area

#: Family name -> the contract class its factories' products are instances of.
CONTRACTS = {
    "collision_kernels": contracts.CollisionKernel,
    "restitution_laws": contracts.RestitutionLaw,
    "quadratures": contracts.Quadrature,
    "collision_operators": contracts.CollisionOperator,
    "time_integrators": contracts.TimeIntegrator,
    "initial_conditions": contracts.InitialCondition,
    "array_backends": contracts.ArrayBackend,
    "reconstructions": contracts.Reconstruction,
    "boundaries": contracts.Boundary,
    "communicators": contracts.Communicator,
    "collision_models": contracts.CollisionModel,
}

#: Relative speeds a restitution law and a kernel's speed part are sampled at: zero,
#: small, moderate and large.
SPEEDS = numpy.array([0.0, 1e-8, 1e-3, 0.1, 0.5, 1.0, 2.0, 10.0, 1e3, 1e6])

#: cos(theta) samples for a kernel's angular part.
COSINES = numpy.linspace(-1.0, 1.0, 201)


class ContractViolation(ValueError):
    """What a product does against its family's contract (the message says what)."""


def _fail(message: str):
    raise ContractViolation(message)


def _finite_array(values, shape, what: str) -> numpy.ndarray:
    values = numpy.asarray(values)
    if values.shape != shape:
        _fail(f"{what} must have the input's shape {shape}, got shape {values.shape}")
    if not numpy.all(numpy.isfinite(values)):
        _fail(f"{what} must be finite, got {values[~numpy.isfinite(values)][:3]!r}")
    return values


def check_restitution_law(law) -> None:
    """e at :data:`SPEEDS` (and a 2D array of them) finite, in [0, 1], of the input's shape."""
    for speeds in (SPEEDS, SPEEDS.reshape(2, -1)):
        values = _finite_array(law(speeds), speeds.shape, "e(r)")
        bad = (values < 0.0) | (values > 1.0)
        if numpy.any(bad):
            i = numpy.flatnonzero(bad.ravel())[0]
            _fail(f"e(r) must lie in [0, 1], got e({speeds.ravel()[i]:g}) = "
                  f"{float(values.ravel()[i])!r}")
    if law.is_constant and numpy.ptp(law(SPEEDS)) > 0.0:
        _fail("is_constant is True but e(r) depends on r")


def check_collision_kernel(kernel) -> None:
    """Positive finite prefactor and parts, and an isotropy flag that agrees with b."""
    for d in (2, 3):
        c = kernel.prefactor(d)
        if not (numpy.isfinite(c) and c > 0.0):
            _fail(f"prefactor({d}) must be positive and finite, got {c!r}")
    s = _finite_array(kernel.speed_part(SPEEDS), SPEEDS.shape, "speed_part(r)")
    if numpy.any(s[1:] <= 0.0) or s[0] < 0.0:
        _fail(f"speed_part(r) must be >= 0 at r = 0 and > 0 for r > 0, got {s!r}")
    lam = kernel.speed_exponent
    if not numpy.isfinite(lam):
        _fail(f"speed_exponent must be finite, got {lam!r}")
    b = _finite_array(kernel.angular_part(COSINES), COSINES.shape, "angular_part(cos theta)")
    if numpy.any(b <= 0.0):
        _fail(f"angular_part(cos theta) must be positive, found min {b.min():.3g}")
    if kernel.is_isotropic and numpy.ptp(b) > 1e-12 * numpy.max(b):
        _fail(f"is_isotropic is True but angular_part is not constant on [-1, 1] (from "
              f"{b.min():.6g} to {b.max():.6g})")


def check_quadrature(rule) -> None:
    """Finite nodes and weights, ``n_points`` of them; surface rules: unit nodes and
    weights summing to |S^{d-1}|; radial rules: nodes in [0, R], weights summing to R."""
    if rule.kind not in ("radial", "circle", "sphere"):
        _fail(f"kind must be 'radial', 'circle' or 'sphere', got {rule.kind!r}")
    m = rule.n_points
    if isinstance(rule, contracts.SurfaceQuadrature):
        d = rule.dimension
        nodes = _finite_array(rule.nodes(), (m, d), "nodes")
        weights = _finite_array(rule.weights(), (m,), "weights")
        norms = numpy.linalg.norm(nodes, axis=1)
        if numpy.max(numpy.abs(norms - 1.0)) > 1e-12:
            _fail(f"nodes must be unit vectors, found |node| = {norms[numpy.argmax(abs(norms - 1))]!r}")
        area = sphere_area(d)
        if abs(weights.sum() - area) > 1e-12 * area:
            _fail(f"weights must sum to |S^{d - 1}| = {area!r}, got {weights.sum()!r}")
        return
    radius = 2.0
    nodes, weights = rule.rule(radius)
    nodes = _finite_array(nodes, (m,), "nodes")
    weights = _finite_array(weights, (m,), "weights")
    if numpy.any((nodes < 0.0) | (nodes > radius)):
        _fail(f"nodes of rule({radius}) must lie in [0, {radius}]")
    if abs(weights.sum() - radius) > 1e-12 * radius:
        _fail(f"weights of rule({radius}) must sum to {radius}, got {weights.sum()!r}")


_CHECKS = {
    "collision_kernels": check_collision_kernel,
    "restitution_laws": check_restitution_law,
    "quadratures": check_quadrature,
}


def check_product(family: str, product) -> None:
    """Raise :class:`ContractViolation` when ``product`` breaks ``family``'s contract."""
    contract = CONTRACTS[family]
    if not isinstance(product, contract):
        _fail(f"must build a {contract.__module__}.{contract.__qualname__}, got "
              f"{type(product).__module__}.{type(product).__qualname__}")
    check = _CHECKS.get(family)
    if check is not None:
        check(product)
