"""Time-integrator interface for df/dt = F(t, f).

Schemes (forward Euler, SSP Runge-Kutta, RK4, exponential and adaptive
schemes) are registered as plugins through ``granframe_register_time_integrators``;
the runner looks them up by name and never branches on scheme names.
"""

from __future__ import annotations

import abc
from typing import Callable, ClassVar


class TimeIntegrator(abc.ABC):
    """One step f(t) -> f(t + dt) of an explicit one-step method.

    Attributes
    ----------
    order : int
        Classical order of accuracy p: the global error is O(dt^p).
    adaptive : bool
        True when the scheme chooses its own step from an error estimate.
    """

    order: ClassVar[int]
    adaptive: ClassVar[bool] = False

    @abc.abstractmethod
    def step(self, rhs: Callable, t: float, f, dt: float):
        """Return f(t + dt) given ``rhs(t, f) -> df/dt``; ``f`` is not modified."""
