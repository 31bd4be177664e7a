"""The contracts of time stepping: the equation df/dt = N(t, f) + L f, the names of its
stiff parts, and the one-step time integrators (fixed and adaptive).

:mod:`granframe.equations` implements the equations, :mod:`granframe.stepping` the
integrators and the step limits read from the stiff parts. Imported from
:mod:`granframe.abc`.
"""

from __future__ import annotations

import abc
import enum
import math
from typing import ClassVar


# -- The stiff parts of an equation ---------------------------------------------------------


class Part(enum.StrEnum):
    """The names of an equation's stiff parts (:meth:`Equation.stiffness`,
    :attr:`TimeIntegrator.explicit_parts`, :mod:`granframe.stepping.stability`).

    A :class:`enum.StrEnum`: each member is its string (``Part.LINEAR == "linear"``, and it
    formats and is stored as ``"linear"``), so plain strings of the names keep working.
    """

    #: the heat bath tau Delta_v
    LINEAR = "linear"
    #: the collision term Q/eps
    NONLINEAR = "nonlinear"
    #: the energy dissipation of Q/eps (a part of the collision term)
    DISSIPATION = "dissipation"
    #: the drift of the rescaled formulation (an imaginary spectrum)
    DRIFT = "drift"


# -- Equations and time integrators --------------------------------------------------------

class Equation(abc.ABC):
    """df/dt = N(t, f) + L f with L linear and cheap to exponentiate."""

    @abc.abstractmethod
    def nonlinear(self, t: float, f):
        """N(t, f)."""

    @abc.abstractmethod
    def linear(self, f):
        """L f."""

    @abc.abstractmethod
    def propagate(self, f, dt: float):
        """exp(dt L) f."""

    def __call__(self, t: float, f):
        """The whole right-hand side N(t, f) + L f."""
        return self.nonlinear(t, f) + self.linear(f)

    def stiffness(self, f) -> dict:
        """Estimated spectral radii of the parts of the equation at f, by part name
        (``linear``, ``nonlinear``, ``dissipation``): what explicit step limits are
        computed from (:mod:`granframe.stepping.stability`). None known by default."""
        return {}

    def relaxation(self, f):
        r"""A relaxation P(f) = r (M[f] - f) that penalised schemes treat implicitly.

        Returns ``(r, M)``: a rate r >= 0 of the size of the stiff part's Lipschitz
        constant and a target M[f] that P leaves invariant, M[f + s (M[f] - f)] = M[f]
        for every s, so that the implicit stage f = g + a dt P(f) has the explicit
        solution (g + a dt r M[g]) / (1 + a dt r). The default, ``(0.0, f)``, has no
        penalisation: the penalised schemes are then their explicit parts.
        """
        return 0.0, f


class TimeIntegrator(abc.ABC):
    """One step f(t) -> f(t + dt) of a one-step method.

    Attributes
    ----------
    order : int
        Classical order p: the global error is O(dt^p).
    adaptive : bool
        True for schemes with an embedded error estimate
        (:class:`AdaptiveIntegrator`); the runner then controls the step.
    explicit_parts : frozenset of str
        Which stiff parts of an equation (:meth:`Equation.stiffness`) the scheme
        treats explicitly, so that dt rate must stay within ``stability_interval``.
    stability_interval : float
        Extent of the scheme's (explicit part's) stability region along the negative
        real axis: stable for dt lambda in [-stability_interval, 0].
    imaginary_interval : float
        Extent along the imaginary axis: stable for dt lambda in i[-b, b] with b this
        value; 0 for schemes unstable there at any step (forward Euler, two-stage
        second-order schemes). Transport terms (the drift of the rescaled
        formulation, :mod:`granframe.equations.rescaled`) have an imaginary spectrum.
    """

    order: ClassVar[int]
    adaptive: ClassVar[bool] = False
    explicit_parts: ClassVar[frozenset] = frozenset({Part.LINEAR, Part.NONLINEAR, Part.DRIFT})
    stability_interval: ClassVar[float] = math.inf
    imaginary_interval: ClassVar[float] = 0.0

    @abc.abstractmethod
    def step(self, equation: Equation, t: float, f, dt: float):
        """Return f(t + dt); ``f`` is not modified."""


class AdaptiveIntegrator(TimeIntegrator):
    """A scheme with an embedded lower-order solution for step-size control.

    Attributes
    ----------
    embedded_order : int
        Order q of the embedded solution; the error estimate is O(dt^{q+1}).
    """

    adaptive: ClassVar[bool] = True
    embedded_order: ClassVar[int]

    @abc.abstractmethod
    def attempt(self, equation: Equation, t: float, f, dt: float):
        """Return ``(f_new, error)``: the step of order p and the difference to the embedded one."""

    def step(self, equation, t, f, dt):
        return self.attempt(equation, t, f, dt)[0]
