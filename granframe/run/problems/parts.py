"""What both problems build the same way: the collision operator and the step check."""

from __future__ import annotations

from granframe.equations.conservative import ConservativeCorrection
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
    registries = default_registries()
    schemes = [(name, registries.get("time_integrators", name).factory)
               for name in registries.names("time_integrators")]
    check_time_step(integrator, d.integrator.name, equation, f0, d.time_step, schemes)
