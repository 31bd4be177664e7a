"""VelocityGrid.moments (one pass, one transfer) against the single-moment methods."""

import numpy
import pytest

from granframe.velocity.grid import VelocityGrid


@pytest.mark.parametrize("dimension, n_modes", [(2, 32), (3, 16)])
@pytest.mark.parametrize("velocity", [0.0, 0.4])
def test_fused_moments_match_the_single_moment_methods(dimension, n_modes, velocity):
    grid = VelocityGrid(dimension, n_modes, 3.0)
    u = [velocity, -0.5 * velocity, 0.25 * velocity][:dimension]
    rng = numpy.random.default_rng(dimension)
    f = (grid.maxwellian(1.3, u, 0.8)
         + 1e-3 * grid.maxwellian(0.5, [-1.0] * dimension, 0.3)
         - 1e-4 * rng.random(grid.shape))
    fused = grid.moments(f)
    for name in ("mass", "kinetic_energy", "temperature", "kurtosis", "sonine_a2"):
        assert fused[name] == pytest.approx(getattr(grid, name)(f), rel=1e-13, abs=1e-15), name
    numpy.testing.assert_allclose(fused["momentum"], grid.momentum(f), rtol=1e-13, atol=1e-15)
    numpy.testing.assert_allclose(fused["bulk_velocity"], grid.bulk_velocity(f), rtol=1e-12,
                                  atol=1e-15)
    for name in ("pressure_tensor", "heat_flux"):
        numpy.testing.assert_allclose(fused[name], getattr(grid, name)(f), rtol=1e-11,
                                      atol=1e-14, err_msg=name)
    assert fused["min_f"] == f.min()
    assert fused["negative_mass_fraction"] == pytest.approx(
        numpy.maximum(-f, 0.0).sum() / numpy.abs(f).sum(), rel=1e-13)


def test_fused_moments_of_a_zero_mass_are_nan_where_the_methods_refuse():
    grid = VelocityGrid(2, 8, 1.0)
    fused = grid.moments(numpy.zeros(grid.shape))
    assert fused["mass"] == 0.0 and fused["kinetic_energy"] == 0.0
    for name in ("temperature", "kurtosis", "sonine_a2", "negative_mass_fraction"):
        assert numpy.isnan(fused[name])
    with pytest.raises(ValueError, match="mass"):
        grid.temperature(numpy.zeros(grid.shape))


def test_fused_moments_check_the_shape():
    grid = VelocityGrid(2, 8, 1.0)
    with pytest.raises(ValueError, match="grid shape"):
        grid.moments(numpy.zeros((8, 4)))
