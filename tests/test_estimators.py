"""Error indicators (granframe.velocity.estimators) against closed forms for Maxwellians."""

import math

import pytest
import scipy.special

import granframe as gf
from granframe.velocity.estimators import mass_beyond, pair_share_beyond, spectral_tail


@pytest.mark.parametrize("dimension, n_modes, temperature", [(2, 32, 1.0), (2, 64, 0.2),
                                                              (3, 16, 1.0)])
@pytest.mark.parametrize("shell", [1, 3])
def test_spectral_tail_of_a_maxwellian(dimension, n_modes, temperature, shell):
    grid = gf.VelocityGrid(dimension, n_modes, 4.0)
    f = grid.maxwellian(temperature=temperature)
    def gaussian(k):   # the continuous transform's ratio at wavenumber k
        return math.exp(-temperature * (math.pi * k / grid.half_width) ** 2 / 2)

    # the DFT of the samples is the periodised continuous transform (aliasing of k + m N); the
    # largest coefficient of the band lies on an axis at |k| = N/2 - shell
    k = n_modes // 2 - shell
    exact = (sum(gaussian(k + m * n_modes) for m in range(-3, 4))
             / sum(gaussian(m * n_modes) for m in range(-3, 4)))
    assert spectral_tail(grid, f, shell) == pytest.approx(exact, rel=1e-9, abs=1e-15)


def test_spectral_tail_sees_under_resolution():
    """Halving the temperature at fixed h is what free cooling does: the tail grows."""
    grid = gf.VelocityGrid(2, 32, 4.0)
    tails = [spectral_tail(grid, grid.maxwellian(temperature=t)) for t in (1.0, 0.25, 0.0625)]
    assert tails[0] < 1e-6 and 1e-2 < tails[1] < 0.1 < tails[2]


@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("radius", [2.0, 3.5])
def test_mass_beyond_a_radius_of_a_maxwellian(dimension, radius):
    grid = gf.VelocityGrid(dimension, 64 if dimension == 2 else 48, 4.0)
    temperature = 1.3
    f = grid.maxwellian(velocity=[0.3] + [0.0] * (dimension - 1), temperature=temperature)
    exact = scipy.special.gammaincc(dimension / 2, radius ** 2 / (2 * temperature))
    # the rectangle rule on a ball has an O(h) boundary error
    assert mass_beyond(grid, f, radius) == pytest.approx(exact, rel=0.05)


@pytest.mark.parametrize("call, parameter", [
    (lambda g, f: spectral_tail(g, f, 0), "shell"),
    (lambda g, f: spectral_tail(g, f, 16), "shell"),
    (lambda g, f: spectral_tail(g, 0 * f), "f"),
    (lambda g, f: mass_beyond(g, f, -1.0), "radius"),
    (lambda g, f: mass_beyond(g, f[:4], 1.0), "f.shape"),
    (lambda g, f: pair_share_beyond(g, f, 0.0), "radius"),
])
def test_bad_input_is_named(call, parameter):
    grid = gf.VelocityGrid(2, 32, 4.0)
    with pytest.raises((ValueError, TypeError), match=f"'{parameter}'"):
        call(grid, grid.maxwellian())


@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("radius", [3.0, 5.0])
@pytest.mark.parametrize("power", [0.0, 3.0])
def test_pair_share_beyond_a_relative_speed_of_a_maxwellian(dimension, radius, power):
    grid = gf.VelocityGrid(dimension, 64 if dimension == 2 else 40, 4.0)
    temperature = 1.3
    f = grid.maxwellian(velocity=[0.3] + [0.0] * (dimension - 1), temperature=temperature)
    exact = scipy.special.gammaincc((dimension + power) / 2, radius ** 2 / (4 * temperature))
    # lags lie on the grid too: the same O(h) boundary error as for the mass beyond a radius
    assert pair_share_beyond(grid, f, radius, power) == pytest.approx(exact, rel=0.05)
