import math

import numpy
import pytest
from scipy import integrate

from granframe.equations.homogeneous import collision_frequency
from granframe.model.kernels import VariableHardSpheres, hard_spheres, maxwell_molecules
from granframe.space import exact
from granframe.velocity.grid import VelocityGrid


# -- Free-molecular walls ----------------------------------------------------------------------

def _half_range(weight, T, positive):
    """int over v_1 > 0 (or < 0) of weight(v_1) M_T(v_1) dv_1 by adaptive quadrature."""
    density = lambda v: weight(v) * math.exp(-v * v / (2 * T)) / math.sqrt(2 * math.pi * T)
    bounds = (0.0, math.inf) if positive else (-math.inf, 0.0)
    return integrate.quad(density, *bounds, epsabs=1e-14, epsrel=1e-13)[0]


def _full(weight, T):
    return integrate.quad(lambda v: weight(v) * math.exp(-v * v / (2 * T))
                          / math.sqrt(2 * math.pi * T), -math.inf, math.inf,
                          epsabs=1e-14, epsrel=1e-13)[0]


@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("T1,T2,density", [(1.0, 2.0, 1.0), (3.0, 0.5, 0.7)])
def test_free_molecular_walls_against_quadrature(dimension, T1, T2, density):
    state = exact.free_molecular_walls(dimension, T1, T2, density)
    n1, n2 = state["n1"], state["n2"]
    moment = {}
    for name, weight1, transverse in (("mass", lambda v: 1.0, lambda v: 1.0),
                                      ("flux", lambda v: v, lambda v: 1.0),
                                      ("P11", lambda v: v * v, lambda v: 1.0),
                                      ("P22", lambda v: 1.0, lambda v: v * v),
                                      ("q11", lambda v: v ** 3, lambda v: 1.0),
                                      ("q1t", lambda v: v, lambda v: v * v)):
        moment[name] = sum(n * _half_range(weight1, T, sign) * _full(transverse, T)
                           for n, T, sign in ((n1, T1, True), (n2, T2, False)))
    assert moment["mass"] == pytest.approx(density, rel=1e-10)
    assert abs(moment["flux"]) < 1e-10                                   # u_1 = 0
    assert moment["P11"] == pytest.approx(state["P11"], rel=1e-10)
    assert moment["P22"] == pytest.approx(state["P"][1, 1], rel=1e-10)
    trace = moment["P11"] + (dimension - 1) * moment["P22"]
    assert trace / (dimension * density) == pytest.approx(state["T"], rel=1e-10)
    q1 = 0.5 * (moment["q11"] + (dimension - 1) * moment["q1t"])
    assert q1 == pytest.approx(state["q1"], rel=1e-10)
    if dimension == 2:       # the 2D moments once more as genuine double integrals
        def f(v2, v1):
            n, T = (n1, T1) if v1 > 0 else (n2, T2)
            return n * math.exp(-(v1 * v1 + v2 * v2) / (2 * T)) / (2 * math.pi * T)
        q = integrate.dblquad(lambda v2, v1: 0.5 * v1 * (v1 * v1 + v2 * v2) * f(v2, v1),
                              0, 15, -15, 15, epsabs=1e-13)[0]
        q += integrate.dblquad(lambda v2, v1: 0.5 * v1 * (v1 * v1 + v2 * v2) * f(v2, v1),
                               -15, 0, -15, 15, epsabs=1e-13)[0]
        assert q == pytest.approx(state["q1"], rel=1e-10)


def _speeds(grid):
    c = grid.points().copy()
    c[0] = 0.0
    return c


