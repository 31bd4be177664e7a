r"""d_t f + v_1 d_x f = Q(f, f)/eps + tau Delta_v f, split into transport and collisions.

One step of length dt is Strang's splitting (G. Strang, SIAM J. Numer. Anal. 5 (1968)
506-517)

.. math:: f^{n+1} = \mathcal T_{\Delta t/2}\, \mathcal C_{\Delta t}\, \mathcal T_{\Delta t/2}\, f^n,

second order when both parts are: T is the transport sub-step
(:mod:`granframe.space.transport`, three-stage SSP Runge-Kutta) and C one step of the
run's time integrator on the space-homogeneous equation d_t f = Q(f, f)/eps + tau Delta_v f
(:class:`~granframe.equations.homogeneous.HomogeneousBoltzmann` on the batch of cells)
in every cell at once. Each stage of C is one batched call of the collision operator on
all cells (f of shape (blocks, block_cells, *grid.shape)). With a penalised integrator
(``penalised_euler``, ``penalised_ars222``) the collision step is stable for any dt/eps
(asymptotic preserving, Filbet & Jin 2010), so dt is set by the transport's CFL limit
alone; an explicit integrator keeps its own limit O(eps).
"""

from __future__ import annotations

from granframe.space.conserving import conserving_step


class SingleModel:
    """The collision stage of a run with one collision model: one step of the run's time
    integrator on its equation in every cell at once, the conserved cell moments set back
    against round-off (:func:`~granframe.space.conserving.conserving_step`)."""

    def __init__(self, integrator, equation):
        self.integrator, self.equation = integrator, equation

    def apply(self, inner, t: float, dt: float) -> None:
        """Advance the cells ``inner`` (blocks, block_cells, *grid.shape), in place."""
        inner[...] = conserving_step(self.equation, self.integrator, t, inner, dt)


class LevelledModels:
    """The collision stage of a run with a hierarchy of collision models: every cell at
    its own level (:class:`~granframe.space.hierarchy.HybridCollisions`)."""

    def __init__(self, hierarchy):
        self.hierarchy = hierarchy

    def apply(self, inner, t: float, dt: float) -> None:
        """Advance the cells ``inner`` (blocks, block_cells, *grid.shape), in place."""
        cells = inner.reshape((-1,) + inner.shape[2:])
        inner[...] = self.hierarchy.advance(cells, t, dt).reshape(inner.shape)


class FreeFlight:
    """The collision stage of a collisionless gas: nothing happens."""

    def apply(self, inner, t: float, dt: float) -> None:
        """Leave the cells ``inner`` as they are."""


class SplitStep:
    """One Strang step T(dt/2) C(dt) T(dt/2) on a block array (see the module notes).

    The time integrator of a space problem: ``step(equation, t, array, dt)``. ``collide``
    is C, the collision stage of every owned cell: :class:`SingleModel` (one model, the
    run's equation and integrator), :class:`LevelledModels` (a hierarchy, every cell at
    its own level) or :class:`FreeFlight` (a collisionless gas), all with
    ``apply(inner, t, dt)``. The walls see the time of each transport stage.
    ``rescaling``: the :class:`~granframe.equations.rescaled.Rescaling` of a rescaled run,
    whose transport over a half step of s is that of
    :meth:`~granframe.equations.rescaled.Rescaling.transport_time`.
    """

    adaptive = False

    def __init__(self, collide, transport, rescaling=None):
        self.collide, self.transport, self.rescaling = collide, transport, rescaling

    def transport_stage(self, array, t: float, duration: float) -> None:
        """T(duration) from t, in place: the transport over ``duration`` of s in a rescaled
        run (:meth:`~granframe.equations.rescaled.Rescaling.transport_time`)."""
        if self.rescaling is not None:
            duration = self.rescaling.transport_time(t, duration)
        self.transport.advance(array, duration, t)

    def collision_stage(self, array, t: float, dt: float) -> None:
        """C(dt) from t on the owned cells of ``array``, in place."""
        self.collide.apply(self.transport.domain.interior(array), t, dt)

    def step(self, equation, t, array, dt):
        half = 0.5 * dt
        self.transport_stage(array, t, half)
        self.collision_stage(array, t, dt)
        self.transport_stage(array, t + half, half)
        return array
