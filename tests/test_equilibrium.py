"""Discrete Maxwellians (granframe.velocity.equilibrium) and the BGK penalisation built on them.

The discrete Maxwellian exp(a + b.v + c|v|^2) has exactly the grid mass, momentum and second
moment asked for, is positive, equals the sampled continuum Maxwellian to the grid's
quadrature error where the grid resolves it, and says where no grid function of that form
has the moments (the discrete realisability bound: a mean between two nodes needs a least
variance). The penalisation r (M[f] - f) of a space run then conserves every cell's mass,
momentum and energy to round-off.
"""

import numpy
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import granframe as gf
from granframe.equations.homogeneous import HomogeneousBoltzmann as CellCollisions
from granframe.velocity.equilibrium import discrete_maxwellians


def _moments(grid, f):
    """Grid mass, momentum (node -L at -L) and h^d sum |v|^2 f of a stack f (n, *shape)."""
    h, n = grid.cell_volume, f.shape[0]
    flat = f.reshape(n, -1)
    mesh = [numpy.broadcast_to(m, grid.shape).reshape(-1) for m in grid.mesh()]
    return (flat.sum(axis=1) * h, numpy.stack([flat @ m for m in mesh], axis=1) * h,
            flat @ sum(m * m for m in mesh) * h)


@settings(max_examples=25, deadline=None)
@given(dimension=st.sampled_from([2, 3]), seed=st.integers(0, 2**32 - 1),
       temperature=st.floats(0.3, 3.0), speed=st.floats(0.0, 1.5))
def test_the_moments_are_exact_and_the_maxwellian_positive(dimension, seed, temperature, speed):
    """Data: three positive grid functions (a Maxwellian of the drawn T and speed, plus a
    second one and noise): the discrete Maxwellians of their moments have them to 1e-13."""
    grid = gf.VelocityGrid(dimension, 24 if dimension == 2 else 16, 3.5)
    rng = numpy.random.default_rng(seed)
    data = []
    for k in range(3):
        u = rng.normal(size=dimension) * speed
        f = (grid.maxwellian(1.0 + k, u, temperature)
             + 0.3 * grid.maxwellian(0.5, -u, 0.5 * temperature)
             + 1e-3 * rng.random(grid.shape))
        data.append(f)
    rho, momentum, second = _moments(grid, numpy.stack(data))
    m, converged = discrete_maxwellians(grid, rho, momentum, second)
    assert converged.all()
    assert m.min() > 0.0
    rho_m, momentum_m, second_m = _moments(grid, m)
    numpy.testing.assert_allclose(rho_m, rho, rtol=1e-13)
    numpy.testing.assert_allclose(momentum_m, momentum, atol=1e-13 * rho.max())
    numpy.testing.assert_allclose(second_m, second, rtol=1e-13)


def test_a_resolved_maxwellian_is_its_own_discrete_maxwellian():
    """On N = 48, S = 4.5 the sampled Maxwellian's tails are below 1e-16 of its peak: the
    discrete Maxwellian of its moments is the sampled Maxwellian to 1e-12."""
    grid = gf.VelocityGrid(2, 48, 4.5)
    f = numpy.stack([grid.maxwellian(rho, u, t) for rho, u, t in
                     [(0.5, [0.3, -0.2], 0.8), (1.0, [0.0, 0.0], 1.0), (2.0, [-0.5, 0.1], 1.3)]])
    m, converged = discrete_maxwellians(grid, *_moments(grid, f))
    assert converged.all()
    assert numpy.abs(m - f).max() < 1e-12 * f.max()


def test_it_has_the_energy_the_sampled_maxwellian_misses():
    """f: a Maxwellian of T = 0.37 projected onto the Nyquist-free modes on N = 20, S = 3 in
    3D (h = 0.68 > sqrt T). The sampled Maxwellian of f's grid rho, u, T, scaled to f's grid
    mass, misses f's grid energy by 1.6e-6; the discrete Maxwellian has it to 1e-14."""
    grid = gf.VelocityGrid(3, 20, 3.0)
    f = grid.project(grid.maxwellian(1.0, [0.3, 0.0, 0.0], 0.37))
    rho, u, t = grid.mass(f), grid.momentum(f) / grid.mass(f), grid.temperature(f)
    sampled = grid.maxwellian(rho, u, t)
    sampled *= rho / grid.mass(sampled)
    assert abs(grid.kinetic_energy(sampled) / grid.kinetic_energy(f) - 1) > 1e-6
    moments = _moments(grid, f[None])
    m, converged = discrete_maxwellians(grid, *moments)
    assert converged.all()
    assert abs(grid.kinetic_energy(m[0]) / grid.kinetic_energy(f) - 1) < 1e-14


def test_moments_without_a_discrete_maxwellian_are_flagged():
    """No mass, no temperature, NaN, and a mean velocity between two nodes with less than the
    least variance two neighbouring nodes allow: not converged; a good row beside them is."""
    grid = gf.VelocityGrid(2, 24, 3.5)
    h = grid.spacing
    good = _moments(grid, grid.maxwellian(1.0, [0.2, 0.0], 1.0)[None])
    u = 0.5 * h                                      # halfway between the nodes 0 and h
    least = (u - 0.0) * (h - u)                      # the least variance along v_1
    rho = numpy.array([good[0][0], 0.0, 1.0, numpy.nan, 1.0])
    momentum = numpy.array([good[1][0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [u, 0.0]])
    second = numpy.array([good[2][0], 1.0, 0.0, 1.0, u * u + 0.5 * least])
    m, converged = discrete_maxwellians(grid, rho, momentum, second)
    assert converged.tolist() == [True, False, False, False, False]
    assert numpy.isfinite(m).all() and m.min() >= 0.0


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_penalisation_conserves_every_cell_to_round_off(dimension):
    """r (M[f] - f) of CellCollisions: zero grid mass, momentum and energy in every cell of a
    batch (blocks, cells, *grid.shape) of non-Maxwellian data, to 1e-14 of the cell's."""
    grid = gf.VelocityGrid(dimension, 24 if dimension == 2 else 16, 3.0)
    operator = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("maxwell"),
                                     gf.restitution_law("constant", value=0.9))
    equation = CellCollisions(operator, knudsen=1e-10)
    f = numpy.stack([[grid.project(grid.maxwellian(1.0 + 0.2 * i, [0.4 * j] + [0.0] * (
        dimension - 1), 0.7 + 0.2 * j) + grid.maxwellian(0.3, [-1.0] + [0.2] * (dimension - 1),
                                                         0.5)) for j in range(3)]
                     for i in range(2)])
    rate, target = equation.relaxation(f)
    assert rate.shape == (2, 3) + (1,) * dimension and numpy.all(rate > 1e9)
    flat_f = f.reshape((-1,) + grid.shape)
    flat_m = target.reshape((-1,) + grid.shape)
    for before, after in zip(_moments(grid, flat_f), _moments(grid, flat_m)):
        assert numpy.abs(after - before).max() <= 1e-14 * numpy.abs(before).max() + 1e-16
