"""Explicit time-step limits, checked before a run starts (docs/stability.md).

A scheme that treats a part of the equation explicitly is stable only while
dt rho(part) <= its stability interval on the negative real axis
(:attr:`TimeIntegrator.stability_interval`), where rho(part) is the spectral
radius that :meth:`Equation.stiffness` estimates:

- the heat bath tau Delta (``linear``): tau max |k|^2 (pi/L)^2, exact;
- the collisions Q/eps (``nonlinear``): the largest loss frequency over eps;
- the energy dissipation (``dissipation``), which the penalised schemes keep
  explicit: (1 - e^2) nu / (4 eps).

A fixed step above a limit would amplify the stiff modes from round-off on
and blow up a few hundred steps later; the runner refuses it up front, with
the limit, the rate behind it and the schemes that do not have it.
"""

from __future__ import annotations

import attrs

from granframe import validators as check

PART_NAMES = {"linear": "the heat bath tau Delta_v",
              "nonlinear": "the collision term Q/eps",
              "dissipation": "the energy dissipation of Q/eps"}


#: the energy dissipation is a part of the collision term: a scheme explicit in the
#: collisions is explicit in it too
_CONTAINED_IN = {"dissipation": "nonlinear"}


def treats_explicitly(scheme, part: str) -> bool:
    """Whether ``scheme`` (an integrator or its class) treats ``part`` explicitly."""
    parts = getattr(scheme, "explicit_parts", None)
    if parts is None:
        return True            # unknown scheme: assume the worst
    return part in parts or _CONTAINED_IN.get(part) in parts


@attrs.frozen
class StepLimit:
    """dt <= ``limit`` = ``interval`` / ``rate`` for ``part`` under the named scheme."""

    part: str
    rate: float
    interval: float

    @property
    def limit(self) -> float:
        return self.interval / self.rate if self.rate > 0 else float("inf")


def step_limits(integrator, equation, f) -> list[StepLimit]:
    """The explicit step limits of ``integrator`` on ``equation`` at ``f``, smallest first."""
    rates = equation.stiffness(f)
    limits = [StepLimit(part, float(rates[part]), integrator.stability_interval)
              for part in sorted(integrator.explicit_parts) if part in rates]
    return sorted(limits, key=lambda limit: limit.limit)


def check_time_step(integrator, name: str, equation, f, dt: float, alternatives=()) -> None:
    """Refuse a fixed step ``dt`` above an explicit stability limit, with a clear message.

    ``alternatives`` holds (registered name, factory) pairs; the fixed-step schemes that
    do not treat the offending part explicitly are suggested.
    """
    for limit in step_limits(integrator, equation, f):
        if dt > limit.limit:
            others = sorted(other for other, scheme in alternatives
                            if not treats_explicitly(scheme, limit.part)
                            and not getattr(scheme, "adaptive", False))
            check.reject(
                "RunDescription", "time_step", dt,
                f"must be <= {limit.limit:.4g}, the explicit stability limit of '{name}' for "
                f"{PART_NAMES.get(limit.part, limit.part)}: its spectral radius is "
                f"{limit.rate:.4g} and '{name}' is stable for dt * rate <= {limit.interval:g}"
                + (f"; or use an integrator that treats it implicitly or exactly: "
                   f"{', '.join(others)}" if others else ""))
