"""d_t f = Q(f, f)/eps + tau Delta_v f for a batch of distributions, split for the integrators.

A space-homogeneous run steps a batch of one distribution; the collision step of a space
run steps every cell of its blocks at once (f of shape (..., *grid.shape)). One equation
serves both: the operator and the heat bath act on the whole batch, and the moments behind
the BGK penalisation, the stiffness and the restoration of the conserved moments come from
the moment service (:class:`~granframe.velocity.moments.FieldMoments`) on the backend.
"""

from __future__ import annotations

import numpy

from granframe.abc import Part
from granframe.backends import to_host
from granframe.equations.conservative import ConservativeCorrection
from granframe.model.restitution import is_elastic
from granframe.stepping.integrators import Equation
from granframe.velocity.equilibrium import discrete_maxwellians
from granframe.velocity.guard import guard_moments
from granframe.velocity.heatbath import HeatBath
from granframe.velocity.moments import FieldMoments


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
    r"""d_t f = Q_I(f, f)/\varepsilon + \tau \Delta_v f (review, eq. (homo_heat), with
    Knudsen \varepsilon) for f of shape (..., *grid.shape): one distribution or a batch
    (the cells of a space run).

    N(t, f) = Q(f, f)/eps is the explicit part; L = tau Delta_v is the linear
    part, exact through :meth:`HeatBath.propagate` in integrating-factor schemes. The
    stiffness is the largest over the batch, and the BGK penalisation of the penalised
    integrators is taken distribution by distribution (a rate and a Maxwellian each), all
    from the moment service on the backend.

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
        grid = operator.grid
        kernel, d = operator.kernel, grid.dimension
        self._frequency_constant = kernel.prefactor(d) * kernel.angular_integral(d)
        self.moments = FieldMoments(grid, 1.0, operator.backend.xp)
        #: what the collision step conserves exactly in every distribution, which
        #: :meth:`restore` keeps against round-off: with the conservative correction the
        #: mass, and without a heat bath (whose periodic Laplacian moves momentum by the
        #: grid's edge terms) the momentum and, for an elastic gas, the energy; nothing
        #: without the correction
        self.invariants = ()
        if isinstance(operator, ConservativeCorrection):
            elastic = is_elastic(operator.restitution, grid)
            self.invariants = (("mass",) if self.heat.tau else
                               ("mass", "momentum") + (("energy",) if elastic else ()))

    def nonlinear(self, t, f):
        q = self.operator(f)
        return q if self.knudsen == 1.0 else q * (1.0 / self.knudsen)

    def linear(self, f):
        """tau Delta_v f; the scalar 0 without a heat bath (no transforms)."""
        return self.heat(f) if self.heat.tau else 0.0

    def propagate(self, f, dt):
        return self.heat.propagate(f, dt)

    def frequencies(self, density, temperature, energy):
        r"""The mean loss frequency of every distribution of a batch at once, on the
        arrays' device: nu_c = C int b dsigma rho_c <s(|g|)>(T_c) phi(E_c)
        (:func:`collision_frequency`, its angular factor cached), with
        :meth:`~granframe.abc.CollisionKernel.mean_speed_parts`."""
        kernel, d = self.operator.kernel, self.operator.grid.dimension
        speed = kernel.mean_speed_parts(d, temperature, self.operator.backend.xp)
        return self._frequency_constant * density * speed * kernel.energy_factors(energy)

    def stiffness(self, f) -> dict:
        """The largest spectral radii over the distributions of f (those of
        :meth:`distribution_stiffness` for the one where rho phi(E), which the rates grow
        with, is largest); for one distribution, its own."""
        grid = self.operator.grid
        flat = f.reshape((-1,) + tuple(grid.shape))
        if flat.shape[0] == 1:
            return self.distribution_stiffness(flat[0])
        rho, _, _, energy = (to_host(a) for a in self.moments.primitives(flat, node="periodic"))
        kernel = self.operator.kernel
        weight = rho * (kernel.energy_factors(numpy.where(energy > 0, energy, 1.0))
                        if kernel.energy_exponent else 1.0)
        return self.distribution_stiffness(flat[int(numpy.argmax(weight))])

    def distribution_stiffness(self, f) -> dict:
        r"""Spectral radii at one distribution f that bound explicit time steps
        (:mod:`granframe.stepping.stability`).

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
        r"""BGK penalisation r (M[f] - f) for
        :class:`~granframe.stepping.integrators.PenalisedIMEX`, per distribution of f.

        r_c = penalty nu(rho_c, T_c) / eps with :meth:`frequencies`. The penalty (2 by
        default) must bound the spectrum of the linearised collision operator, which
        extends beyond -nu: in the stiff limit ARS(2,2,2) is stable only for modes with
        |lambda| <= r eps, and the stability map (docs/stability.md) blows up with penalty
        1 and 1.5 and holds with 2. M[f] is the discrete Maxwellian with exactly the grid
        mass, momentum (node -L at -L) and energy of f
        (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`): P(f) = r (M[f] - f)
        conserves them to round-off, so M is invariant under P whatever r dt
        [Filbet & Jin, J. Comput. Phys. 229 (2010), section 4]. Where rho or T is not
        positive and finite, r = 0: the step goes on explicitly there and the runner's
        health check reports the state. On the device, no transfer; the rates have the
        batch shape followed by d axes of length 1.
        """
        grid, xp = self.operator.grid, self.operator.backend.xp
        d = grid.dimension
        flat = f.reshape((-1,) + tuple(grid.shape))
        guarded = guard_moments(*self.moments.primitives(flat, node="periodic"), xp)
        rate = xp.where(guarded.valid, self.penalty * self.frequencies(
            guarded.density, guarded.temperature, guarded.energy), 0.0)
        target, _ = discrete_maxwellians(grid, guarded.density, guarded.momentum,
                                         guarded.second, xp, self.moments.points)
        shape = f.shape[:-d] + (1,) * d
        return (rate * (1.0 / self.knudsen)).reshape(shape), target.reshape(f.shape)

    def conserved(self, f):
        """The grid mass, momentum (node -L at -L) and second moment h^d sum |v|^2 f of every
        distribution of f (..., *grid.shape), on the device: what :meth:`restore` takes."""
        grid = self.operator.grid
        flat = f.reshape((-1,) + tuple(grid.shape))
        rho, velocity, _, energy = self.moments.primitives(flat, node="periodic")
        return rho, rho[:, None] * velocity, 2.0 * energy

    def restore(self, f, before):
        r"""f with the moments in :attr:`invariants` of every distribution set back to
        ``before`` (:meth:`conserved` of the data of the collision step).

        The stages of a penalised step sum terms of size dt |Q|/eps whose round-off,
        u dt |Q|/eps with u the unit round-off, shows in the moments that the step
        conserves exactly: 1e-7 of the mass per step at eps = 1e-10 and dt/eps = 1e8.
        The correction adds the difference of two discrete Maxwellians,

        .. math:: f \leftarrow f + \mathcal M[\rho^0, J^0, S^0] - \mathcal M[\rho, J, S],

        (with J^0 = J and S^0 = S for what is not conserved), whose moments are exactly the
        defect: it is of the size of the round-off and changes nothing else. Distributions
        where either Maxwellian does not converge are left as they are.
        """
        if not self.invariants:
            return f
        grid, xp = self.operator.grid, self.operator.backend.xp
        flat = f.reshape((-1,) + tuple(grid.shape))
        now = self.conserved(flat)
        goal = (before[0], before[1] if "momentum" in self.invariants else now[1],
                before[2] if "energy" in self.invariants else now[2])
        points = self.moments.points
        wanted, ok_wanted = discrete_maxwellians(grid, *goal, xp, points)
        present, ok_present = discrete_maxwellians(grid, *now, xp, points)
        ok = (ok_wanted & ok_present).reshape((-1,) + (1,) * grid.dimension)
        return (flat + xp.where(ok, wanted - present, 0.0)).reshape(f.shape)
