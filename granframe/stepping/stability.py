"""Explicit time-step limits, checked before a run starts (docs/stability.md).

A scheme is stable only while dt times the sum of the spectral radii of the
parts it treats explicitly stays within its stability interval on the negative
real axis (:attr:`TimeIntegrator.stability_interval`). The radii are those that
:meth:`Equation.stiffness` estimates:

- the heat bath tau Delta (``linear``): tau max |k|^2 (pi/L)^2, exact;
- the collisions Q/eps (``nonlinear``): the largest loss frequency over eps;
- the energy dissipation (``dissipation``), which the penalised schemes keep
  explicit: (1 - e^2) nu / (4 eps);
- the drift of the rescaled formulation (``drift``, :mod:`granframe.equations.rescaled`), a
  transport term with an imaginary spectrum: schemes not stable on the imaginary
  axis (:attr:`TimeIntegrator.imaginary_interval` = 0) are refused at any step, and
  the others get the smaller of their two intervals.

A fixed step above a limit would amplify the stiff modes from round-off on
and blow up a few hundred steps later; the runner refuses it up front, with
the limit, the rate behind it and the schemes that do not have it.

:func:`granframe.run.problems.time_step_limit` gives the same limit from a description
alone, before anything of the operator is built (on an :class:`OperatorOutline`): every radius but the drift's reads only the grid, the kernel, the
restitution law and the moments of f0, and the drift's needs the cooling rate a_0, whose
collision integral, the energy dissipation D(f0), is taken in closed form from the weak
form of Q (:meth:`~granframe.equations.conservative.ConservativeCorrection.dissipation`).
"""

from __future__ import annotations

import attrs

from granframe import validators as check
from granframe.abc import CollisionOperator, Part

PART_NAMES = {Part.LINEAR: "the heat bath tau Delta_v",
              Part.NONLINEAR: "the collision term Q/eps",
              Part.DISSIPATION: "the energy dissipation of Q/eps",
              Part.DRIFT: "the drift of the rescaled formulation"}


#: the energy dissipation is a part of the collision term: a scheme explicit in the
#: collisions is explicit in it too
_CONTAINED_IN = {Part.DISSIPATION: Part.NONLINEAR}


def treats_explicitly(scheme, part: str) -> bool:
    """Whether ``scheme`` (an integrator or its class) treats ``part`` explicitly."""
    parts = getattr(scheme, "explicit_parts", None)
    if parts is None:
        return True            # unknown scheme: assume the worst
    return part in parts or _CONTAINED_IN.get(part) in parts


@attrs.frozen
class StepLimit:
    """dt <= ``limit`` = ``interval`` / (sum of the ``rates`` of the explicit parts).

    ``rates`` maps each part the scheme treats explicitly to its spectral radius. The
    radii add: the spectrum of the explicit right-hand side lies within the sum of its
    parts' (the stability map shows RK4 blowing up 5 % below the heat bath's own limit
    when the collisions are left out).
    """

    rates: dict
    interval: float

    @property
    def rate(self) -> float:
        return float(sum(self.rates.values()))

    @property
    def limit(self) -> float:
        return self.interval / self.rate if self.rate > 0 else float("inf")

    @property
    def dominant(self) -> str:
        return max(self.rates, key=self.rates.get)


def step_limit(integrator, equation, f) -> StepLimit | None:
    """The explicit step limit of ``integrator`` on ``equation`` at ``f`` (None if the
    equation estimates none of the parts the scheme treats explicitly)."""
    rates = equation.stiffness(f)
    parts = {part: float(rate) for part, rate in rates.items()
             if treats_explicitly(integrator, part)}
    if Part.NONLINEAR in parts:
        parts.pop(Part.DISSIPATION, None)        # contained in the collision term
    if not parts:
        return None
    interval = integrator.stability_interval
    if Part.DRIFT in parts:
        interval = min(interval, getattr(integrator, "imaginary_interval", 0.0))
    return StepLimit(parts, interval)


def check_time_step(integrator, name: str, equation, f, dt: float, alternatives=()) -> None:
    """Refuse a fixed step ``dt`` above the explicit stability limit, with a clear message.

    ``alternatives`` holds (registered name, factory) pairs; the fixed-step schemes that
    do not treat the dominant part explicitly are suggested.
    """
    limit = step_limit(integrator, equation, f)
    if limit is None or dt <= limit.limit:
        return
    if limit.interval == 0.0:
        others = sorted(other for other, scheme in alternatives
                        if getattr(scheme, "imaginary_interval", 0.0) > 0.0
                        and not getattr(scheme, "adaptive", False))
        check.reject("RunDescription", "integrator", name,
                     f"is unstable at any step for {PART_NAMES['drift']}, whose spectrum is "
                     f"imaginary; use a scheme stable on the imaginary axis: "
                     f"{', '.join(others) or 'none registered'}")
    radii = ", ".join(f"{PART_NAMES.get(part, part)} = {rate:.4g}"
                      for part, rate in sorted(limit.rates.items(), key=lambda x: -x[1]))
    others = sorted(other for other, scheme in alternatives
                    if not treats_explicitly(scheme, limit.dominant)
                    and not getattr(scheme, "adaptive", False))
    dominant = PART_NAMES.get(limit.dominant, limit.dominant)
    check.reject(
        "RunDescription", "time_step", dt,
        f"must be <= {limit.limit:.4g}, the explicit stability limit of '{name}', set by "
        f"{dominant} (spectral radii: {radii}); "
        f"'{name}' is stable for dt * (sum of radii) <= {limit.interval:g}"
        + (f"; or use an integrator that treats {dominant} implicitly or exactly: "
           f"{', '.join(others)}" if others else ""))


class OperatorOutline(CollisionOperator):
    """A collision operator without its precomputation: the grid, kernel, restitution law
    and backend, which is all that the stiffness estimates (:meth:`Equation.stiffness`) and
    the closed-form energy dissipation
    (:meth:`~granframe.equations.conservative.ConservativeCorrection.dissipation`) read.
    :func:`granframe.run.problems.time_step_limit` builds the problem on it; it cannot be
    evaluated."""

    name = "operator outline"

    def __call__(self, f):
        raise TypeError("an OperatorOutline has no precomputation and cannot evaluate Q; "
                        "build the run's collision operator (Simulation)")
