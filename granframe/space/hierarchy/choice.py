r"""The choice of the level of every cell from its indicators
(:mod:`granframe.space.hierarchy`, "Which level a cell takes"): array operations over all
cells at once, in any array namespace (the backend's, so that the choice stays on the
device), with no loop over the cells.
"""

from __future__ import annotations

import numpy


def choose_levels(previous, kappa, delta, realizable, thresholds, distances,
                  hysteresis: float, reach, periodic: bool, xp=numpy):
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
        Cells on each side (across the ends of a periodic interval).
    periodic : bool
    xp : module
        The array namespace of the arrays.

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
    return spread_levels(level, reach, periodic, top, xp)


def spread_levels(level, reach, periodic: bool, top: int, xp=numpy):
    r"""Every cell lifted to the highest level of the cells that reach it:

    .. math:: \ell'_i = \max\bigl(\ell_i,\ \max\{\ell_j : |i - j| \le r_j\}\bigr),
              \qquad r_j = \min(\max(\text{reach}_j, 0), C),

    with |i - j| the distance across the ends of a ``periodic`` interval of C cells. For
    each level k = 1..``top`` the cells covered by the intervals [j - r_j, j + r_j] of the
    cells at k or above are counted by a difference array: +1 at j - r_j and -1 at
    j + r_j + 1 (two :func:`bincount` of the cells), whose cumulative sum is positive on
    the covered cells; a periodic interval is laid out three times, j shifted by C, and
    the three copies folded onto one."""
    cells = level.shape[0]
    radius = xp.clip(xp.broadcast_to(xp.asarray(reach, dtype=xp.int64), (cells,)), 0, cells)
    index = xp.arange(cells)
    start, stop = index - radius, index + radius + 1
    if periodic:
        start, stop, span = start + cells, stop + cells, 3 * cells
    else:
        start, stop, span = xp.maximum(start, 0), xp.minimum(stop, cells), cells
    widened = level
    for k in range(1, top + 1):
        sources = (level >= k).astype(float)
        change = (xp.bincount(start, weights=sources, minlength=span + 1)
                  - xp.bincount(stop, weights=sources, minlength=span + 1))
        covered = xp.cumsum(change)[:span] > 0.5
        if periodic:
            covered = covered.reshape(3, cells).any(axis=0)
        widened = xp.where(covered, xp.maximum(widened, k), widened)
    return widened
