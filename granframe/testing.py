"""Accuracy checks shared by granframe's tests, its studies and plugin authors' tests.

Like ``zarr.testing``: a plugin that adds a collision operator can run the
same physics checks granframe runs on its own.
"""

from __future__ import annotations

from granframe.exact import heated_maxwell_temperature
from granframe.heatbath import HeatBath


def heated_maxwell_error(operator, restitution: float, heat_bath: float = 0.1,
                         initial_temperature: float = 8.0, time_step: float = 0.01,
                         steps: int = 200):
    """Run the review's heated Maxwell-molecule problem; return (max relative T error, mass drift).

    d_t f = Q(f, f) + tau Delta f from a Maxwellian of temperature T0, classical RK4 with
    ``time_step`` for ``steps`` steps (the review: dt = 0.01 to t = 2), temperature compared
    at every step with :func:`granframe.exact.heated_maxwell_temperature`. ``operator``
    must be built for Maxwell molecules with the review's constant and constant
    restitution coefficient ``restitution``.
    """
    grid, xp = operator.grid, operator.backend.xp
    heat = HeatBath(grid, heat_bath, operator.backend)

    def rhs(f):
        return operator(f) + heat(f)

    f = operator.backend.asarray(grid.maxwellian(temperature=initial_temperature))
    rho0, dt, worst = grid.mass(f, xp), time_step, 0.0
    for step in range(1, steps + 1):
        k1 = rhs(f)
        k2 = rhs(f + dt / 2 * k1)
        k3 = rhs(f + dt / 2 * k2)
        k4 = rhs(f + dt * k3)
        f = f + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        exact = heated_maxwell_temperature(step * dt, initial_temperature, restitution,
                                           heat_bath, rho0)
        worst = max(worst, abs(grid.temperature(f, xp) / exact - 1))
    return worst, abs(grid.mass(f, xp) / rho0 - 1)
