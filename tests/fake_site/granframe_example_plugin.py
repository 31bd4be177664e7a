"""A third-party granframe plugin, installed only as a .dist-info on sys.path.

It adds one restitution law and two collision kernels (one of them not a power law),
written exactly as docs/plugins.md tells a stranger to write them.
"""

import math

import attrs
import numpy

import granframe
from granframe import validators
from granframe.abc import CollisionKernel
from granframe.model.restitution import RestitutionLaw


@attrs.frozen
class ExponentialDecay(RestitutionLaw):
    """e(r) = e_min + (1 - e_min) exp(-r / scale): elastic at rest, e_min when fast."""

    minimum: float = attrs.field(converter=validators.to_float,
                                 validator=validators.real(0.0, 1.0))
    scale: float = attrs.field(default=1.0, converter=validators.to_float,
                               validator=validators.real(0.0, math.inf, lower_open=True))

    def _evaluate(self, speed):
        return self.minimum + (1.0 - self.minimum) * numpy.exp(-speed / self.scale)


@attrs.frozen
class SoftenedHardSpheres(CollisionKernel):
    """B = C |g|^lambda / (1 + |g|/g0): a power law at low speed, softened above g0."""

    exponent: float = attrs.field(default=1.0, converter=validators.to_float,
                                  validator=validators.real(0.0, 2.0))
    speed_scale: float = attrs.field(default=1.0, converter=validators.to_float,
                                     validator=validators.real(0.0, math.inf, lower_open=True))

    def prefactor(self, dimension):
        return 1.0 / (2.0 * math.pi) if dimension == 2 else 1.0 / (4.0 * math.pi)

    def speed_part(self, speed, xp=numpy):
        r = xp.abs(speed)
        return r ** self.exponent / (1.0 + r / self.speed_scale)

    @property
    def speed_exponent(self):
        # s(r) <= max(1, g0) max(1, r)^(lambda - 1)
        return self.exponent - 1.0


def forward_peaked(exponent=0.0, anisotropy=0.5):
    """VHS kernel with b(cos theta) = 1 + a cos theta, 0 <= a < 1."""
    return granframe.VariableHardSpheres(exponent=exponent,
                                         angular=lambda c: 1.0 + anisotropy * c)


@granframe.hookimpl
def granframe_register_restitution_laws(registry):
    registry.add("exponential_decay", ExponentialDecay,
                 examples=[{"minimum": 0.4}, {"minimum": 0.0, "scale": 3.0}])


@granframe.hookimpl
def granframe_register_collision_kernels(registry):
    registry.add("forward_peaked", forward_peaked)
    registry.add("softened_hard_spheres", SoftenedHardSpheres,
                 examples=[{}, {"exponent": 2.0, "speed_scale": 0.5}])
