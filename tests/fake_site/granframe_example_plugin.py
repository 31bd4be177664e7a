"""A third-party granframe plugin, installed only as a .dist-info on sys.path.

It adds one restitution law and one collision kernel, written exactly as
docs/plugins.md tells a stranger to write them.
"""

import math

import attrs
import numpy

import granframe
from granframe import validators
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


def forward_peaked(exponent=0.0, anisotropy=0.5):
    """VHS kernel with b(cos theta) = 1 + a cos theta, 0 <= a < 1."""
    return granframe.VariableHardSpheres(exponent=exponent,
                                         angular=lambda c: 1.0 + anisotropy * c)


@granframe.hookimpl
def granframe_register_restitution_laws(registry):
    registry.add("exponential_decay", ExponentialDecay)


@granframe.hookimpl
def granframe_register_collision_kernels(registry):
    registry.add("forward_peaked", forward_peaked)
