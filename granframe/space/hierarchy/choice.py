r"""The choice of the level of every cell from its indicators
(:mod:`granframe.space.hierarchy`, "Which level a cell takes"), on the host.
"""

from __future__ import annotations

import numpy


def choose_levels(previous, kappa, delta, realizable, thresholds, distances,
                  hysteresis: float, reach, periodic: bool):
    """The level of every cell from its level ``previous`` and its indicators (see the
    module notes): for each level k >= 1, the cell is at least at k when kappa exceeds
    ``thresholds[k-1]`` or delta exceeds ``distances[k-1]``, each threshold scaled by
    ``hysteresis`` for a cell already at k or above; cells without an equilibrium
    (``realizable`` false) take the top level; then every cell lifts the cells within its
    ``reach`` (cells each side: an integer, or one per cell; across the ends of a
    periodic interval) to at least its own level."""
    top = len(thresholds)
    level = numpy.zeros(len(previous), dtype=numpy.int64)
    for k in range(1, top + 1):
        scale = numpy.where(previous >= k, hysteresis, 1.0)
        need = (kappa > thresholds[k - 1] * scale) | (delta > distances[k - 1] * scale)
        level = numpy.where(need, k, level)
    level = numpy.where(realizable, level, top)
    cells = len(level)
    reach = numpy.broadcast_to(numpy.asarray(reach, dtype=numpy.int64), (cells,))
    widened = level.copy()
    for j in numpy.flatnonzero((level > 0) & (reach > 0)):
        r = int(min(reach[j], cells))
        if periodic:
            near = numpy.arange(j - r, j + r + 1) % cells
        else:
            near = numpy.arange(max(j - r, 0), min(j + r, cells - 1) + 1)
        widened[near] = numpy.maximum(widened[near], level[j])
    return widened
