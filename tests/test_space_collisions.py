"""The collisions of a space run: every registered kernel, law and operator, batched over the
cells, equals the homogeneous equation cell by cell; the per-cell penalisation; the split
step's structure; the batched heat bath."""

import numpy
import pytest

import granframe as gf
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.equations.homogeneous import HomogeneousBoltzmann as CellCollisions
from granframe.velocity.moments import FieldMoments

GRID = gf.VelocityGrid(2, 16, 3.5)


def _cells(grid, count=6, seed=3):
    """Distinct smooth distributions: shifted, heated Maxwellians (count, *grid.shape)."""
    rng = numpy.random.default_rng(seed)
    return numpy.stack([grid.project(grid.maxwellian(
        rng.uniform(0.5, 1.5), tuple(rng.uniform(-0.4, 0.4, grid.dimension)),
        rng.uniform(0.7, 1.3))) for _ in range(count)])


OPERATORS = [("fast_spectral", {"quadrature": "review"}), ("direct_spectral", {})]
KERNELS = [("maxwell", {}), ("hard_spheres", {}), ("vhs", {"exponent": 0.5})]
LAWS = [("constant", {"value": 0.7}), ("viscoelastic", {"strength": 0.2})]


@pytest.mark.parametrize("operator", OPERATORS, ids=lambda o: o[0])
@pytest.mark.parametrize("kernel", KERNELS, ids=lambda k: k[0])
@pytest.mark.parametrize("law", LAWS, ids=lambda l: l[0])
def test_the_batched_collisions_of_all_cells_equal_the_operator_cell_by_cell(operator, kernel,
                                                                             law):
    grid = GRID
    backend = gf.array_backend("numpy")
    op = gf.collision_operator(operator[0], grid, gf.collision_kernel(kernel[0], **kernel[1]),
                               gf.restitution_law(law[0], **law[1]), backend=backend,
                               **operator[1])
    f = _cells(grid).reshape((2, 3) + grid.shape)          # (blocks, block_cells, ...)
    equation = CellCollisions(op, heat_bath=0.0, knudsen=0.5)
    batched = equation.nonlinear(0.0, f)
    single = HomogeneousBoltzmann(op, knudsen=0.5)
    for b in range(2):
        for c in range(3):
            expected = single.nonlinear(0.0, f[b, c])
            assert numpy.max(numpy.abs(batched[b, c] - expected)) <= 1e-13 * numpy.max(
                numpy.abs(expected))


def test_the_per_cell_penalisation_equals_the_homogeneous_one_in_every_cell():
    grid = GRID
    op = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("hard_spheres"),
                               gf.restitution_law("constant", value=0.8), quadrature="review")
    f = _cells(grid, 4)
    rates, targets = CellCollisions(op, knudsen=1e-3).relaxation(f)
    single = HomogeneousBoltzmann(op, knudsen=1e-3)
    for c in range(4):
        rate, target = single.relaxation(f[c])
        assert rates[c].item() == pytest.approx(rate, rel=1e-12)
        assert numpy.max(numpy.abs(targets[c] - target)) <= 1e-12 * numpy.max(target)


def test_the_stiffness_is_the_stiffest_cell():
    grid = GRID
    op = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("hard_spheres"),
                               gf.restitution_law("constant", value=0.5), quadrature="review")
    f = _cells(grid, 5)
    batched = CellCollisions(op, knudsen=0.1).stiffness(f)
    single = HomogeneousBoltzmann(op, knudsen=0.1)
    for part, rate in batched.items():
        assert rate == pytest.approx(max(single.stiffness(f[c])[part] for c in range(5)),
                                     rel=1e-12)


def test_the_batched_heat_bath_equals_the_planned_one_cell_by_cell():
    grid = GRID
    op = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("maxwell"),
                               gf.restitution_law("constant", value=0.5), quadrature="review")
    f = _cells(grid, 3)
    equation = CellCollisions(op, heat_bath=0.3)
    single = HomogeneousBoltzmann(op, heat_bath=0.3)
    for c in range(3):
        numpy.testing.assert_allclose(equation.linear(f)[c], single.linear(f[c]), rtol=0,
                                      atol=1e-14 * numpy.abs(f).max())
        numpy.testing.assert_allclose(equation.propagate(f, 0.07)[c],
                                      single.propagate(f[c], 0.07), rtol=0,
                                      atol=1e-14 * numpy.abs(f).max())


