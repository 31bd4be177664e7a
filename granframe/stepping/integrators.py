"""Time integrators for df/dt = N(t, f) + L f.

The equation is split into a part N treated explicitly (the collision term
Q(f, f)/eps) and a linear part L that is diagonal in Fourier space (the heat
bath tau Delta_v). Explicit Runge-Kutta schemes use the sum; the
integrating-factor scheme treats L exactly through exp(dt L). Schemes are
registered through ``granframe_register_time_integrators`` (the built-ins
in ``granframe._builtin``); the runner looks them up by name and never
branches on scheme names.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import ClassVar

import attrs
import numpy
from granframe.abc import AdaptiveIntegrator, Equation, Part, TimeIntegrator


def _fractions(rows):
    return tuple(tuple(float(Fraction(x)) for x in row) for row in rows)


@attrs.frozen
class Tableau:
    """Butcher tableau (A strictly lower triangular, weights b, nodes c = row sums of A)."""

    a: tuple
    b: tuple

    @property
    def c(self):
        return tuple(sum(row) for row in self.a)


def _combine(f, dt, weights, stages):
    """f + dt sum_j w_j k_j, skipping zero weights."""
    result = f
    for w, k in zip(weights, stages):
        if w != 0.0:
            result = result + (dt * w) * k
    return result


class ExplicitRungeKutta(TimeIntegrator):
    r"""Explicit Runge-Kutta method of a given tableau on N + L.

    .. math:: k_i = F\big(t + c_i \Delta t,\ f + \Delta t \sum_{j<i} a_{ij} k_j\big),\qquad
              f^{n+1} = f^n + \Delta t \sum_i b_i k_i,

    with F = N + L.
    """

    tableau: ClassVar[Tableau]

    def step(self, equation, t, f, dt):
        stages = []
        for row, c in zip(self.tableau.a, self.tableau.c):
            stages.append(equation(t + c * dt, _combine(f, dt, row, stages)))
        return _combine(f, dt, self.tableau.b, stages)


class ForwardEuler(ExplicitRungeKutta):
    """Forward Euler, order 1."""

    order = 1
    stability_interval = 2.0
    tableau = Tableau(a=((),), b=(1.0,))


class SSPRK2(ExplicitRungeKutta):
    """Strong-stability-preserving RK2 (Heun; Shu-Osher), order 2, SSP coefficient 1."""

    order = 2
    stability_interval = 2.0
    tableau = Tableau(a=_fractions([[], ["1"]]), b=(0.5, 0.5))


class SSPRK3(ExplicitRungeKutta):
    """Strong-stability-preserving RK3 of Shu and Osher (1988), order 3, SSP coefficient 1."""

    order = 3
    stability_interval = 2.5127   # |1 + z + z^2/2 + z^3/6| = 1 at z = -2.5127
    imaginary_interval = math.sqrt(3.0)
    tableau = Tableau(a=_fractions([[], ["1"], ["1/4", "1/4"]]),
                      b=tuple(float(Fraction(x)) for x in ("1/6", "1/6", "2/3")))


RK4_TABLEAU = Tableau(a=_fractions([[], ["1/2"], ["0", "1/2"], ["0", "0", "1"]]),
                      b=tuple(float(Fraction(x)) for x in ("1/6", "1/3", "1/3", "1/6")))


class RK4(ExplicitRungeKutta):
    """Classical fourth-order Runge-Kutta method (the review's time integrator)."""

    order = 4
    stability_interval = 2.7853   # |1 + z + ... + z^4/24| = 1 at z = -2.7853
    imaginary_interval = 2.0 * math.sqrt(2.0)
    tableau = RK4_TABLEAU


class IntegratingFactorRK4(TimeIntegrator):
    r"""Lawson's integrating-factor RK4: the linear part L = tau Delta is integrated exactly.

    With w(t) = e^{-tL} f(t), dw/dt = e^{-tL} N(t, e^{tL} w) is advanced by the
    classical RK4 tableau; in f:

    .. math:: Y_i = e^{c_i \Delta t L} f + \Delta t \sum_{j<i} a_{ij}
              e^{(c_i - c_j)\Delta t L} k_j,\quad k_i = N(t + c_i\Delta t, Y_i),\quad
              f^{n+1} = e^{\Delta t L} f + \Delta t \sum_i b_i e^{(1-c_i)\Delta t L} k_i .

    Order 4; exact for df/dt = L f, so the heat bath sets no step-size limit.
    Reference: J. D. Lawson, SIAM J. Numer. Anal. 4 (1967).
    """

    order = 4
    explicit_parts = frozenset({Part.NONLINEAR, Part.DRIFT})
    stability_interval = 2.7853
    imaginary_interval = 2.0 * math.sqrt(2.0)
    tableau = RK4_TABLEAU

    def step(self, equation, t, f, dt):
        a, b, c = self.tableau.a, self.tableau.b, self.tableau.c
        propagated = {}   # e^{c dt L} f for each distinct node c (1/2 and 1 are used twice)

        def propagate_f(node):
            if node not in propagated:
                propagated[node] = equation.propagate(f, node * dt)
            return propagated[node]

        stages = []
        for i, row in enumerate(a):
            y = propagate_f(c[i])
            for j, w in enumerate(row):
                if w != 0.0:
                    y = y + (dt * w) * equation.propagate(stages[j], (c[i] - c[j]) * dt)
            stages.append(equation.nonlinear(t + c[i] * dt, y))
        result = propagate_f(1.0)
        for i, w in enumerate(b):
            result = result + (dt * w) * equation.propagate(stages[i], (1.0 - c[i]) * dt)
        return result


class DormandPrince54(AdaptiveIntegrator):
    """Dormand-Prince 5(4) embedded pair, first-same-as-last (6 evaluations per accepted step).

    Reference: J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980).
    """

    order = 5
    embedded_order = 4
    _b = ("35/384", "0", "500/1113", "125/192", "-2187/6784", "11/84", "0")
    _b_embedded = ("5179/57600", "0", "7571/16695", "393/640", "-92097/339200", "187/2100",
                   "1/40")
    tableau = Tableau(
        a=_fractions([[], ["1/5"], ["3/40", "9/40"], ["44/45", "-56/15", "32/9"],
                      ["19372/6561", "-25360/2187", "64448/6561", "-212/729"],
                      ["9017/3168", "-355/33", "46732/5247", "49/176", "-5103/18656"],
                      _b[:6]]),   # first same as last: the last row is b
        b=_fractions([_b])[0])
    #: b - b_embedded, the weights of the error estimate
    error_weights = tuple(float(Fraction(x) - Fraction(y)) for x, y in zip(_b, _b_embedded))

    def __init__(self):
        self._last = None       # (f, t, F(t, f)): the first stage, known when f is
        self._candidate = None  # the same for the last attempt's new solution

    def attempt(self, equation, t, f, dt):
        stages = []
        for i, (row, c) in enumerate(zip(self.tableau.a, self.tableau.c)):
            if i == 0 and self._last is not None and self._last[0] is f and self._last[1] == t:
                stages.append(self._last[2])
                continue
            y = _combine(f, dt, row, stages)
            stages.append(equation(t + c * dt, y))
            if i == 0:
                self._last = (f, t, stages[0])
        # the last row equals b: its stage point y is the new solution, its stage F(t+dt, y)
        self._candidate = (y, t + dt, stages[-1])
        error = dt * self.error_weights[0] * stages[0]
        error = _combine(error, dt, self.error_weights[1:], stages[1:])
        return y, error

    def accept(self):
        """Tell the scheme its last attempt was accepted (its last stage starts the next step)."""
        self._last = self._candidate


def _is_zero(value) -> bool:
    """``value`` is the number 0 (a relaxation rate given per distribution is an array)."""
    return numpy.ndim(value) == 0 and value == 0.0


class PenalisedIMEX(TimeIntegrator):
    r"""Implicit-explicit Runge-Kutta with the BGK penalisation of Filbet & Jin (2010).

    The stiff part N = Q/eps is split as N = (N - P) + P with the relaxation
    P(f) = r (M[f] - f) of :meth:`Equation.relaxation`: N - P explicitly, P
    implicitly. Stage i of the pair (A_E, b_E), (A_I, b_I):

    .. math:: g_i = f^n + \Delta t \sum_{j<i} (a^E_{ij} K^E_j + a^I_{ij} K^I_j),\qquad
              F_i = \frac{g_i + a^I_{ii}\Delta t\, r\, M[g_i]}{1 + a^I_{ii}\Delta t\, r},

    K^I_i = r (M[F_i] - F_i), K^E_i = N(F_i) - K^I_i, f^{n+1} = f^n + dt sum_i
    (b^E_i K^E_i + b^I_i K^I_i). Since M[F_i] = M[g_i], every stage is explicit.
    The linear part L (the heat bath) is split off and integrated exactly:
    Strang splitting e^{dt L/2} (IMEX step) e^{dt L/2} for the second-order
    scheme, Lie splitting (IMEX step) e^{dt L} for the first-order one.

    As eps -> 0 the implicit part relaxes f to M[f] in one step: the scheme is
    stable for dt >> eps (asymptotic preserving), where explicit schemes need
    dt = O(eps). What stays explicit is N - P; for the inelastic operator the
    energy dissipation (rate (1-e^2) rho / (4 eps) for Maxwell molecules) is in
    it and keeps its own, much milder, step limit (docs/stability.md).

    Reference: F. Filbet, S. Jin, "A class of asymptotic-preserving schemes for
    kinetic equations and related problems with stiff sources", J. Comput. Phys.
    229 (2010) 7625-7648.
    """

    explicit: ClassVar[Tableau]
    implicit: ClassVar[tuple]      # (A_I rows including the diagonal, b_I)
    strang: ClassVar[bool]
    # relaxation is implicit and the heat bath exact: only the energy dissipation, which the
    # penalisation conserves, is explicit (forward Euler / the ARS explicit part: [-2, 0]),
    # and a drift term (neither is stable on the imaginary axis)
    explicit_parts = frozenset({Part.DISSIPATION, Part.DRIFT})
    stability_interval = 2.0

    def _imex(self, equation, t, f, dt):
        a_e, b_e = self.explicit.a, self.explicit.b
        a_i, b_i = self.implicit
        c = self.explicit.c
        stages = len(b_e)
        # K^E_i is needed only where a later stage or the update uses it
        needed = [b_e[i] != 0.0 or any(a_e[k][i] != 0.0 for k in range(i + 1, stages))
                  for i in range(stages)]
        k_e, k_i = [], []
        for i in range(stages):
            g = f
            for j in range(i):
                for w, k in ((a_e[i][j], k_e[j]), (a_i[i][j], k_i[j])):
                    if w != 0.0 and k is not None:
                        g = g + (dt * w) * k
            rate, target = equation.relaxation(g)   # a number, or one per distribution
            diagonal = a_i[i][i] * dt * rate
            stage = g if _is_zero(diagonal) else (g + diagonal * target) * (1.0 / (1.0 + diagonal))
            k_i.append(None if _is_zero(rate) else rate * (target - stage))
            if needed[i]:
                k = equation.nonlinear(t + c[i] * dt, stage)
                k_e.append(k - k_i[i] if k_i[i] is not None else k)
            else:
                k_e.append(None)
        result = f
        for weights, ks in ((b_e, k_e), (b_i, k_i)):
            for w, k in zip(weights, ks):
                if w != 0.0 and k is not None:
                    result = result + (dt * w) * k
        return result

    def step(self, equation, t, f, dt):
        if self.strang:
            half = equation.propagate(f, 0.5 * dt)
            return equation.propagate(self._imex(equation, t, half, dt), 0.5 * dt)
        return equation.propagate(self._imex(equation, t, f, dt), dt)


class PenalisedEuler(PenalisedIMEX):
    """First-order penalised scheme of Filbet & Jin: forward Euler on Q - P, backward
    Euler on P, Lie splitting for the heat bath (one collision evaluation per step)."""

    order = 1
    explicit = Tableau(a=((), (1.0,)), b=(1.0, 0.0))
    implicit = (((0.0, 0.0), (0.0, 1.0)), (0.0, 1.0))
    strang = False


_GAMMA = 1.0 - 1.0 / math.sqrt(2.0)
_DELTA = 1.0 - 1.0 / (2.0 * _GAMMA)


class PenalisedARS222(PenalisedIMEX):
    """Second-order penalised scheme: the stiffly accurate, L-stable IMEX pair ARS(2,2,2)
    (two collision evaluations per step), Strang splitting for the heat bath.

    Reference: U. M. Ascher, S. J. Ruuth, R. J. Spiteri, Appl. Numer. Math. 25 (1997),
    section 2.6, with gamma = 1 - 1/sqrt 2, delta = 1 - 1/(2 gamma).
    """

    order = 2
    explicit = Tableau(a=((), (_GAMMA,), (_DELTA, 1.0 - _DELTA)), b=(_DELTA, 1.0 - _DELTA, 0.0))
    implicit = (((0.0, 0.0, 0.0), (0.0, _GAMMA, 0.0), (0.0, 1.0 - _GAMMA, _GAMMA)),
                (0.0, 1.0 - _GAMMA, _GAMMA))
    strang = True


class EquilibriumProjection(TimeIntegrator):
    r"""The eps -> 0 limit of the penalised schemes: f relaxed to its local equilibrium,

    .. math:: f^{n+1} = \mathcal M[f^n],

    the equilibrium of :meth:`Equation.relaxation` (for the space equation the discrete
    Maxwellian of every cell's grid mass, momentum and energy). Between transport steps
    this is the kinetic scheme for the Euler equations of the velocity grid (the
    kinetic flux-vector splitting: B. Perthame, SIAM J. Numer. Anal. 29 (1992) 1-19;
    S. M. Deshpande, NASA TM-88321 (1986)): the reference a penalised run converges to
    as eps -> 0 with the same transport. Distributions without an equilibrium (rate 0:
    no positive mass or temperature) are left as they are. Not a scheme for
    d f/dt = N(f) at finite eps, so not registered among the run's integrators.
    """

    order = 1
    explicit_parts = frozenset()

    def step(self, equation, t, f, dt):
        rate, target = equation.relaxation(f)
        if _is_zero(rate):
            return f
        xp = equation.operator.backend.xp
        return xp.where(xp.asarray(rate) > 0.0, target, f)


class StepSizeError(RuntimeError):
    """The adaptive step size fell to round-off level (stiffness beyond the scheme, or a blow-up)."""


@attrs.frozen
class StepController:
    r"""Elementary step-size control for an :class:`AdaptiveIntegrator`.

    The scaled error of an attempt is
    err = max|E| / (tolerance * max(max|f^n|, max|f^{n+1}|)); the step is
    accepted when err <= 1, and the next step is
    dt * min(growth, max(shrink, safety * err^{-1/(q+1)})) with q the embedded order
    [Hairer, Norsett, Wanner, Solving ODEs I, section II.4].
    """

    tolerance: float
    safety: float = 0.9
    shrink: float = 0.2
    growth: float = 5.0

    def scaled_error(self, xp, f, f_new, error) -> float:
        scale = max(float(xp.max(xp.abs(f))), float(xp.max(xp.abs(f_new))))
        return float(xp.max(xp.abs(error))) / (self.tolerance * scale)

    def next_step(self, dt: float, err: float, embedded_order: int) -> float:
        if not math.isfinite(err):
            return dt * self.shrink
        factor = self.growth if err == 0.0 else self.safety * err ** (-1.0 / (embedded_order + 1))
        return dt * min(self.growth, max(self.shrink, factor))

    def advance(self, integrator: AdaptiveIntegrator, equation: Equation, t: float, f,
                dt: float, target: float, xp):
        """One accepted step from t, at most to ``target`` (landed on exactly).

        Returns ``(f_new, t_new, dt_taken, dt_next)``; rejected attempts are
        retried with smaller steps, and a step below round-off raises
        :class:`StepSizeError`.
        """
        proposed = dt
        while True:
            dt = min(dt, target - t)
            if dt <= 1e-14 * max(1.0, abs(t)):
                raise StepSizeError(f"the adaptive step size fell to {dt:.3g} (stiffness beyond "
                                    "the scheme's stability, or a blow-up)")
            f_new, error = integrator.attempt(equation, t, f, dt)
            err = self.scaled_error(xp, f, f_new, error)
            dt_next = self.next_step(dt, err, integrator.embedded_order)
            if err <= 1.0:
                integrator.accept()
                t_new = target if target - (t + dt) <= 1e-12 * max(1.0, abs(target)) else t + dt
                # a step shortened to land on an output says nothing against the proposed one
                return f_new, t_new, dt, max(dt_next, proposed) if dt < proposed else dt_next
            dt = dt_next
