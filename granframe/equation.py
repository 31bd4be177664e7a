"""The space-homogeneous equation d_t f = Q(f, f)/eps + tau Delta_v f, split for the integrators."""

from __future__ import annotations

from granframe.heatbath import HeatBath
from granframe.integrators import Equation


class HomogeneousBoltzmann(Equation):
    r"""d_t f = Q_I(f, f)/\varepsilon + \tau \Delta_v f (review, eq. (homo_heat), with Knudsen \varepsilon).

    N(t, f) = Q(f, f)/eps is the explicit part; L = tau Delta_v is the linear
    part, exact through :meth:`HeatBath.propagate` in integrating-factor schemes.

    Parameters
    ----------
    operator : CollisionOperator
    heat_bath : float
        tau >= 0.
    knudsen : float
        eps > 0.
    """

    def __init__(self, operator, heat_bath: float = 0.0, knudsen: float = 1.0):
        self.operator = operator
        self.heat = HeatBath(operator.grid, heat_bath, operator.backend)
        self.knudsen = float(knudsen)

    def nonlinear(self, t, f):
        q = self.operator(f)
        return q if self.knudsen == 1.0 else q * (1.0 / self.knudsen)

    def linear(self, f):
        """tau Delta_v f; the scalar 0 without a heat bath (no transforms)."""
        return self.heat(f) if self.heat.tau else 0.0

    def propagate(self, f, dt):
        return self.heat.propagate(f, dt)
