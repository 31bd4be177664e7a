"""Hypothesis strategies for the conformance kit: valid distributions on a velocity grid.

A valid f is positive, finite and smooth enough for the grid: a sum of one to three
Maxwellians whose temperatures and mean velocities keep them resolved on the grid
(temperatures between 0.4 and 0.9 of the grid's ``(support_radius / 2)^2``, drifts within
a tenth of the support), so that spectral operators see their design accuracy.
"""

from __future__ import annotations

import numpy
from hypothesis import strategies as st


@st.composite
def maxwellian_parameters(draw, dimension: int, support_radius: float):
    """(density, velocity, temperature) of one resolved Maxwellian."""
    scale = (support_radius / 2.0) ** 2
    density = draw(st.floats(0.2, 2.0))
    temperature = scale * draw(st.floats(0.4, 0.9))
    drift = 0.1 * support_radius
    velocity = draw(st.lists(st.floats(-drift, drift), min_size=dimension,
                             max_size=dimension))
    return density, velocity, temperature


@st.composite
def distributions(draw, grid, max_components: int = 3):
    """A valid f on ``grid`` (a NumPy array of ``grid.shape``): a sum of Maxwellians."""
    components = draw(st.lists(maxwellian_parameters(grid.dimension, grid.support_radius),
                               min_size=1, max_size=max_components))
    return sum(grid.maxwellian(density, numpy.array(velocity), temperature)
               for density, velocity, temperature in components)


def distribution_stacks(grid, size: int = 3):
    """``size`` valid distributions stacked along a new leading axis."""
    return st.lists(distributions(grid), min_size=size, max_size=size).map(numpy.stack)
