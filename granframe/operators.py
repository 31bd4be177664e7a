"""Collision-operator interface.

An operator is built once for a velocity grid, a collision kernel, a
restitution law, its quadratures and an array backend (the expensive
precomputation happens here), then evaluated many times on f. Operators are
registered through ``granframe_register_collision_operators`` and built by
name with :func:`granframe.collision_operator`.
"""

from __future__ import annotations

import abc

from granframe import validators as check
from granframe.backends import ArrayBackend
from granframe.grid import VelocityGrid
from granframe.kernels import VariableHardSpheres
from granframe.restitution import RestitutionLaw


def check_arguments(owner: str, grid, kernel, restitution, backend) -> None:
    """Refuse arguments of the wrong kind (a kernel's name, None for the grid, ...), naming
    the parameter, before an operator uses them. A kernel is accepted by what it offers
    (docs/plugins.md: "an object like VariableHardSpheres")."""
    if not isinstance(grid, VelocityGrid):
        check.reject(owner, "grid", grid, "must be a granframe.VelocityGrid", error=TypeError)
    if not all(hasattr(kernel, a) for a in ("prefactor", "speed_part", "is_isotropic")):
        check.reject(owner, "kernel", kernel, "must be a collision kernel like "
                     "granframe.VariableHardSpheres, e.g. collision_kernel('maxwell')",
                     error=TypeError)
    if not isinstance(restitution, RestitutionLaw):
        check.reject(owner, "restitution", restitution, "must be a granframe.RestitutionLaw, "
                     "e.g. restitution_law('constant', value=0.5)", error=TypeError)
    if not isinstance(backend, ArrayBackend):
        check.reject(owner, "backend", backend, "must be a granframe.ArrayBackend, e.g. "
                     "array_backend('numpy')", error=TypeError)


class CollisionOperator(abc.ABC):
    """Q_I(f, f) on a fixed grid.

    Subclasses are constructed as ``Operator(grid, kernel, restitution,
    backend, **options)``, where ``options`` carry method-specific settings
    such as quadratures, and implement :meth:`__call__`. The arguments are checked
    (:func:`check_arguments`) under the owner name ``name``.
    """

    #: Name used in error messages (the registered name of the built-in operators).
    name: str = "collision operator"

    def __init__(self, grid: VelocityGrid, kernel: VariableHardSpheres,
                 restitution: RestitutionLaw, backend: ArrayBackend):
        check_arguments(self.name, grid, kernel, restitution, backend)
        self.grid = grid
        self.kernel = kernel
        self.restitution = restitution
        self.backend = backend

    @classmethod
    def estimate_memory(cls, grid, kernel, restitution, backend, **options) -> int | None:
        """Bytes the operator would hold for these arguments, found without allocating
        anything large; None when not known (the default). A run adds it to its own
        estimate before building anything (:mod:`granframe.memory`)."""
        return None

    @abc.abstractmethod
    def __call__(self, f):
        """Return Q_I(f, f) sampled on the grid, an array like ``f`` in ``backend.xp``."""
