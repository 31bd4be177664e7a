"""The conformance checks of time integrators: the declared order (and an adaptive
scheme's embedded order) observed on a linear test equation with a known solution.
"""

from __future__ import annotations

import math

import numpy

from granframe.abc import AdaptiveIntegrator, Equation, TimeIntegrator
from granframe.testing.conformance.common import require


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
    require(isinstance(integrator, TimeIntegrator),
            f"{integrator!r} is not a granframe.TimeIntegrator")
    name, order = type(integrator).__name__, integrator.order
    equation = LinearTestEquation()
    f0 = numpy.array([1.0, -0.5, 2.0])
    copy = f0.copy()
    integrator.step(equation, 0.0, f0, 0.1)
    require(numpy.array_equal(f0, copy), f"{name}: step() modified its input f")
    exact = equation.solution(1.0, f0)
    errors = [float(numpy.max(numpy.abs(_integrate(integrator, equation, f0, dt) - exact)))
              for dt in (0.1, 0.05)]
    observed = math.log2(errors[0] / errors[1]) if errors[1] > 0 else math.inf
    require(observed >= order - 0.3,
            f"{name}: declared order {order}, observed {observed:.2f} on a linear test "
            f"equation (errors {errors[0]:.3g} at dt = 0.1, {errors[1]:.3g} at 0.05)")
    if isinstance(integrator, AdaptiveIntegrator):
        estimates = [float(numpy.max(numpy.abs(integrator.attempt(equation, 0.0, f0, dt)[1])))
                     for dt in (0.1, 0.05)]
        observed = math.log2(estimates[0] / estimates[1])
        q = integrator.embedded_order
        require(observed >= q + 1 - 0.3,
                f"{name}: embedded order {q}, but the error estimate falls as "
                f"dt^{observed:.2f} (expected dt^{q + 1})")
