r"""Two patterns of the collision step of a space run, written once.

- :func:`conserving_step`: one step of a time integrator on a
  :class:`~granframe.space.collisions.CellCollisions` equation with the cell moments it
  conserves set back against round-off,

  .. math:: f^{n+1} = R\bigl(S_{\Delta t}(f^n);\ m(f^n)\bigr),

  m the grid mass, momentum and second moment of every cell
  (:meth:`~granframe.space.collisions.CellCollisions.conserved`), S the integrator's step
  and R :meth:`~granframe.space.collisions.CellCollisions.restore`;
- :func:`guard_moments`: the moments of every cell with the cells that have no
  equilibrium (rho or T not positive and finite) replaced by a harmless standard state,
  rho = T = E = 1 and u = 0, so that a division by rho, a power of T or a discrete
  Maxwellian of the batch stays finite there while ``valid`` says which values mean
  something. Everything on the arrays' device, no transfer.
"""

from __future__ import annotations

import attrs


def conserving_step(equation, integrator, t: float, f, dt: float):
    r"""f after one step of ``integrator`` on ``equation`` from t to t + dt, with the cell
    moments in ``equation.invariants`` restored to their values before the step:

    .. math:: f \leftarrow R\bigl(S_{\Delta t}(f);\ (\rho, J, S)(f)\bigr),

    (:meth:`~granframe.space.collisions.CellCollisions.restore`); without invariants the
    integrator's step as it is.

    Parameters
    ----------
    equation : CellCollisions
        Has ``invariants``, ``conserved(f)`` and ``restore(f, before)``.
    integrator : TimeIntegrator
        Has ``step(equation, t, f, dt)``.
    t, dt : float
    f : array (..., *grid.shape)
        On the equation's backend.
    """
    before = equation.conserved(f) if equation.invariants else None
    return equation.restore(integrator.step(equation, t, f, dt), before)


@attrs.frozen
class GuardedMoments:
    r"""The moments of a batch of cells where they describe an equilibrium, a standard
    state elsewhere (:func:`guard_moments`); arrays (cells,) and (cells, d) on the device.

    Attributes
    ----------
    valid : boolean array
        rho and T positive and finite (and the ``where`` of :func:`guard_moments`).
    density, temperature : array
        rho and T where ``valid``, 1 elsewhere.
    velocity : array (cells, d)
        u where ``valid``, 0 elsewhere.
    energy : array or None
        E = int |v|^2/2 f where ``valid`` and E > 0, 1 elsewhere.
    second : array or None
        The second moment S = 2E where ``valid``, d (that of rho = T = 1, u = 0)
        elsewhere.
    """

    valid: object
    density: object
    velocity: object
    temperature: object
    energy: object
    second: object

    @property
    def momentum(self):
        """J = rho u of every cell (cells, d): 0 where not ``valid``."""
        return self.density[:, None] * self.velocity


def guard_moments(density, velocity, temperature, energy, xp,
                  where=None) -> GuardedMoments:
    r"""The guarded moments of every cell (:class:`GuardedMoments`):

    .. math:: \text{valid} = (0 < \rho < \infty) \wedge (0 < T < \infty),\qquad
              \tilde\rho = \begin{cases}\rho & \text{valid}\\ 1\end{cases},\quad
              \tilde T = \begin{cases}T & \text{valid}\\ 1\end{cases},\quad
              \tilde u = \begin{cases}u & \text{valid}\\ 0\end{cases},

    E where valid and E > 0 (1 elsewhere) and S = 2E where valid (d elsewhere).

    Parameters
    ----------
    density, velocity, temperature, energy : arrays in ``xp``
        rho (cells,), u (cells, d), T and E (cells,), e.g. of
        :meth:`~granframe.velocity.moments.FieldMoments.primitives`; ``energy`` None: no
        ``energy`` and ``second`` (None).
    xp : module
        Their array namespace.
    where : boolean array, optional
        Cells to count as not valid besides (e.g. those whose discrete Maxwellian did not
        converge).
    """
    valid = (xp.isfinite(density) & (density > 0) & xp.isfinite(temperature)
             & (temperature > 0))
    if where is not None:
        valid = valid & where
    safe_t = xp.where(valid, temperature, 1.0)
    safe_e = second = None
    if energy is not None:
        safe_e = xp.where(valid & (energy > 0), energy, 1.0)
        second = xp.where(valid, 2.0 * energy, velocity.shape[1] * safe_t)
    return GuardedMoments(valid, xp.where(valid, density, 1.0),
                          xp.where(valid[:, None], velocity, 0.0), safe_t, safe_e, second)
