r"""The choice of the level of every cell from its indicators
(:mod:`granframe.space.hierarchy`, "Which level a cell takes"): array operations over all
cells at once, in any array namespace (the backend's, so that the choice stays on the
device), with no loop over the cells.
"""

from __future__ import annotations

import math

import numpy


def choose_levels(previous, kappa, delta, realizable, thresholds, distances,
                  hysteresis: float, reach, periodic, xp=numpy, shape=None):
    r"""The level of every cell from its level ``previous`` and its indicators (see the
    package notes).

    For each level k >= 1 the cell is at least at k when

    .. math:: \kappa > \kappa_k\,s \quad\text{or}\quad \delta > \delta_k\,s,\qquad
              s = \begin{cases}h & \ell^{\rm prev} \ge k\\ 1\end{cases},

    (``thresholds[k-1]``, ``distances[k-1]``, h the ``hysteresis``); cells without an
    equilibrium (``realizable`` false) take the top level; then every cell lifts the cells
    within its ``reach`` to at least its own level (:func:`spread_levels`).

    Parameters
    ----------
    previous : integer array (cells,)
    kappa, delta : arrays (cells,)
        Finite (0 where not ``realizable``).
    realizable : boolean array (cells,)
    thresholds, distances : sequences of float
        One per level after the first.
    hysteresis : float
    reach : int or integer array (cells,)
        Cells on each side along every space axis (across the ends of a periodic one).
    periodic : bool or sequence of bool
        One per space axis.
    xp : module
        The array namespace of the arrays.
    shape : tuple of int, optional
        The cells along the space axes, (C,) (the default) or (C_x, C_y); the arrays hold
        them in C order (x slowest).

    Returns
    -------
    integer array (cells,)
    """
    top = len(thresholds)
    level = xp.zeros(previous.shape, dtype=xp.int64)
    for k in range(1, top + 1):
        scale = xp.where(previous >= k, hysteresis, 1.0)
        need = (kappa > thresholds[k - 1] * scale) | (delta > distances[k - 1] * scale)
        level = xp.where(need, k, level)
    level = xp.where(realizable, level, top)
    shape = tuple(previous.shape) if shape is None else tuple(shape)
    if getattr(reach, "ndim", 0):
        reach = reach.reshape(shape)
    return spread_levels(level.reshape(shape), reach, periodic, top, xp).reshape(-1)


def spread_levels(level, reach, periodic, top: int, xp=numpy):
    r"""Every cell lifted to the highest level of the cells that reach it:

    .. math:: \ell'_i = \max\bigl(\ell_i,\ \max\{\ell_j : |i_a - j_a| \le r_j
              \text{ on every axis } a\}\bigr),
              \qquad r_j = \max(\text{reach}_j, 0),

    i, j the cells' indices on the D space axes of ``level`` (shape (C_0, ..., C_{D-1})),
    |i_a - j_a| the distance across the ends of an axis ``periodic`` (one bool for all
    axes or one per axis): cell j reaches the box of side 2 r_j + 1 about it (r_j cut to
    C_a on axis a). For each level
    k = 1..``top`` the cells covered by the boxes of the cells at k or above are counted by
    a difference array: +-1 at the 2^D corners of each box, (j_a - r_j or j_a + r_j + 1 on
    each axis, the sign (-1) to the number of upper corners; D :func:`bincount` of the
    cells summed), whose cumulative sums along every axis are positive on the covered
    cells; a periodic axis is laid out three times, j_a shifted by C_a, and the three
    copies folded onto one. On an interval (D = 1) this is the two bincounts +1 at
    j - r_j, -1 at j + r_j + 1."""
    shape = tuple(level.shape)
    dimension = len(shape)
    periodic = ((bool(periodic),) * dimension if isinstance(periodic, (bool, numpy.bool_))
                else tuple(bool(p) for p in periodic))
    reach = xp.broadcast_to(xp.asarray(reach, dtype=xp.int64), shape).reshape(-1)
    bounds, spans = [], []
    for axis, (cells, wraps) in enumerate(zip(shape, periodic)):
        index = xp.broadcast_to(xp.arange(cells).reshape(
            (1,) * axis + (-1,) + (1,) * (dimension - 1 - axis)), shape).reshape(-1)
        radius = xp.clip(reach, 0, cells)
        start, stop = index - radius, index + radius + 1
        if wraps:
            start, stop, span = start + cells, stop + cells, 3 * cells
        else:
            start, stop, span = xp.maximum(start, 0), xp.minimum(stop, cells), cells
        bounds.append((start, stop))
        spans.append(span)
    sizes = [span + 1 for span in spans]
    strides = [math.prod(sizes[a + 1:]) for a in range(dimension)]
    corners = []
    for corner in numpy.ndindex(*(2,) * dimension):
        place = sum(bounds[a][c] * strides[a] for a, c in enumerate(corner))
        corners.append((place, -1.0 if sum(corner) % 2 else 1.0))
    widened = level
    for k in range(1, top + 1):
        sources = (level >= k).astype(float).reshape(-1)
        change = sum(sign * xp.bincount(place, weights=sources, minlength=math.prod(sizes))
                     for place, sign in corners)
        covered = change.reshape(sizes)
        for axis in range(dimension):
            covered = xp.cumsum(covered, axis=axis)
        covered = covered[tuple(slice(0, span) for span in spans)] > 0.5
        for axis, (cells, wraps) in enumerate(zip(shape, periodic)):
            if wraps:
                covered = covered.reshape(shape[:axis] + (3, cells) + covered.shape[axis + 1:]
                                          ).any(axis=axis)
        widened = xp.where(covered, xp.maximum(widened, k), widened)
    return widened
