"""The contracts of the physical model: the restitution law e(r), the collision kernel B
and the initial condition f0.

:mod:`granframe.model` implements them (and :mod:`granframe.space.initial` the initial
conditions of a space run), plugins add more; :mod:`granframe.contract_checks` checks
each where it is built by name. Imported from :mod:`granframe.abc`.
"""

from __future__ import annotations

import abc
import math

import numpy

from granframe import validators as check
from granframe.rules import circle_rule, gauss_legendre


# -- Restitution laws ----------------------------------------------------------------------

class RestitutionLaw(abc.ABC):
    """A restitution coefficient e(r) of the relative speed r = |v - v_*|.

    An implementation provides :meth:`_evaluate`, vectorised over a NumPy array of speeds,
    with values in [0, 1] of the array's shape, and sets ``is_constant`` when e does not
    depend on r (operators then evaluate it once). :meth:`__call__` refuses speeds that
    are negative or not finite before calling it. The framework checks a law where it is
    built by name (values in [0, 1], finite, of the input's shape, at zero, small and
    large speeds) and where an operator receives it
    (:class:`~granframe.abc.CollisionOperator`).
    """

    is_constant: bool = False

    def __call__(self, speed):
        speed = numpy.asarray(speed, dtype=float)
        if speed.size and not (numpy.all(numpy.isfinite(speed)) and speed.min() >= 0.0):
            check.reject(type(self).__name__, "speed", speed,
                         "relative speeds must be finite and >= 0")
        with numpy.errstate(divide="ignore", over="ignore", invalid="ignore"):
            return self._evaluate(speed)

    @abc.abstractmethod
    def _evaluate(self, speed):
        """e at the speeds ``speed`` (a float array, finite and >= 0), an array of its shape."""


# -- Collision kernels ---------------------------------------------------------------------

