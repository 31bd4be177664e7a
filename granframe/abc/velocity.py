"""The contracts of the velocity discretisation: quadrature rules (radial, and on the
unit sphere S^{d-1}) and the velocity grid.

:mod:`granframe.velocity` implements them (:mod:`granframe.velocity.quadratures`,
:class:`granframe.velocity.grid.VelocityGrid`). Imported from :mod:`granframe.abc`.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import numpy

from granframe.rules import antipodal_pairs


# -- Quadratures ---------------------------------------------------------------------------

class Quadrature(abc.ABC):
    """A quadrature rule; radial rules provide ``rule(radius)``, surface rules subclass
    :class:`SurfaceQuadrature`.

    An implementation provides ``kind``, :attr:`degree` and :attr:`n_points`; a radial
    rule (``kind = "radial"``) provides ``rule(radius)``, the nodes and weights on
    [0, radius]. The framework checks a rule where it is built by name: finite nodes and
    weights, ``n_points`` of them, and for surface rules unit nodes and weights summing
    to |S^{d-1}|.

    Attributes
    ----------
    kind : {"radial", "circle", "sphere"}
        The domain: an interval [0, R], S^1, or S^2.
    degree : int
        Highest total degree of polynomials integrated exactly.
    n_points : int
        Number of nodes.
    """

    kind: ClassVar[str]

    @property
    @abc.abstractmethod
    def degree(self) -> int:
        """Highest total degree of polynomials the rule integrates exactly."""

    @property
    @abc.abstractmethod
    def n_points(self) -> int:
        """Number of nodes."""


class SurfaceQuadrature(Quadrature):
    """A rule on the unit sphere S^{d-1}: ``nodes()`` (M, d), ``weights()`` (M,).

    An implementation provides ``dimension`` and :meth:`_rule`, returning unit nodes of
    shape (M, d) and weights of shape (M,) that sum to |S^{d-1}| (2 pi, 4 pi).
    """

    #: Dimension d of the ambient space (2 for the circle, 3 for the sphere).
    dimension: ClassVar[int]

    def nodes(self):
        return self._rule()[0]

    def weights(self):
        return self._rule()[1]

    @property
    def is_antipodal(self) -> bool:
        """True when -ghat is a node of equal weight for every node ghat."""
        _, w_plus, w_minus = antipodal_pairs(*self._rule())
        return bool(numpy.allclose(w_plus, w_minus, rtol=1e-12, atol=0.0))

    @abc.abstractmethod
    def _rule(self):
        """``(nodes, weights)``: unit nodes (M, d) and weights (M,) summing to |S^{d-1}|."""


# -- Velocity grids ------------------------------------------------------------------------

class Grid(abc.ABC):
    """A velocity grid, what every ``grid`` argument of these contracts is:
    :class:`granframe.VelocityGrid` is the implementation.

    It declares no members: those of :class:`~granframe.velocity.grid.VelocityGrid` are the
    contract. It lets the core check a grid (:func:`~granframe.abc.check_arguments`) without
    importing the velocity layer, which is built on the core.
    """

    __slots__ = ()
