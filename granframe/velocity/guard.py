r"""The moments of a batch of distributions with a guard where they describe no
equilibrium (:func:`guard_moments`): rho or T not positive and finite replaced by a
harmless standard state, rho = T = E = 1 and u = 0, so that a division by rho, a power of
T or a discrete Maxwellian of the batch stays finite there while ``valid`` says which
values mean something. The guard of the BGK targets and rates of the collision step and
of the fluid levels of a space run's hierarchy; on the arrays' device, no transfer.
"""

from __future__ import annotations

import attrs


@attrs.frozen
class GuardedMoments:
    r"""The moments of a batch of distributions (the cells of a space run) where they
    describe an equilibrium, a standard state elsewhere (:func:`guard_moments`); arrays
    (cells,) and (cells, d) on the device.

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
