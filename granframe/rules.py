"""The numerics of quadrature rules, below the contracts that need them.

The defaults of :class:`granframe.abc.CollisionKernel` integrate with the Gauss-Legendre
and circle rules, :class:`granframe.abc.SurfaceQuadrature` pairs antipodal directions and
the registry's checks (:mod:`granframe.contract_checks`) need |S^{d-1}|. The validated,
registered rules of :mod:`granframe.velocity.quadratures` are built on these functions (and
re-export :func:`sphere_area` and :func:`antipodal_pairs`); living here, in the core, they
serve the contracts without an import of the velocity layer above them. Arguments are
not checked: the rules check theirs.
"""

from __future__ import annotations

import functools
import math

import numpy


def gauss_legendre(n_points: int, radius: float):
    """Nodes and weights of the ``n_points``-point Gauss-Legendre rule on [0, ``radius``]:
    rho_i = R (x_i + 1)/2, w_i = R w_i^GL / 2; exact for polynomials of degree 2n - 1."""
    x, w = legendre(n_points)
    return 0.5 * radius * (x + 1.0), 0.5 * radius * w


@functools.lru_cache(maxsize=32)
def legendre(n_points: int):
    """Nodes and weights of the ``n_points``-point Gauss-Legendre rule on [-1, 1],
    read-only: they are cached, and numpy's ``leggauss`` solves an n x n eigenproblem."""
    x, w = numpy.polynomial.legendre.leggauss(n_points)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


def circle_rule(n_points: int, phase: float = 0.0):
    """Unit nodes (M, 2) and weights (M,) of the equispaced rule on S^1: ghat_j = (cos
    phi_j, sin phi_j), phi_j = phase + 2 pi j/M, every weight 2 pi / M."""
    phi = phase + 2.0 * math.pi * numpy.arange(n_points) / n_points
    return (numpy.stack([numpy.cos(phi), numpy.sin(phi)], axis=1),
            numpy.full(n_points, 2.0 * math.pi / n_points))


def sphere_area(dimension: int) -> float:
    """|S^{d-1}| = 2 pi^{d/2} / Gamma(d/2)."""
    return 2.0 * math.pi ** (dimension / 2) / math.gamma(dimension / 2)


def antipodal_pairs(nodes, weights):
    """Group a rule's directions into pairs (ghat, -ghat).

    Returns representative directions (P, d) and the weights of ghat and of
    -ghat (zero when -ghat is not a node). The fast spectral method needs one
    transform per pair, so antipodal rules halve its work. Node i, in order, is a
    representative unless it was paired before; its partner is the node closest to -ghat_i
    when that matches -ghat_i to 1e-12 (``numpy.isclose``), found for all nodes at once
    from |ghat_i + ghat_j|^2 in blocks (Lebedev 131, 5810 nodes: about 1 s), else by a scan of
    the nodes not yet paired.
    """
    nodes = numpy.asarray(nodes, dtype=float)
    weights = numpy.asarray(weights, dtype=float)
    count = len(weights)
    squares = numpy.einsum("ij,ij->i", nodes, nodes)
    closest = numpy.empty(count, dtype=int)
    for start in range(0, count, 512):
        block = slice(start, min(start + 512, count))
        gap = squares[block, None] + squares[None, :] + 2.0 * (nodes[block] @ nodes.T)
        closest[block] = numpy.argmin(gap, axis=1)
    paired = numpy.zeros(count, dtype=bool)
    reps, w_plus, w_minus = [], [], []
    for i in range(count):
        if paired[i]:
            continue
        paired[i] = True
        j = int(closest[i])
        if paired[j] or not numpy.allclose(nodes[j], -nodes[i], atol=1e-12):
            j = next((k for k in range(i + 1, count) if not paired[k]
                      and numpy.allclose(nodes[k], -nodes[i], atol=1e-12)), None)
        reps.append(nodes[i])
        w_plus.append(weights[i])
        if j is None:
            w_minus.append(0.0)
        else:
            paired[j] = True
            w_minus.append(weights[j])
    return numpy.array(reps), numpy.array(w_plus), numpy.array(w_minus)