class CollisionKernel(abc.ABC):
    r"""A collision kernel B(|g|, cos theta, E) = C s(|g|) b(cos theta) phi(E).

    C is :meth:`prefactor`, s the speed part, b the angular part and phi the energy
    factor of the kinetic energy E = int |v|^2/2 f dv. The operators, the step limits
    and the run planner read a kernel only through these members.

    An implementation must provide :meth:`prefactor`, :meth:`speed_part` (finite and
    >= 0, vectorised in any array namespace ``xp``) and :attr:`speed_exponent`, an upper
    bound lambda of its growth: s(r) <= s_1 max(1, r)^lambda for some constant s_1
    (the power of a power law; growth and cost estimates use it). The other members
    have defaults: isotropic scattering (b = 1), no energy dependence, not Maxwell
    molecules, and numerical angular integrals, maxima and Maxwellian averages of s. A
    kernel with an angular part overrides :meth:`angular_part` and sets
    ``is_isotropic`` False; one whose speed part is constant sets ``is_maxwellian``.
    The framework checks a kernel where it is built by name: positive finite values of
    the speed and angular parts and of the prefactor, and an isotropy flag that agrees
    with the angular part; operators accept only instances of this class.

    Attributes
    ----------
    is_isotropic : bool
        True when b is constant (operators then skip the angular quadrature).
    is_maxwellian : bool
        True when s is constant (Maxwell pseudo-molecules; exact laws exist).
    energy_exponent : float
        gamma of phi(E) = E^gamma (0: no energy dependence); :meth:`energy_factor`
        computes phi.
    """

    is_isotropic: bool = True
    is_maxwellian: bool = False
    energy_exponent: float = 0.0

    @abc.abstractmethod
    def prefactor(self, dimension: int) -> float:
        """The constant C used in dimension ``dimension`` (2 or 3), > 0."""

    @abc.abstractmethod
    def speed_part(self, speed, xp=numpy):
        """s(|g|) at the speeds ``speed`` (an array of ``xp``), an array of its shape."""

    @property
    @abc.abstractmethod
    def speed_exponent(self) -> float:
        """An upper bound lambda of the growth of s: s(r) <= s_1 max(1, r)^lambda."""

    def angular_part(self, cos_theta):
        """b(cos theta) for a NumPy array of cos theta in [-1, 1]; 1 by default."""
        return numpy.ones_like(numpy.asarray(cos_theta, dtype=float))

    def angular_integral(self, dimension: int, weight=None) -> float:
        """int_{S^{d-1}} b(cos theta) w(cos theta) dsigma (w = 1 when ``weight`` is None).

        In 2D the trapezoidal rule on 2048 equispaced angles (the largest
        :class:`~granframe.velocity.quadratures.CircleTrapezoid`; spectral for smooth b); in
        3D 2 pi times the 200-point Gauss-Legendre rule in cos theta. |S^{d-1}| for b = 1.
        """
        if dimension == 2:
            nodes, w = circle_rule(2048)
            t = nodes[:, 0]
        else:
            nodes, w = gauss_legendre(200, 2.0)
            t, w = nodes - 1.0, 2 * math.pi * w
        values = self.angular_part(t) * (1.0 if weight is None else weight(t))
        return float(w @ values)

    def largest_speed_part(self, radius: float) -> float:
        """max s(r) over r in [0, ``radius``] (relative speeds are cut at the grid's R);
        by default the largest of 257 equispaced samples."""
        return float(numpy.max(self.speed_part(numpy.linspace(0.0, radius, 257))))

    def mean_speed_part(self, dimension: int, temperature: float) -> float:
        r"""<s(|g|)> over the relative velocities g of two particles of a Maxwellian at
        ``temperature``: g is Maxwellian at 2T, |g| has the density proportional to
        r^{d-1} exp(-r^2/(4T)). By default a 64-point Gauss-Legendre rule on
        [0, 18 sqrt(T)] (the density is below e^-80 beyond)."""
        if not (temperature > 0.0 and math.isfinite(temperature)):
            check.reject(type(self).__name__, "temperature", temperature,
                         "must be positive and finite")
        r, w = gauss_legendre(64, 18.0 * math.sqrt(temperature))
        density = w * r ** (dimension - 1) * numpy.exp(-r * r / (4.0 * temperature))
        return float(density @ self.speed_part(r) / density.sum())

    def mean_speed_parts(self, dimension: int, temperature, xp=numpy):
        r""":meth:`mean_speed_part` at every temperature of an array of ``xp`` (one per cell
        of a space run), in ``xp``: no transfer to the host. By default the same 64-point
        Gauss-Legendre rule on [0, 18 sqrt(T)], in the variable x = r / (18 sqrt T) whose
        weights x^{d-1} exp(-81 x^2) do not depend on T."""
        x, w = gauss_legendre(64, 1.0)
        density = w * x ** (dimension - 1) * numpy.exp(-81.0 * x * x)
        speeds = 18.0 * xp.sqrt(temperature)[..., None] * xp.asarray(x)
        return self.speed_part(speeds, xp) @ xp.asarray(density / density.sum())

    def energy_factors(self, energy):
        """phi(E) = E^gamma at every energy of an array (positive, checked by the caller)."""
        return 1.0 if self.energy_exponent == 0.0 else energy ** self.energy_exponent

    def energy_factor(self, energy: float) -> float:
        """phi(E) = E^gamma for the kinetic energy E = int |v|^2/2 f dv."""
        if self.energy_exponent == 0.0:
            return 1.0
        if not (energy > 0.0 and math.isfinite(energy)):
            check.reject(type(self).__name__, "energy", energy,
                         "must be positive and finite when energy_exponent != 0")
        return energy ** self.energy_exponent

    def __call__(self, speed, cos_theta, energy: float = 1.0, *, dimension: int):
        """B(|g|, cos theta, E) = C s(|g|) b(cos theta) phi(E)."""
        return (self.prefactor(dimension) * self.speed_part(numpy.asarray(speed, dtype=float))
                * self.angular_part(cos_theta) * self.energy_factor(energy))


# -- Initial conditions --------------------------------------------------------------------

class InitialCondition(abc.ABC):
    """f0 on a velocity grid."""

    @abc.abstractmethod
    def sample(self, grid) -> numpy.ndarray:
        """f0 at the grid points, shape ``grid.shape``."""

    @property
    def intended_mass(self) -> float | None:
        """The mass f0 carries on the whole space, or ``None`` when not known."""
        return None
