import math
import warnings

import numpy
import pytest

from granframe import AliasingWarning, VelocityGrid


def test_defaults_follow_the_review():
    grid = VelocityGrid(dimension=2, n_modes=64, support_radius=10.0)
    # Test 1 of the review: S = 10 gives L = 5 (3 + sqrt 2) and R = 20.
    assert grid.half_width == pytest.approx(5.0 * (3.0 + math.sqrt(2.0)), rel=1e-15)
    assert grid.truncation_radius == 20.0
    assert grid.spacing == pytest.approx(2 * grid.half_width / 64)
    v = grid.points()
    assert v[0] == -grid.half_width and v[32] == pytest.approx(0.0, abs=1e-14)
    k = grid.wavenumbers()
    assert list(k[:3]) == [0, 1, 2] and k[32] == -32 and k[-1] == -1


@pytest.mark.parametrize("dimension,n_modes,radius", [(2, 64, 10.0), (3, 32, 4.0)])
def test_moments_of_a_maxwellian(dimension, n_modes, radius):
    grid = VelocityGrid(dimension, n_modes, radius)
    u = numpy.array([0.3, -0.2, 0.1][:dimension])
    T = 0.8 * (radius / 4) ** 2
    f = grid.maxwellian(density=2.0, velocity=u, temperature=T)
    assert grid.mass(f) == pytest.approx(2.0, rel=1e-12)
    numpy.testing.assert_allclose(grid.bulk_velocity(f), u, atol=1e-12)
    assert grid.temperature(f) == pytest.approx(T, rel=1e-10)
    assert grid.kinetic_energy(f) == pytest.approx(2.0 * (dimension * T + u @ u) / 2, rel=1e-10)
    assert grid.kurtosis(f) == pytest.approx((dimension + 2) / dimension, rel=1e-9)
    assert abs(grid.sonine_a2(f)) < 1e-9


def test_flat_profile_kurtosis():
    # Uniform on the square [-w, w]^2: <c^2> = 2 w^2/3, <c^4> = 2 w^4/5 + 2 w^4/9 -> kappa = 1.4
    grid = VelocityGrid(2, 128, 10.0)
    v1, v2 = grid.mesh()
    w = 2 * math.sqrt(6)
    f = ((abs(v1) < w) & (abs(v2) < w)) / (4 * w * w)
    assert grid.kurtosis(f) == pytest.approx(1.4, rel=0.03)


@pytest.mark.parametrize("name,value", [("half_width", 20.0), ("truncation_radius", 19.0)])
def test_below_safe_bounds_requires_override_and_warns(name, value):
    with pytest.raises(ValueError, match=rf"'{name}' = {value}.*allow_aliasing=True"):
        VelocityGrid(2, 64, 10.0, **{name: value})
    with pytest.warns(AliasingWarning, match=name):
        grid = VelocityGrid(2, 64, 10.0, allow_aliasing=True, **{name: value})
    assert getattr(grid, name) == value


def test_safe_values_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        VelocityGrid(3, 16, 4.0, half_width=9.0, truncation_radius=12.0)


@pytest.mark.parametrize("kwargs,error,fragment", [
    (dict(dimension=4, n_modes=64, support_radius=1.0), ValueError, "'dimension' = 4"),
    (dict(dimension=2, n_modes=63, support_radius=1.0), ValueError, "'n_modes' = 63"),
    (dict(dimension=2, n_modes=2, support_radius=1.0), ValueError, "'n_modes' = 2"),
    (dict(dimension=2, n_modes=64.0, support_radius=1.0), TypeError, "'n_modes' = 64.0"),
    (dict(dimension=2, n_modes=True, support_radius=1.0), TypeError, "'n_modes' = True"),
    (dict(dimension=2, n_modes=64, support_radius=-1.0), ValueError, "'support_radius' = -1.0"),
    (dict(dimension=2, n_modes=64, support_radius=math.nan), ValueError, "'support_radius' = nan"),
    (dict(dimension=2, n_modes=64, support_radius="1"), TypeError, "'support_radius' = '1'"),
    (dict(dimension=2, n_modes=64, support_radius=1.0, allow_aliasing=1), TypeError,
     "'allow_aliasing' = 1"),
])
def test_invalid_grids_are_named(kwargs, error, fragment):
    with pytest.raises(error, match=fragment.replace("(", r"\(")) as info:
        VelocityGrid(**kwargs)
    assert "must" in str(info.value)


def test_moment_of_wrong_shape_is_refused():
    grid = VelocityGrid(2, 16, 1.0)
    with pytest.raises(ValueError, match=r"'f.shape' = \(8, 8\)"):
        grid.mass(numpy.ones((8, 8)))


def test_absurd_mode_counts_are_refused():
    with pytest.raises(ValueError, match=r"'n_modes' = 131072 is invalid; must be an even "
                                         r"integer >= 4 and <= 65536"):
        VelocityGrid(2, 2 ** 17, 1.0)
    with pytest.raises(ValueError, match="'n_modes'"):
        VelocityGrid(2, 10 ** 400, 1.0)
