"""Accuracy checks shared by granframe's tests, its studies and plugin authors' tests.

Like ``zarr.testing``: a plugin that adds a collision operator can run the
same physics checks granframe runs on its own. :mod:`granframe.testing.conformance` holds
the conformance kit (a pytest test class per family to subclass, and the check functions
behind them); :mod:`granframe.testing.strategies` the Hypothesis strategies of valid
distributions it uses.
"""

from __future__ import annotations

from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.model.exact import heated_maxwell_temperature
from granframe.registry import default_registries


def heated_maxwell_error(operator, restitution: float, heat_bath: float = 0.1,
                         initial_temperature: float = 8.0, time_step: float = 0.01,
                         steps: int = 200):
    """Run the review's heated Maxwell-molecule problem; return (max relative T error, mass drift).

    d_t f = Q(f, f) + tau Delta f from a Maxwellian of temperature T0, the registered
    classical RK4 with ``time_step`` for ``steps`` steps (the review: dt = 0.01 to t = 2),
    temperature compared at every step with
    :func:`granframe.model.exact.heated_maxwell_temperature`. ``operator`` must be built for
    Maxwell molecules with the review's constant and constant restitution coefficient
    ``restitution``.
    """
    grid, xp = operator.grid, operator.backend.xp
    equation = HomogeneousBoltzmann(operator, heat_bath)
    rk4 = default_registries().create("time_integrators", "rk4")
    f = operator.backend.asarray(grid.maxwellian(temperature=initial_temperature))
    rho0, dt, worst = grid.mass(f, xp), time_step, 0.0
    for step in range(1, steps + 1):
        f = rk4.step(equation, (step - 1) * dt, f, dt)
        exact = heated_maxwell_temperature(step * dt, initial_temperature, restitution,
                                           heat_bath, rho0)
        worst = max(worst, abs(grid.temperature(f, xp) / exact - 1))
    return worst, abs(grid.mass(f, xp) / rho0 - 1)


def evaluate_on_host(operator, f):
    """Q(f) for a host (NumPy) f, evaluated on the operator's array backend and returned as a
    host array: the way one test body checks an operator on every backend."""
    backend = operator.backend
    return backend.to_numpy(operator(backend.asarray(f)))
