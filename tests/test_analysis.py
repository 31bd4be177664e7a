"""The fits the studies report: decay rates and tail exponents, on data with known answers."""

import numpy
import pytest

import granframe as gf
from granframe.tools.analysis import exponential_rate, relative_entropy, tail_exponent


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0])
def test_tail_exponent_of_a_symmetric_grid_slice(alpha):
    v = gf.VelocityGrid(2, 128, 10.0).points()        # mirrored points differ by round-off
    f = 3.0 * numpy.exp(-0.7 * numpy.abs(v) ** alpha)
    fitted, stderr = tail_exponent(numpy.abs(v), f, (3.0, 12.0))
    assert fitted == pytest.approx(alpha, abs=1e-3) and stderr < 1e-3   # O(h^2) differences


def test_tail_exponent_sees_a_lower_order_factor_as_an_uncertainty():
    """f = |v|^2 exp(-|v|): the prefactor biases alpha; the fit's error bar must show it."""
    v = numpy.linspace(0.5, 20, 400)
    alpha, stderr = tail_exponent(v, v ** 2 * numpy.exp(-v), (4.0, 18.0))
    assert abs(alpha - 1.0) < 0.5 and stderr > 1e-3


def test_exponential_rate_and_relative_entropy():
    t = numpy.arange(0.0, 30.0)
    rate, stderr = exponential_rate(t, 2.0 * numpy.exp(-0.3 * t), (2.0, 20.0))
    assert rate == pytest.approx(0.3, rel=1e-12) and stderr < 1e-12
    grid = gf.VelocityGrid(2, 64, 6.0)
    f, g = grid.maxwellian(temperature=1.0), grid.maxwellian(temperature=1.5)
    # H(M_1 | M_1.5) = (d/2) (T1/T2 - 1 - ln(T1/T2)) for equal masses and velocities
    exact = (1.0 / 1.5 - 1.0 - numpy.log(1.0 / 1.5))
    assert relative_entropy(f, g, grid.cell_volume) == pytest.approx(exact, rel=1e-10)
    assert relative_entropy(f, f, grid.cell_volume) == 0.0
