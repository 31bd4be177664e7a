"""The space-homogeneous equation d_t f = Q(f, f)/eps + tau Delta_v f, split for the integrators."""

from __future__ import annotations

import math

import numpy

from granframe.abc import Part
from granframe.velocity.equilibrium import discrete_maxwellians
from granframe.velocity.heatbath import HeatBath
from granframe.stepping.integrators import Equation


def collision_frequency(kernel, dimension: int, density: float, temperature: float,
                        energy: float, angular: float | None = None) -> float:
    r"""Mean loss frequency of a Maxwellian: nu = C int b dsigma rho <s(|g|)> phi(E).

    The relative velocity of two particles of a Maxwellian at temperature T is
    Maxwellian at 2T; <s(|g|)> is the kernel's
    :meth:`~granframe.abc.CollisionKernel.mean_speed_part` ((4T)^{lambda/2}
    Gamma((d+lambda)/2) / Gamma(d/2) for |g|^lambda); exact for Maxwell molecules
    (nu = C |S^{d-1}| rho). ``angular`` is C int b dsigma when already known.
    """
    d = dimension
    if angular is None:
        angular = kernel.prefactor(d) * kernel.angular_integral(d)
    speed = kernel.mean_speed_part(d, temperature)
    return angular * density * speed * kernel.energy_factor(energy)


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
    penalty : float
        Multiple of the mean collision frequency used as the BGK penalisation rate of
        the penalised integrators (:meth:`relaxation`).
    """

    def __init__(self, operator, heat_bath: float = 0.0, knudsen: float = 1.0,
                 penalty: float = 2.0):
        self.operator = operator
        self.heat = HeatBath(operator.grid, heat_bath, operator.backend)
        self.knudsen = float(knudsen)
        self.penalty = float(penalty)
        kernel, d = operator.kernel, operator.grid.dimension
        self._frequency_constant = kernel.prefactor(d) * kernel.angular_integral(d)

    def nonlinear(self, t, f):
        q = self.operator(f)
        return q if self.knudsen == 1.0 else q * (1.0 / self.knudsen)

    def linear(self, f):
        """tau Delta_v f; the scalar 0 without a heat bath (no transforms)."""
        return self.heat(f) if self.heat.tau else 0.0

    def propagate(self, f, dt):
        return self.heat.propagate(f, dt)

    def collision_frequency(self, density: float, temperature: float, energy: float) -> float:
        """:func:`collision_frequency` of the operator's kernel (its angular factor cached)."""
        return collision_frequency(self.operator.kernel, self.operator.grid.dimension, density,
                                   temperature, energy, self._frequency_constant)

    def stiffness(self, f) -> dict:
        r"""Spectral radii at f that bound explicit time steps (:mod:`granframe.stepping.stability`).

        - ``linear``: the heat bath, tau max |k|^2 (pi/L)^2 over the evolved modes;
        - ``nonlinear``: the collisions, nu_max / eps with the largest loss frequency
          nu_max = C int b dsigma rho max s(|g|) phi(E), the maximum over |g| <= R
          (relative speeds are cut at R; R^lambda for |g|^lambda);
          for Maxwell molecules nu_max = nu, and RK4's observed boundary lies on
          2.7853 eps / nu within the resolution of the stability map (docs/stability.md);
        - ``dissipation``: the energy loss, (1 - e_min^2) nu_max / (4 eps) with e_min the
          smallest restitution coefficient over relative speeds in [0, R]; for Maxwell
          molecules and constant e the exact rate of dT/dt = -(1-e^2) rho T / (4 eps).
        """
        grid = self.operator.grid
        xp = numpy if isinstance(f, numpy.ndarray) else self.operator.backend.xp
        density = grid.mass(f, xp)
        energy = grid.kinetic_energy(f, xp)
        kernel = self.operator.kernel
        cut = kernel.largest_speed_part(grid.truncation_radius)
        factor = kernel.energy_factor(energy) if energy > 0 else 1.0
        frequency = self._frequency_constant * density * cut * factor
        speeds = numpy.linspace(0.0, grid.truncation_radius, 257)
        e_min = float(numpy.min(self.operator.restitution(speeds)))
        rates = {Part.NONLINEAR: frequency / self.knudsen,
                 Part.DISSIPATION: (1.0 - e_min ** 2) * frequency / (4.0 * self.knudsen)}
        if self.heat.tau:
            rates[Part.LINEAR] = self.heat.spectral_radius
        return rates

    def relaxation(self, f):
        r"""BGK penalisation for :class:`~granframe.stepping.integrators.PenalisedIMEX`.

        r = penalty nu(rho, T) / eps with :meth:`collision_frequency`. The penalty (2 by
        default) must bound the spectrum of the linearised collision operator, which
        extends beyond -nu: in the stiff limit ARS(2,2,2) is stable only for modes with
        |lambda| <= r eps, and the stability map (docs/stability.md) blows up with penalty
        1 and 1.5 and holds with 2. M[f] is the discrete Maxwellian with exactly the grid
        mass, momentum and energy of f
        (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`): P(f) = r (M[f] - f)
        conserves them to round-off, so M is invariant under P whatever r dt
        [Filbet & Jin, J. Comput. Phys. 229 (2010), section 4]. Where T is not positive
        and finite, r = 0: the step goes on explicitly and the runner's health check
        reports the state.
        """
        grid, xp = self.operator.grid, self.operator.backend.xp
        density = grid.mass(f, xp)
        if not (density > 0.0 and math.isfinite(density)):
            return 0.0, f
        momentum = grid.momentum(f, xp)
        temperature = grid.temperature(f, xp)
        if not (temperature > 0.0 and math.isfinite(temperature)):
            return 0.0, f
        energy = grid.kinetic_energy(f, xp)
        target, _ = discrete_maxwellians(grid, xp.asarray([density]),
                                         xp.asarray(momentum).reshape(1, -1),
                                         xp.asarray([2.0 * energy]), xp)
        target = target[0]
        rate = self.penalty * self.collision_frequency(density, temperature, energy)
        return rate / self.knudsen, target