@pytest.mark.parametrize("dimension,n", [(2, 32), (3, 16)])
def test_free_molecular_walls_grid_is_discrete_steady_state(dimension, n):
    grid = VelocityGrid(dimension, n, 6.0)
    state = exact.free_molecular_walls_grid(grid, 1.0, 2.0, 0.8)
    f, h = state["f"], grid.cell_volume
    c = _speeds(grid).reshape(grid.mesh()[0].shape)
    assert abs(h * numpy.sum(c * f)) < 1e-15                  # zero discrete mass flux
    assert state["rho"] == pytest.approx(0.8, rel=1e-14)
    # the emitted half ranges are the grid-sampled wall Maxwellians
    ratio = f / grid.maxwellian(1.0, None, 1.0)
    assert numpy.ptp(ratio[n // 2 + 1:]) < 1e-12 * state["n1"]
    # kept speed-0 nodes from initial data
    initial = grid.maxwellian(0.8, None, 1.5)
    kept = exact.free_molecular_walls_grid(grid, 1.0, 2.0, 0.8, rest=initial)
    assert numpy.array_equal(kept["f"][n // 2], initial[n // 2])
    assert kept["rho"] == pytest.approx(0.8, rel=1e-14)
    assert abs(h * numpy.sum(c * kept["f"])) < 1e-15


@pytest.mark.parametrize("support,bound", [(6.0, 0.051), (8.0, 0.099)])
def test_free_molecular_walls_grid_against_closed_form(support, bound):
    """2D, N = 32, T1 = 1, T2 = 2: h = 2L/N is 0.83 (S = 6) or 1.10 (S = 8); the largest
    relative difference, in q_1, is 4.98e-2 and 9.71e-2 (T and P_11: 5.4e-3, 1.05e-2)."""
    grid = VelocityGrid(2, 32, support)
    state = exact.free_molecular_walls_grid(grid, 1.0, 2.0, 1.0)
    closed = exact.free_molecular_walls(2, 1.0, 2.0, 1.0)
    errors = {key: abs(state[key] / closed[key] - 1.0) for key in ("T", "P11", "q1")}
    assert max(errors.values()) < bound and errors["q1"] > 0.9 * bound
    assert state["P"][1, 1] == pytest.approx(state["P11"], rel=1e-12)     # isotropic
    assert abs(state["u"][0]) < 1e-12


def test_free_molecular_walls_grid_converges_at_second_order():
    """The speed-0 node v_1 = 0 holding the average of the two half ranges makes each
    half-range sum a trapezoidal rule ending at the kink v_1 = 0: O(h^2)."""
    closed = exact.free_molecular_walls(2, 1.0, 2.0, 1.0)
    errors = []
    for n in (64, 128, 256):
        state = exact.free_molecular_walls_grid(VelocityGrid(2, n, 6.0), 1.0, 2.0, 1.0)
        errors.append([abs(state[key] / closed[key] - 1.0) for key in ("T", "q1")])
    orders = numpy.log2(numpy.array(errors[:-1]) / numpy.array(errors[1:]))
    assert numpy.all(orders > 1.95) and numpy.all(orders < 2.1), orders


# -- Free transport --------------------------------------------------------------------------

def test_free_transport_sine_is_exact():
    edges = numpy.linspace(0.0, 2.0, 17)
    c = numpy.array([-1.3, 0.0, 0.7])
    averages = exact.free_transport_sine(edges, 0.4, c, 0.3, 2, 2.0)
    for i in range(16):
        for j, cj in enumerate(c):
            value = integrate.quad(lambda x: 1 + 0.3 * math.sin(2 * math.pi * 2 * (x - 0.4 * cj)
                                                              / 2.0), edges[i], edges[i + 1],
                                   epsabs=1e-15)[0] / (edges[i + 1] - edges[i])
            assert averages[i, j] == pytest.approx(value, abs=1e-14)
    with pytest.raises(ValueError, match="'wavenumber' = 1.5"):
        exact.free_transport_sine(edges, 0.4, c, 0.3, 1.5, 2.0)


def _uneven(x, v):
    """Data with g(0, v) != g(0, -v): the image solution has jumps at the folds."""
    return (1.0 + 0.4 * numpy.sin(2 * math.pi * x + 0.3)) * numpy.exp(-(v - 0.5) ** 2 / 2)


def test_specular_images_zero_wall_flux_and_mass():
    grid = VelocityGrid(2, 32, 2.0)
    v, c = grid.points(), _speeds(grid)
    h, ell = grid.spacing, 1.0
    for t in (0.37, 2.9):          # at t = 0 the data, not reflected, are what they are
        walls = exact.specular_images(_uneven, ell, [0.0, ell], t, v, c)
        assert numpy.abs(walls @ c).max() < 1e-14 * numpy.abs(walls).max()
    edges = numpy.linspace(0.0, ell, 41)
    masses = [h * numpy.diff(edges) @ exact.specular_images_cell_averages(
        _uneven, ell, edges, t, v, c).sum(axis=1) for t in (0.0, 0.37, 2.9)]
    assert numpy.ptp(masses) < 1e-13 * masses[0]
    # the node j = 0 (speed 0) does not move; the reflection pairs v and -v at the walls
    later = exact.specular_images_cell_averages(_uneven, ell, edges, 0.37, v, c)
    assert numpy.allclose(later[:, 0], exact.specular_images_cell_averages(
        _uneven, ell, edges, 0.0, v, c)[:, 0], rtol=0, atol=1e-15)


def test_specular_images_equal_periodic_even_extension():
    ell, t = 1.0, 0.83
    v = numpy.linspace(-3.0, 3.0, 13)
    edges = numpy.linspace(0.0, ell, 26)
    # cos(pi k x/ell): the even extension is smooth and 2 ell-periodic
    for k in (1, 3):
        images = exact.specular_images_cell_averages(
            lambda x, u: 1 + 0.3 * numpy.cos(math.pi * k * x / ell), ell, edges, t, v)
        periodic = exact.free_transport_sine(edges, t, v, 0.3, k, 2 * ell, phase=math.pi / 2)
        assert numpy.abs(images - periodic).max() < 1e-14
    # sin(2 pi x/ell): the even extension 1 + a sin(2 pi |y|/ell) has kinks; its primitive
    a = 0.4

    def primitive(y):
        y = numpy.asarray(y)
        periods = numpy.floor((y + ell) / (2 * ell))
        z = y - 2 * ell * periods                                      # in [-ell, ell)
        inner = numpy.abs(z) + a * ell / (2 * math.pi) * (1 - numpy.cos(2 * math.pi * z / ell))
        return numpy.sign(z) * inner + periods * 2 * ell

    images = exact.specular_images_cell_averages(
        lambda x, u: 1 + a * numpy.sin(2 * math.pi * x / ell), ell, edges, t, v)
    shifted = edges[:, None] - v[None, :] * t
    expected = (primitive(shifted[1:]) - primitive(shifted[:-1])) / numpy.diff(edges)[:, None]
    assert numpy.abs(images - expected).max() < 1e-13


# -- Mean free path and Knudsen number -------------------------------------------------------

@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("exponent", [0.0, 0.5, 1.0])
def test_mean_free_path_formula(dimension, exponent):
    kernel = VariableHardSpheres(exponent)
    rho, T, eps = 1.7, 0.6, 0.05
    mean_g = (4 * T) ** (exponent / 2) * math.gamma((dimension + exponent) / 2) \
        / math.gamma(dimension / 2)
    vbar = math.sqrt(2 * T) * math.gamma((dimension + 1) / 2) / math.gamma(dimension / 2)
    expected = eps * vbar / (rho * mean_g)
    assert exact.mean_free_path(kernel, dimension, rho, T, eps) == pytest.approx(expected,
                                                                                rel=1e-13)
    nu = collision_frequency(kernel, dimension, rho, T, dimension * rho * T / 2)
    assert exact.mean_free_path(kernel, dimension, rho, T, eps) == pytest.approx(
        eps * vbar / nu, rel=1e-14)
    assert exact.knudsen_number(kernel, dimension, rho, T, eps, 2.0) == pytest.approx(
        expected / 2.0, rel=1e-13)


def test_mean_free_path_classical_values():
    sqrt2 = math.sqrt(2.0)
    assert exact.mean_free_path(maxwell_molecules(), 2, 1, 1) == pytest.approx(
        math.sqrt(math.pi / 2), rel=1e-14)
    assert exact.mean_free_path(maxwell_molecules(), 3, 1, 1) == pytest.approx(
        math.sqrt(8 / math.pi), rel=1e-14)
    # hard spheres, B = sigma^2 |g| / 4 = |g| / (4 pi): pi sigma^2 = 1, lambda = 1/(sqrt 2 n)
    sigma2 = 1.0 / math.pi
    for rho, T, eps in ((1.0, 1.0, 1.0), (2.5, 0.3, 0.1)):
        classical = eps / (sqrt2 * rho * math.pi * sigma2)
        assert exact.mean_free_path(hard_spheres(), 3, rho, T, eps) == pytest.approx(
            classical, rel=1e-13)
        assert exact.mean_free_path(hard_spheres(), 2, rho, T, eps) == pytest.approx(
            eps / (sqrt2 * rho), rel=1e-13)


@pytest.mark.parametrize("dimension", [2, 3])
def test_mean_relative_speed_by_monte_carlo(dimension):
    """<|v - v_*|^lambda> and <|v|> over two independent Maxwellians, sampled."""
    rng = numpy.random.default_rng(7)
    T, samples = 0.8, 400_000
    v = rng.normal(0.0, math.sqrt(T), (samples, dimension))
    w = rng.normal(0.0, math.sqrt(T), (samples, dimension))
    g = numpy.linalg.norm(v - w, axis=1)
    speed = numpy.linalg.norm(v, axis=1)
    assert abs(speed.mean() - exact.mean_speed(dimension, T)) < 4 * speed.std() / math.sqrt(
        samples)
    for exponent in (0.5, 1.0):
        kernel = VariableHardSpheres(exponent)
        sample = g ** exponent
        assert abs(sample.mean() - kernel.mean_speed_part(dimension, T)) \
            < 4 * sample.std() / math.sqrt(samples)
