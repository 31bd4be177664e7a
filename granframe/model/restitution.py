"""Restitution laws e(|g|) in [0, 1] (review, section 1, "Restitution coefficient").

Each law is a frozen attrs class, vectorised over a NumPy array of relative
speeds r = |v - v_*| >= 0, and reports whether it is constant (the fast
spectral method then needs e at one value only).
"""

from __future__ import annotations

import math

import attrs
import numpy

from granframe import validators as check
from granframe.abc import RestitutionLaw


@attrs.frozen
class Constant(RestitutionLaw):
    """Constant restitution coefficient, e(r) = e; e = 1 is elastic, e = 0 sticky."""

    value: float = attrs.field(converter=check.to_float, validator=check.real(0.0, 1.0))
    is_constant = True

    def _evaluate(self, speed):
        return numpy.full_like(speed, self.value)


@attrs.frozen
class Toscani(RestitutionLaw):
    """Toscani's law e(r) = 1 / (1 + c r^gamma) [Toscani 2000], c >= 0, gamma real.

    For gamma > 0, e -> 1 as r -> 0; gamma = 0 or c = 0 give a constant law.
    """

    strength: float = attrs.field(converter=check.to_float, validator=check.real(0.0))
    exponent: float = attrs.field(converter=check.to_float, validator=check.real())

    @property
    def is_constant(self) -> bool:
        return self.strength == 0.0 or self.exponent == 0.0

    def _evaluate(self, speed):
        if self.strength == 0.0:  # elastic; avoids 0 * inf at r = 0 when gamma < 0
            return numpy.ones_like(speed)
        return 1.0 / (1.0 + self.strength * speed ** self.exponent)


@attrs.frozen
class Viscoelastic(RestitutionLaw):
    """Viscoelastic hard spheres: e solves e + a r^{1/5} e^{3/5} = 1, a > 0.

    Notes
    -----
    With x = e^{1/5} and c = a r^{1/5} the relation is h(x) = x^5 + c x^3 - 1
    = 0, h increasing and convex on (0, inf). Newton's method started at
    x_0 = min(1, c^{-1/3}) >= root converges monotonically; it is iterated
    until x stops decreasing, i.e. to machine precision. [Brilliantov &
    Poschel 2004, ch. 3; review eq. (defRestiCoeffViscoEl)]
    """

    strength: float = attrs.field(converter=check.to_float,
                                  validator=check.real(0.0, math.inf, lower_open=True))

    def _evaluate(self, speed):
        c = self.strength * speed ** 0.2
        x = numpy.minimum(1.0, numpy.where(c > 0.0, c, 1.0) ** (-1.0 / 3.0))
        for _ in range(200):
            step = (x ** 5 + c * x ** 3 - 1.0) / (5.0 * x ** 4 + 3.0 * c * x ** 2)
            x_new = x - step
            if not numpy.any(x_new < x):
                break
            x = numpy.minimum(x, x_new)
        return x ** 5


@attrs.frozen
class Tanh(RestitutionLaw):
    """Smooth velocity-dependent law of the review's Test 3.

    e(r) = (e0 - 1)/2 tanh((r - centre)/width) + (e0 + 1)/2, which moves from
    about 1 at small relative speed to about e0 at large speed; the review uses
    centre = 4 and width = 1.
    """

    asymptotic_value: float = attrs.field(converter=check.to_float, validator=check.real(0.0, 1.0))
    centre: float = attrs.field(default=4.0, converter=check.to_float, validator=check.real())
    width: float = attrs.field(default=1.0, converter=check.to_float,
                               validator=check.real(0.0, math.inf, lower_open=True))

    @property
    def is_constant(self) -> bool:
        return self.asymptotic_value == 1.0

    def _evaluate(self, speed):
        e0 = self.asymptotic_value
        return 0.5 * (e0 - 1.0) * numpy.tanh((speed - self.centre) / self.width) + 0.5 * (e0 + 1.0)


@attrs.frozen
class Threshold(RestitutionLaw):
    """Threshold law [Poschel et al. 2005]: e(r) = 1 for r < r_*, e_bar for r >= r_*."""

    threshold: float = attrs.field(converter=check.to_float,
                                   validator=check.real(0.0, math.inf, lower_open=True))
    value: float = attrs.field(converter=check.to_float, validator=check.real(0.0, 1.0))

    @property
    def is_constant(self) -> bool:
        return self.value == 1.0

    def _evaluate(self, speed):
        return numpy.where(speed < self.threshold, 1.0, self.value)


def is_elastic(restitution, grid) -> bool:
    """e = 1 at every relative speed the operators see (|g| <= R, 65 speeds)."""
    speeds = numpy.linspace(0.0, grid.truncation_radius, 65)
    return bool(numpy.all(restitution(speeds) == 1.0))
