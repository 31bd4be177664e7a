"""Quadrature rules for the fast spectral method (review, section 2.2).

The gain term is discretised by a product rule in g = rho ghat: a radial rule
for rho = |g| on [0, R] and a rule on the unit sphere S^{d-1} for ghat (a
circle for d = 2). Every rule states the polynomial degree it integrates
exactly (``degree``); the test suite checks it and checks it is sharp.

Rules on S^{d-1} return unit nodes of shape (M, d) and weights summing to
|S^{d-1}| (2 pi on the circle, 4 pi on the sphere).
"""

from __future__ import annotations

import functools
import math
from typing import ClassVar

import attrs
import numpy
import scipy.integrate
import scipy.special

from granframe import validators as check
from granframe.abc import Quadrature, SurfaceQuadrature
from granframe.rules import circle_rule, gauss_legendre, legendre
# defined in the core, whose contracts need them too; the rules' users import them here
from granframe.rules import antipodal_pairs, sphere_area  # noqa: F401

#: Largest Gauss-Legendre rule: numpy's ``leggauss`` solves a dense n x n eigenproblem
#: (4096: 128 MiB, a few seconds), and 4096 nodes resolve radial oscillations far beyond
#: any grid of 65536 modes' needs (the operators' defaults are 30-32 points, and 2N + 16).
MAX_GAUSS_POINTS = 4096

#: Largest rule on S^1 (and on S^2, 2 n_polar^2 points): 2048 directions integrate angular
#: degree 2047, more than the fast method resolves on any grid it fits in memory (the
#: review takes 16 in 2D and 32 in 3D; the default rules, M = N + 8 in 2D).
MAX_SURFACE_POINTS = 2048

#: Orders accepted by :func:`scipy.integrate.lebedev_rule` (= exact degree).
LEBEDEV_ORDERS = (3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31, 35, 41, 47, 53,
                  59, 65, 71, 77, 83, 89, 95, 101, 107, 113, 119, 125, 131)


@attrs.frozen
class GaussLegendre(Quadrature):
    """Gauss-Legendre rule for rho in [0, R]; exact for polynomials of degree 2n - 1.

    1 <= n <= :data:`MAX_GAUSS_POINTS`.
    """

    n_points: int = attrs.field(converter=check.to_int,
                                validator=check.integer(lower=1, upper=MAX_GAUSS_POINTS))
    kind: ClassVar[str] = "radial"

    @property
    def degree(self) -> int:
        return 2 * self.n_points - 1

    def rule(self, radius: float):
        """Nodes and weights on [0, radius]: rho_i = R (x_i + 1)/2, w_i = R w_i^GL / 2."""
        if not check.is_real(radius) or not (0.0 < float(radius) < math.inf):
            check.reject("GaussLegendre", "radius", radius, "must be a positive finite number")
        return gauss_legendre(self.n_points, radius)


@attrs.frozen
class CircleTrapezoid(SurfaceQuadrature):
    """Equispaced rule on S^1, ghat_j = (cos phi_j, sin phi_j), phi_j = phase + 2 pi j/M.

    All weights are 2 pi / M. It integrates trigonometric polynomials of degree
    <= M - 1 exactly, hence polynomials of total degree M - 1 (spectral
    accuracy for smooth periodic integrands; review section 2.2).
    1 <= M <= :data:`MAX_SURFACE_POINTS`.
    """

    n_points: int = attrs.field(converter=check.to_int,
                                validator=check.integer(lower=1, upper=MAX_SURFACE_POINTS))
    phase: float = attrs.field(default=0.0, converter=check.to_float, validator=check.real())
    kind: ClassVar[str] = "circle"
    dimension: ClassVar[int] = 2

    @property
    def degree(self) -> int:
        return self.n_points - 1

    def _rule(self):
        return circle_rule(self.n_points, self.phase)


@attrs.frozen
class Lebedev(SurfaceQuadrature):
    """Lebedev-Laikov rule on S^2 from :func:`scipy.integrate.lebedev_rule`.

    ``order`` is the exact degree; e.g. order 7 has 26 points, order 9 has 38.
    The rule is invariant under the octahedral group, hence antipodal.
    """

    order: int = attrs.field(converter=check.to_int, validator=check.integer(choices=LEBEDEV_ORDERS))
    kind: ClassVar[str] = "sphere"
    dimension: ClassVar[int] = 3

    @property
    def degree(self) -> int:
        return self.order

    @property
    def n_points(self) -> int:
        return self._rule()[0].shape[0]

    def _rule(self):
        return _lebedev(self.order)


@functools.lru_cache(maxsize=16)
def _lebedev(order: int):
    x, w = scipy.integrate.lebedev_rule(order)
    x = numpy.ascontiguousarray(x.T)
    for a in (x, w):
        a.setflags(write=False)
    return x, w


@attrs.frozen
class SphereProduct(SurfaceQuadrature):
    """Gauss product rule on S^2: Gauss-Legendre in cos(theta) times equispaced phi.

    With n Gauss-Legendre nodes z_i in [-1, 1] and 2n angles
    phi_j = pi j / n, the nodes are (sqrt(1-z_i^2) cos phi_j,
    sqrt(1-z_i^2) sin phi_j, z_i) with weights w_i^GL pi / n; M = 2 n^2 points,
    exact for degree 2n - 1 [Atkinson & Han, Spherical Harmonics, sec. 5.2].
    The rule is antipodal (z -> -z and phi -> phi + pi are symmetries).
    1 <= n <= 32, so that M <= :data:`MAX_SURFACE_POINTS`.
    """

    n_polar: int = attrs.field(  # 2 n^2 <= MAX_SURFACE_POINTS
        converter=check.to_int,
        validator=check.integer(lower=1, upper=math.isqrt(MAX_SURFACE_POINTS // 2)))
    kind: ClassVar[str] = "sphere"
    dimension: ClassVar[int] = 3

    @property
    def degree(self) -> int:
        return 2 * self.n_polar - 1

    @property
    def n_points(self) -> int:
        return 2 * self.n_polar ** 2

    def _rule(self):
        n = self.n_polar
        z, wz = legendre(n)
        phi = math.pi * numpy.arange(2 * n) / n
        s = numpy.sqrt(1.0 - z * z)
        nodes = numpy.stack([numpy.outer(s, numpy.cos(phi)), numpy.outer(s, numpy.sin(phi)),
                             numpy.outer(z, numpy.ones_like(phi))], axis=-1).reshape(-1, 3)
        return nodes, numpy.repeat(wz * math.pi / n, 2 * n)


def monomial_sphere_integral(exponents) -> float:
    """Exact int_{S^{d-1}} x_1^{a_1} ... x_d^{a_d} dsigma.

    Zero if any a_i is odd, else 2 prod Gamma((a_i+1)/2) / Gamma(sum (a_i+1)/2)
    [Folland, "How to integrate a polynomial over a sphere", 2001].
    """
    a = numpy.asarray(exponents)
    if numpy.any(a % 2):
        return 0.0
    b = (a + 1) / 2.0
    return float(2.0 * numpy.exp(numpy.sum(scipy.special.gammaln(b)) - scipy.special.gammaln(b.sum())))
