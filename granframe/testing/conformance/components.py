"""The conformance checks of the physical model's components: restitution laws,
collision kernels, quadrature rules and initial conditions.
"""

from __future__ import annotations

import itertools
import math

import numpy

from granframe import contract_checks
from granframe.abc import (CollisionKernel, InitialCondition, Quadrature, RestitutionLaw,
                           SurfaceQuadrature)
from granframe.testing.conformance.common import require, require_contract


def check_restitution_law(law) -> None:
    """Values finite, in [0, 1] and of the input's shape at zero, small and large speeds;
    element-wise (a vectorised call equals calls one speed at a time); ``is_constant``
    true to the values; negative speeds refused with a ValueError."""
    require(isinstance(law, RestitutionLaw), f"{law!r} is not a granframe.RestitutionLaw")
    require_contract("restitution_laws", law)
    speeds = contract_checks.SPEEDS
    together = numpy.asarray(law(speeds))
    alone = numpy.array([numpy.asarray(law(numpy.array([s])))[0] for s in speeds])
    require(numpy.array_equal(together, alone),
            f"{type(law).__name__}: a vectorised call differs from calls one speed at a "
            f"time: {together!r} against {alone!r}")
    try:
        law(numpy.array([-1.0]))
    except ValueError:
        pass
    else:
        raise AssertionError(f"{type(law).__name__}: a negative speed was not refused")


def check_collision_kernel(kernel) -> None:
    """The contract's value checks, B = C s b phi, the isotropy and Maxwell flags, the
    angular integral, the speed-exponent bound, the maximum and the Maxwellian mean of
    the speed part."""
    require(isinstance(kernel, CollisionKernel), f"{kernel!r} is not a granframe.CollisionKernel")
    require_contract("collision_kernels", kernel)
    name = type(kernel).__name__
    speeds, cosines = contract_checks.SPEEDS, contract_checks.COSINES[::20]
    for d in (2, 3):
        full = kernel(speeds[:, None], cosines[None, :], 1.0, dimension=d)
        parts = (kernel.prefactor(d) * kernel.speed_part(speeds)[:, None]
                 * kernel.angular_part(cosines)[None, :])
        require(numpy.allclose(full, parts, rtol=1e-14, atol=0.0),
                f"{name}: B(|g|, cos theta) differs from C s(|g|) b(cos theta)")
        b_mean = kernel.angular_integral(d) / (2 * math.pi ** (d / 2) / math.gamma(d / 2))
        b = kernel.angular_part(contract_checks.COSINES)
        require(b.min() * (1 - 1e-12) <= b_mean <= b.max() * (1 + 1e-12),
                f"{name}: angular_integral({d}) / |S^{d - 1}| = {b_mean!r} is not a mean of b")
        mean = kernel.mean_speed_part(d, 0.7)
        reference = CollisionKernel.mean_speed_part(kernel, d, 0.7)
        require(math.isclose(mean, reference, rel_tol=1e-6),
                f"{name}: mean_speed_part({d}, 0.7) = {mean!r}, the Maxwellian mean of "
                f"speed_part is {reference!r}")
    s = kernel.speed_part(speeds)
    require(not kernel.is_maxwellian or numpy.ptp(s) == 0.0,
            f"{name}: is_maxwellian is True but speed_part is not constant")
    largest = kernel.largest_speed_part(10.0)
    require(largest >= numpy.max(s[speeds <= 10.0]) * (1 - 1e-12),
            f"{name}: largest_speed_part(10) = {largest!r} is below speed_part at a "
            "speed <= 10")
    lam = kernel.speed_exponent
    large = numpy.logspace(0, 6, 61)
    ratio = kernel.speed_part(large) / large ** lam
    require(ratio[-1] <= 1.01 * numpy.max(ratio[:31]),
            f"{name}: speed_part grows faster than |g|^speed_exponent = |g|^{lam:g} "
            f"(s(r)/r^lambda from {ratio[30]:.3g} at r = 1e3 to {ratio[-1]:.3g} at 1e6)")
    if kernel.energy_exponent == 0.0:
        require(kernel.energy_factor(2.0) == 1.0,
                f"{name}: energy_factor(E) must be 1 when energy_exponent is 0")


def _monomials(dimension: int, degree: int):
    for exponents in itertools.product(range(degree + 1), repeat=dimension):
        if sum(exponents) <= degree:
            yield exponents


def check_quadrature(rule) -> None:
    """The contract's value checks and the declared exactness: every polynomial of
    total degree <= ``degree`` integrated to round-off (monomials on [0, R] or on
    S^{d-1})."""
    from granframe.velocity.quadratures import monomial_sphere_integral

    require(isinstance(rule, Quadrature), f"{rule!r} is not a granframe.Quadrature")
    require_contract("quadratures", rule)
    name, degree = type(rule).__name__, rule.degree
    require(isinstance(degree, int) and degree >= 0,
            f"{name}: degree must be an integer >= 0, got {degree!r}")
    if isinstance(rule, SurfaceQuadrature):
        nodes, weights = rule.nodes(), rule.weights()
        for exponents in _monomials(rule.dimension, degree):
            value = float(weights @ numpy.prod(nodes ** numpy.array(exponents), axis=1))
            exact = monomial_sphere_integral(exponents)
            require(abs(value - exact) <= 1e-12 * 4 * math.pi,
                    f"{name}: declared degree {degree}, but the monomial with exponents "
                    f"{exponents} integrates to {value!r}, not {exact!r}")
        return
    radius = 1.5
    nodes, weights = rule.rule(radius)
    for k in range(degree + 1):
        value, exact = float(weights @ nodes ** k), radius ** (k + 1) / (k + 1)
        require(abs(value - exact) <= 1e-12 * exact,
                f"{name}: declared degree {degree}, but rho^{k} on [0, {radius}] integrates "
                f"to {value!r}, not {exact!r}")


def check_initial_condition(condition) -> None:
    """f0 on a 2D and a 3D grid: of the grid's shape, finite, >= 0, not zero, and of the
    ``intended_mass`` (when known) to 1 %."""
    from granframe.velocity.grid import VelocityGrid

    require(isinstance(condition, InitialCondition),
            f"{condition!r} is not a granframe.InitialCondition")
    name = type(condition).__name__
    for d, n in ((2, 48), (3, 24)):
        grid = VelocityGrid(d, n, 4.0)
        f = numpy.asarray(condition.sample(grid))
        require(f.shape == grid.shape, f"{name}: sample() has shape {f.shape}, the grid "
                                       f"{grid.shape}")
        require(numpy.all(numpy.isfinite(f)) and f.min() >= 0.0 and f.max() > 0.0,
                f"{name}: f0 must be finite, >= 0 and not zero on the {d}D grid")
        mass = condition.intended_mass
        if mass is not None:
            require(math.isclose(grid.mass(f), mass, rel_tol=1e-2),
                    f"{name}: the {d}D grid mass {grid.mass(f)!r} differs from "
                    f"intended_mass {mass!r}")
