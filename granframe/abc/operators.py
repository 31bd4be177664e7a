"""The contract of a collision operator Q_I(f, f) on a fixed grid, and the checks of the
grid, kernel, restitution law and backend it is built from.

The built-in operators are the plugin ``granframe_spectral``'s; the checks refuse an
argument of the wrong contract (:mod:`granframe.abc.model`, :mod:`granframe.abc.velocity`,
:mod:`granframe.abc.arrays`) before an operator uses it. Imported from :mod:`granframe.abc`.
"""

from __future__ import annotations

import abc

import numpy

from granframe import validators as check
from granframe.abc.arrays import ArrayBackend
from granframe.abc.model import CollisionKernel, RestitutionLaw
from granframe.abc.velocity import Grid


def check_arguments(owner: str, grid, kernel, restitution, backend) -> None:
    """Refuse arguments of the wrong kind (a kernel's name, None for the grid, ...), naming
    the parameter, before an operator uses them. A kernel is accepted by what it offers
    (the kernel against :class:`CollisionKernel`, the restitution law by
    :func:`check_restitution`)."""
    if not isinstance(grid, Grid):
        check.reject(owner, "grid", grid, "must be a granframe.VelocityGrid", error=TypeError)
    if not isinstance(kernel, CollisionKernel):
        check.reject(owner, "kernel", kernel, "must be a collision kernel (a "
                     "granframe.CollisionKernel), e.g. collision_kernel('maxwell')", error=TypeError)
    if not isinstance(restitution, RestitutionLaw):
        check.reject(owner, "restitution", restitution, "must be a granframe.RestitutionLaw, "
                     "e.g. restitution_law('constant', value=0.5)", error=TypeError)
    if not isinstance(backend, ArrayBackend):
        check.reject(owner, "backend", backend, "must be a granframe.ArrayBackend, e.g. "
                     "array_backend('numpy')", error=TypeError)
    check_restitution(owner, restitution, grid.truncation_radius)


def check_restitution(owner: str, restitution: RestitutionLaw, radius: float) -> None:
    """Refuse a restitution law whose values at a few speeds on [0, ``radius``] (the
    relative speeds an operator meets) are not finite, outside [0, 1] or not of the
    speeds' shape (e.g. a scalar), naming the law and the first bad value."""
    speeds = numpy.linspace(0.0, radius, 9)
    values = numpy.asarray(restitution(speeds))
    name = type(restitution).__name__
    if values.shape != speeds.shape:
        check.reject(owner, "restitution", restitution,
                     f"{name} must return an array of the speeds' shape {speeds.shape}, "
                     f"got shape {values.shape}")
    bad = ~(numpy.isfinite(values) & (values >= 0.0) & (values <= 1.0))
    if numpy.any(bad):
        i = int(numpy.argmax(bad))
        check.reject(owner, "restitution", restitution,
                     f"{name} must take values in [0, 1]; e({speeds[i]:.4g}) = {float(values[i])!r}")


class CollisionOperator(abc.ABC):
    """Q_I(f, f) on a fixed grid.

    Subclasses are constructed as ``Operator(grid, kernel, restitution,
    backend, **options)``, where ``options`` carry method-specific settings
    such as quadratures, and implement :meth:`__call__`. The arguments are checked
    (:func:`check_arguments`) under the owner name ``name``.
    """

    #: Name used in error messages (the registered name of the built-in operators).
    name: str = "collision operator"

    def __init__(self, grid, kernel,
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