@pytest.mark.parametrize("dimension", [2, 3])
def test_fields_of_every_cell_equal_the_grid_moments(dimension):
    grid = gf.VelocityGrid(dimension, 12 if dimension == 3 else 24, 3.0)
    f = _cells(grid, 4, seed=dimension)
    f[:, 0] = 0.0        # the node -L, which the fields count as +-L (the next test)
    fields = FieldMoments(grid, dx=0.25)(f)
    for c in range(4):
        moments = grid.moments(f[c])
        assert fields["density"][c] == pytest.approx(moments["mass"], rel=1e-13)
        assert fields["temperature"][c] == pytest.approx(moments["temperature"], rel=1e-12)
        numpy.testing.assert_allclose(fields["velocity"][c] * fields["density"][c],
                                      moments["momentum"], atol=1e-13)
        numpy.testing.assert_allclose(fields["pressure_tensor"][c], moments["pressure_tensor"],
                                      atol=1e-12)
        numpy.testing.assert_allclose(fields["heat_flux"][c], moments["heat_flux"], atol=1e-11)
    assert fields["mass"] == pytest.approx(0.25 * fields["density"].sum(), rel=1e-14)


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_fields_count_the_node_minus_L_as_its_two_halves(dimension):
    """What the node v_1 = -L holds moves half each way: no momentum, no heat flux, P_11 =
    L^2 times its mass; the other nodes as the grid moments count them."""
    grid = gf.VelocityGrid(dimension, 8, 1.0)
    f = numpy.zeros((2,) + grid.shape)
    f[0][(0,) + (3,) * (dimension - 1)] = 1.0          # at v_1 = -L only
    f[1] = _cells(grid, 1)[0]
    f[1, 0] = 0.0
    fields = FieldMoments(grid, dx=1.0)(f)
    mass = grid.cell_volume
    assert fields["density"][0] == pytest.approx(mass)
    assert fields["velocity"][0][0] == 0.0 and fields["heat_flux"][0][0] == 0.0
    assert fields["pressure_tensor"][0][0, 0] == pytest.approx(grid.half_width ** 2 * mass)
    moments = grid.moments(f[1])
    numpy.testing.assert_allclose(fields["heat_flux"][1], moments["heat_flux"], atol=1e-12)


def _sod(support_radius, stop=False):
    from granframe.run.description import RunDescription

    return RunDescription.from_dict({
        "final_time": 0.06, "time_step": 0.003,
        "grid": {"dimension": 2, "n_modes": 24, "support_radius": support_radius},
        "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "riemann", "left": {"density": 1.0, "temperature": 1.0},
                    "right": {"density": 0.125, "temperature": 0.8}},
        "operator": {"name": "fast_spectral", "quadrature": "review"},
        "backend": {"name": "numpy"},
        "space": {"cells": 40, "left": "specular", "right": "specular"},
        "health": {"stop_on_accuracy": stop}})


def test_the_edge_monitors_flag_the_worst_cell_of_a_narrow_box():
    """The Sod tube heats the gas behind the shock to T = 1.12: on S = 3.2 the hottest cell
    has 0.1 % of its energy beyond the edge radius (warned, naming grid.support_radius),
    on S = 4 far less; with health.stop_on_accuracy the run stops."""
    from granframe.run.runner import HealthError, Simulation

    narrow = Simulation(_sod(3.2)).run(None, progress=False)
    accuracy = narrow.dataset.attrs
    assert accuracy["progress_accuracy_values_edge_energy"] > 1e-3
    assert any("raise grid.support_radius (now S = 3.2)" in w
               for w in narrow.accuracy_warnings)
    wide = Simulation(_sod(4.0)).run(None, progress=False)
    assert wide.dataset.attrs["progress_accuracy_values_edge_energy"] < 1e-5
    assert not wide.accuracy_warnings
    with pytest.raises(HealthError, match="edge radius .* raise grid.support_radius"):
        Simulation(_sod(3.2, stop=True)).run(None, progress=False)
