"""Every rule integrates exactly the polynomial degree it states, and no more."""

import itertools
import math

import numpy
import pytest

import granframe
from granframe.velocity.quadratures import (CircleTrapezoid, GaussLegendre, Lebedev, SphereProduct,
                                   monomial_sphere_integral, sphere_area)


def monomials(dimension, degree):
    return [a for a in itertools.product(range(degree + 1), repeat=dimension) if sum(a) == degree]


def surface_errors(rule, degree):
    x, w = rule.nodes(), rule.weights()
    errors = []
    for a in monomials(rule.dimension, degree):
        approx = w @ numpy.prod(x ** numpy.array(a), axis=1)
        exact = monomial_sphere_integral(a)
        errors.append(abs(approx - exact) / max(1.0, abs(exact)))
    return numpy.array(errors)


SURFACE_RULES = [CircleTrapezoid(1), CircleTrapezoid(16), CircleTrapezoid(17, phase=0.3),
                 Lebedev(3), Lebedev(7), Lebedev(9), Lebedev(17), Lebedev(31),
                 SphereProduct(1), SphereProduct(4), SphereProduct(8)]


@pytest.mark.parametrize("rule", SURFACE_RULES, ids=repr)
def test_surface_rule_is_exact_to_its_degree_and_not_beyond(rule):
    assert rule.weights().sum() == pytest.approx(sphere_area(rule.dimension), rel=1e-14)
    numpy.testing.assert_allclose(numpy.linalg.norm(rule.nodes(), axis=1), 1.0, rtol=1e-14)
    for degree in range(rule.degree + 1):
        assert surface_errors(rule, degree).max() < 1e-13, f"degree {degree}"
    # Sharp: a zonal harmonic of degree + 1 (or degree + 2 for antipodal rules, which
    # integrate every odd polynomial exactly) is not integrated exactly. Zonal harmonics
    # -- T_k(n.x) on the circle, P_k(n.x) on the sphere -- have zero mean for k >= 1.
    x, w = rule.nodes(), rule.weights()
    zonal = (numpy.polynomial.chebyshev.Chebyshev if rule.dimension == 2
             else numpy.polynomial.legendre.Legendre)
    directions = numpy.random.default_rng(0).normal(size=(5, rule.dimension))
    directions /= numpy.linalg.norm(directions, axis=1, keepdims=True)
    beyond = [abs(w @ zonal.basis(k)(x @ n)) for k in (rule.degree + 1, rule.degree + 2)
              for n in directions]
    assert max(beyond) > 1e-6


@pytest.mark.parametrize("n", [1, 2, 5, 16, 32])
def test_gauss_legendre_on_zero_to_radius(n):
    rule = GaussLegendre(n)
    R = 20.0
    rho, w = rule.rule(R)
    assert rho.min() > 0.0 and rho.max() < R
    # Legendre polynomials in t = 2 rho / R - 1: int_0^R P_k(t) drho = R delta_k0.
    t = 2.0 * rho / R - 1.0
    for k in range(rule.degree + 1):
        assert w @ numpy.polynomial.legendre.Legendre.basis(k)(t) == pytest.approx(
            R * (k == 0), abs=1e-13 * R), k
    # Sharp: P_n^2 has degree 2n, vanishes at the nodes, and int_0^R P_n(t)^2 = R/(2n+1).
    p_n = numpy.polynomial.legendre.Legendre.basis(n)
    assert abs(w @ p_n(t) ** 2) < 1e-12 * R < R / (2 * n + 1)


def test_sizes_and_symmetry():
    assert Lebedev(7).n_points == 26 and Lebedev(9).n_points == 38
    assert SphereProduct(4).n_points == 32
    assert CircleTrapezoid(16).n_points == 16
    for rule in (Lebedev(7), SphereProduct(4), CircleTrapezoid(16)):
        assert rule.is_antipodal
    assert not CircleTrapezoid(15).is_antipodal


def test_monomial_formula_against_known_values():
    assert monomial_sphere_integral((0, 0)) == pytest.approx(2 * math.pi)
    assert monomial_sphere_integral((0, 0, 0)) == pytest.approx(4 * math.pi)
    assert monomial_sphere_integral((2, 0, 0)) == pytest.approx(4 * math.pi / 3)
    assert monomial_sphere_integral((2, 2)) == pytest.approx(math.pi / 4)
    assert monomial_sphere_integral((1, 2, 0)) == 0.0


def test_registered_quadratures_by_name():
    assert granframe.quadrature("lebedev", order=9).n_points == 38
    assert granframe.quadrature("gauss_legendre", n_points=30).degree == 59
    with pytest.raises(ValueError, match=r"'order' = 8 is invalid; must be one of \[3, 5, 7"):
        granframe.quadrature("lebedev", order=8)
    with pytest.raises(ValueError, match="'radius' = -1"):
        GaussLegendre(4).rule(-1.0)
