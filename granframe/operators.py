"""Collision-operator interface.

An operator is built once for a velocity grid, a collision kernel, a
restitution law, its quadratures and an array backend (the expensive
precomputation happens here), then evaluated many times on f. Operators are
registered through ``granframe_register_collision_operators`` and built by
name with :func:`granframe.collision_operator`.
"""

from __future__ import annotations

import abc

from granframe.backends import ArrayBackend
from granframe.grid import VelocityGrid
from granframe.kernels import VariableHardSpheres
from granframe.restitution import RestitutionLaw


class CollisionOperator(abc.ABC):
    """Q_I(f, f) on a fixed grid.

    Subclasses are constructed as ``Operator(grid, kernel, restitution,
    backend, **options)``, where ``options`` carry method-specific settings
    such as quadratures, and implement :meth:`__call__`.
    """

    def __init__(self, grid: VelocityGrid, kernel: VariableHardSpheres,
                 restitution: RestitutionLaw, backend: ArrayBackend):
        self.grid = grid
        self.kernel = kernel
        self.restitution = restitution
        self.backend = backend

    @abc.abstractmethod
    def __call__(self, f):
        """Return Q_I(f, f) sampled on the grid, an array like ``f`` in ``backend.xp``."""
