import math

import numpy
import pytest

import granframe
from granframe.model.kernels import VariableHardSpheres, hard_spheres, maxwell_molecules


def test_review_constants():
    maxwell = maxwell_molecules()
    assert maxwell.prefactor(2) == pytest.approx(1 / (2 * math.pi))
    assert maxwell.prefactor(3) == pytest.approx(1 / (4 * math.pi))
    assert maxwell(numpy.array([3.0]), 0.2, dimension=2)[0] == pytest.approx(1 / (2 * math.pi))
    hs = hard_spheres()
    assert hs(numpy.array([2.0]), -0.5, dimension=3)[0] == pytest.approx(2 / (4 * math.pi))
    assert hs.exponent == 1.0 and maxwell.is_maxwellian and maxwell.is_isotropic


def test_full_kernel():
    kernel = VariableHardSpheres(0.5, angular=lambda c: 1 + 0.5 * c, energy_exponent=-0.5,
                                 constant=2.0)
    value = kernel(numpy.array([4.0]), numpy.array([0.5]), energy=9.0, dimension=3)
    assert value[0] == pytest.approx(2.0 * 2.0 * 1.25 / 3.0)
    assert not kernel.is_isotropic


@pytest.mark.parametrize("kwargs,error,fragment", [
    (dict(exponent=1.5), ValueError, "'exponent' = 1.5"),
    (dict(exponent=-0.1), ValueError, "'exponent' = -0.1"),
    (dict(exponent="hard"), TypeError, "'exponent' = 'hard'"),
    (dict(constant=0.0), ValueError, "'constant' = 0.0"),
    (dict(angular=3.0), TypeError, "'angular' = 3.0"),
    (dict(angular=lambda c: c), ValueError, "'angular'.*bounded below by a positive"),
    (dict(angular=lambda c: 1 / (1 - c)), ValueError, "'angular'"),
    (dict(angular=lambda: 1.0), TypeError, "'angular'.*must accept"),
    (dict(energy_exponent=math.inf), ValueError, "'energy_exponent' = inf"),
])
def test_invalid_kernels(kwargs, error, fragment):
    with pytest.raises(error, match=fragment):
        VariableHardSpheres(**kwargs)


def test_energy_factor_needs_positive_energy():
    kernel = VariableHardSpheres(energy_exponent=0.5)
    assert kernel.energy_factor(4.0) == 2.0
    with pytest.raises(ValueError, match="'energy' = -1.0"):
        kernel.energy_factor(-1.0)


def test_kernels_by_name():
    assert granframe.collision_kernel("hard_spheres").exponent == 1.0
    assert granframe.collision_kernel("vhs", exponent=0.5).exponent == 0.5


@pytest.mark.parametrize("dimension,area", [(2, 2 * math.pi), (3, 4 * math.pi)])
def test_angular_integral_against_closed_forms(dimension, area):
    """int b w dsigma: |S| for b = 1; for b = 2 + c and w = c, int c^2 dsigma = pi (2D),
    4 pi/3 (3D)."""
    isotropic = VariableHardSpheres(0.0)
    assert isotropic.angular_integral(dimension) == pytest.approx(area, rel=1e-14)
    assert isotropic.angular_integral(dimension, lambda t: 1 - t) == pytest.approx(area, rel=1e-14)
    linear = VariableHardSpheres(0.0, angular=lambda c: 2 + c)
    second = math.pi if dimension == 2 else 4 * math.pi / 3
    assert linear.angular_integral(dimension, lambda t: t) == pytest.approx(second, rel=1e-12)


@pytest.mark.parametrize("exponent", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("dimension", [2, 3])
def test_mean_speed_parts_of_many_temperatures_equal_the_closed_form(exponent, dimension):
    """The contract's vectorised quadrature (what a kernel without a closed form uses for
    every cell of a space run) equals its one-temperature rule to round-off, and the closed
    form of variable hard spheres to the rule's error (4e-8 for |g|^0.5, whose root at 0
    the 64 points resolve least)."""
    from granframe.abc import CollisionKernel

    kernel = VariableHardSpheres(exponent)
    temperatures = numpy.array([0.05, 0.7, 1.0, 3.0, 40.0])
    generic = CollisionKernel.mean_speed_parts(kernel, dimension, temperatures)
    scalar = [CollisionKernel.mean_speed_part(kernel, dimension, t) for t in temperatures]
    exact = [kernel.mean_speed_part(dimension, t) for t in temperatures]
    numpy.testing.assert_allclose(generic, scalar, rtol=1e-13)     # the same rule
    numpy.testing.assert_allclose(generic, exact, rtol=1e-7)       # |g|^0.5: 4e-8
    numpy.testing.assert_allclose(kernel.mean_speed_parts(dimension, temperatures), exact,
                                  rtol=1e-15)
