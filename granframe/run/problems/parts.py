"""What both problems build the same way: the collision operator and the step check."""

from __future__ import annotations

from granframe.abc import Part
from granframe.equations.conservative import ConservativeCorrection
from granframe.validators import reject
from granframe.registry import default_registries
from granframe.stepping.stability import check_time_step


def build_operator(description, backend):
    """The description's collision operator on ``backend``, with the conservative
    correction when the description asks for it (docs/conservative.md)."""
    d = description
    operator = d.build("operator", grid=d.grid, kernel=d.build("kernel"),
                       restitution=d.build("restitution"), backend=backend)
    if d.conservative is not None:
        operator = ConservativeCorrection(operator, d.conservative)
    return operator


def check_step(description, integrator, equation, f0) -> None:
    """Refuse a fixed time step above ``integrator``'s explicit stability limit for
    ``equation`` at f0 (unless ``health.step_limit`` is false), naming the schemes that
    would take it (:func:`~granframe.stepping.stability.check_time_step`)."""
    d = description
    if not d.health.step_limit or integrator.adaptive:
        return
    check_penalised_step(d, integrator, equation, f0)
    registries = default_registries()
    schemes = [(name, registries.get("time_integrators", name).factory)
               for name in registries.names("time_integrators")]
    check_time_step(integrator, d.integrator.name, equation, f0, d.time_step, schemes)


#: the most collision times nu dt / eps a scheme that treats the collisions implicitly may
#: take per step without the conservative correction: the operator's energy defect is
#: amplified by that factor (the Sod tube of docs/space.md drifts by 1.7e-3 in energy by
#: t = 0.1 at 67 and loses positivity at 670)
UNCORRECTED_COLLISION_TIMES = 100.0


def check_penalised_step(description, integrator, equation, f0) -> None:
    """Refuse a step of more than :data:`UNCORRECTED_COLLISION_TIMES` collision times in the
    stiffest cell for a scheme that treats Q implicitly (an asymptotic-preserving one:
    ``Part.NONLINEAR`` not among its explicit parts) without the conservative correction.
    """
    d = description
    if Part.NONLINEAR in integrator.explicit_parts or d.conservative is not None:
        return
    rate = equation.stiffness(f0).get(Part.NONLINEAR, 0.0)
    times = rate * d.time_step
    if times > UNCORRECTED_COLLISION_TIMES:
        reject("the run", "time_step", d.time_step,
               f"is {times:.3g} collision times nu dt/knudsen in the stiffest cell; the "
               f"scheme {d.integrator.name!r} amplifies the collision operator's "
               f"conservation defect by that factor, so without the conservative correction "
               f"it takes at most {UNCORRECTED_COLLISION_TIMES:g} (time_step <= "
               f"{UNCORRECTED_COLLISION_TIMES / rate:.3g}): set conservative = true, which "
               f"conserves mass, momentum and energy exactly at any knudsen "
               f"(docs/conservative.md), or a smaller time_step")
