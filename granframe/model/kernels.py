"""Collision kernels B(|g|, cos theta, E) = C |g|^lambda b(cos theta) E^gamma.

This is the generalised hard-sphere kernel of the review (section 1, eq.
``defHSkernelAnomalous``) with an explicit constant C. lambda = 0 gives
Maxwell pseudo-molecules, lambda = 1 hard spheres; the angular part b must
satisfy 0 < beta_1 <= b(x) <= beta_2 < infinity on [-1, 1]; E(f) is the
kinetic energy of f and gamma is real (gamma = 0: no energy dependence).
"""

from __future__ import annotations

import math
from typing import Callable

import attrs
import numpy

from granframe import validators as check
from granframe.abc import CollisionKernel

#: Constant C of the review's numerical section: 1/(2 pi) in 2D, 1/(4 pi) in 3D
#: (C_0 = 1/(2 pi) in Test 1; |g|/(4 pi) for 3D hard spheres).
DEFAULT_CONSTANT = {2: 1.0 / (2.0 * math.pi), 3: 1.0 / (4.0 * math.pi)}

_ANGULAR_SAMPLES = numpy.linspace(-1.0, 1.0, 2001)


def _angular_validator(instance, attribute, value):
    owner = type(instance).__name__
    if value is None:
        return
    if not callable(value):
        check.reject(owner, attribute.name, value,
                     "must be None (isotropic, b = 1) or a callable b(cos_theta)", error=TypeError)
    try:
        with numpy.errstate(all="ignore"):
            samples = numpy.asarray(value(_ANGULAR_SAMPLES), dtype=float)
    except check.USER_CODE_FAILURES as exc:  # a user callable may fail in any way
        check.reject(owner, attribute.name, value, "must accept a NumPy array of cos(theta) "
                     f"in [-1, 1] (calling it raised {check.raised(exc)})", error=TypeError)
    samples = numpy.broadcast_to(samples, _ANGULAR_SAMPLES.shape)
    if not numpy.all(numpy.isfinite(samples)) or samples.min() <= 0.0:
        check.reject(owner, attribute.name, value,
                     "b(cos theta) must be finite and bounded below by a positive constant "
                     f"on [-1, 1] (found min {numpy.nanmin(samples):.3g})")


#: Largest kernel constant C accepted: C R^lambda b(cos theta) must not overflow.
_LARGEST_CONSTANT = 1e100


@attrs.frozen
class VariableHardSpheres(CollisionKernel):
    """Variable hard-sphere kernel B = C |g|^lambda b(cos theta) E^gamma.

    Parameters
    ----------
    exponent : float
        lambda in [0, 1]: 0 Maxwell molecules, 1 hard spheres.
    angular : callable or None
        Angular cross section b(cos theta), vectorised over a NumPy array;
        ``None`` means isotropic scattering, b = 1.
    energy_exponent : float
        gamma, real; the kernel is multiplied by E(f)^gamma.
    constant : float or None
        0 < C <= 1e100 (larger values overflow the kernel). ``None`` takes the review's
        numerical-section value for the grid's dimension: 1/(2 pi) in 2D and 1/(4 pi) in 3D.

    Notes
    -----
    [Carrillo, Hu, Ma, Rey, eq. (defHSkernelAnomalous) and (VHS)].
    """

    exponent: float = attrs.field(default=0.0, converter=check.to_float,
                                  validator=check.real(0.0, 1.0))
    angular: Callable | None = attrs.field(default=None, validator=_angular_validator)
    energy_exponent: float = attrs.field(default=0.0, converter=check.to_float,
                                         validator=check.real())
    constant: float | None = attrs.field(default=None, converter=check.to_float)

    @constant.validator
    def _check_constant(self, attribute, value):
        if value is not None:
            # bounded so that C |g|^lambda b stays finite for any representable grid
            check.real(0.0, _LARGEST_CONSTANT, lower_open=True)(self, attribute, value)

    @property
    def is_isotropic(self) -> bool:
        """True when b is constant (no sigma-quadrature needed)."""
        return self.angular is None

    @property
    def is_maxwellian(self) -> bool:
        """True for Maxwell pseudo-molecules (lambda = 0)."""
        return self.exponent == 0.0

    def prefactor(self, dimension: int) -> float:
        """The constant C used in dimension ``dimension``."""
        if dimension not in DEFAULT_CONSTANT:
            check.reject(type(self).__name__, "dimension", dimension, "must be 2 or 3")
        return DEFAULT_CONSTANT[dimension] if self.constant is None else self.constant

    def speed_part(self, speed, xp=numpy):
        """|g|^lambda (with 0^0 = 1)."""
        return xp.ones_like(speed) if self.exponent == 0.0 else xp.abs(speed) ** self.exponent

    def angular_part(self, cos_theta):
        """b(cos theta); 1 when isotropic."""
        if self.angular is None:
            return numpy.ones_like(numpy.asarray(cos_theta, dtype=float))
        return numpy.broadcast_to(numpy.asarray(self.angular(cos_theta), dtype=float),
                                  numpy.shape(cos_theta))

    @property
    def speed_exponent(self) -> float:
        """lambda: the speed part is the power law |g|^lambda."""
        return self.exponent

    def mean_speed_part(self, dimension: int, temperature: float) -> float:
        """<|g|^lambda> = (4T)^{lambda/2} Gamma((d+lambda)/2) / Gamma(d/2) for the relative
        speeds of a Maxwellian at temperature T (Maxwellian at 2T)."""
        lam = self.exponent
        return (4.0 * temperature) ** (lam / 2) * math.exp(
            math.lgamma((dimension + lam) / 2) - math.lgamma(dimension / 2))

    def mean_speed_parts(self, dimension: int, temperature, xp=numpy):
        """:meth:`mean_speed_part` at every temperature of an array (the same closed form)."""
        return self.mean_speed_part(dimension, temperature)


def maxwell_molecules(angular=None, energy_exponent=0.0, constant=None) -> VariableHardSpheres:
    """Maxwell pseudo-molecules, B = C b(cos theta) E^gamma (lambda = 0)."""
    return VariableHardSpheres(0.0, angular, energy_exponent, constant)


def hard_spheres(angular=None, energy_exponent=0.0, constant=None) -> VariableHardSpheres:
    """Hard spheres, B = C |g| b(cos theta) E^gamma (lambda = 1)."""
    return VariableHardSpheres(1.0, angular, energy_exponent, constant)
