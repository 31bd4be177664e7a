r"""The collision step's pattern conserve, step, restore, written once
(:func:`conserving_step`): one step of a time integrator on a
:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann` equation with the cell moments it
conserves set back against round-off,

.. math:: f^{n+1} = R\bigl(S_{\Delta t}(f^n);\ m(f^n)\bigr),

m the grid mass, momentum and second moment of every cell
(:meth:`~granframe.equations.homogeneous.HomogeneousBoltzmann.conserved`), S the
integrator's step and R :meth:`~granframe.equations.homogeneous.HomogeneousBoltzmann.restore`;
on the arrays' device, no transfer.
"""

from __future__ import annotations


def conserving_step(equation, integrator, t: float, f, dt: float):
    r"""f after one step of ``integrator`` on ``equation`` from t to t + dt, with the cell
    moments in ``equation.invariants`` restored to their values before the step:

    .. math:: f \leftarrow R\bigl(S_{\Delta t}(f);\ (\rho, J, S)(f)\bigr),

    (:meth:`~granframe.equations.homogeneous.HomogeneousBoltzmann.restore`); without
    invariants the integrator's step as it is.

    Parameters
    ----------
    equation : HomogeneousBoltzmann
        E.g. :class:`~granframe.equations.homogeneous.HomogeneousBoltzmann`; has ``invariants``,
        ``conserved(f)`` and ``restore(f, before)``.
    integrator : TimeIntegrator
        Has ``step(equation, t, f, dt)``.
    t, dt : float
    f : array (..., *grid.shape)
        On the equation's backend.
    """
    before = equation.conserved(f) if equation.invariants else None
    return equation.restore(integrator.step(equation, t, f, dt), before)
