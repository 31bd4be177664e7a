"""The default quadratures of fast_spectral (``quadrature = "auto"``) against exact results,
and the review's preset (``quadrature = "review"``): its rules, their precedence, its
errors and its place in a run description."""

import math
import re

import numpy
import pytest
import scipy.stats
import xarray

import granframe as gf
from granframe.model.exact import heated_maxwell_temperature, maxwell_energy_dissipation
from granframe.run.description import RunDescription, check_component
from granframe.run.runner import Simulation
from granframe.velocity.quadratures import CircleTrapezoid, Lebedev, SphereProduct
from granframe_spectral.fast import (QUADRATURES, REVIEW_RADIAL, REVIEW_SIGMA, REVIEW_SPHERE,
                                     FastSpectral, default_quadratures)

KERNEL = gf.collision_kernel("maxwell")
LAW = gf.restitution_law("constant", value=0.5)

#: 3D N = 32, S = 5 (L = 11.0, R = 10): the grid of docs/accuracy-vs-cost.md, heated_3d
GRID_3D = gf.VelocityGrid(3, 32, 5.0)


#: (density, velocity, temperature) of a non-Maxwellian two-Gaussian mixture that the 3D
#: N = 32, S = 5 grid resolves (spectral tail 3e-7)
MIXTURE = ((0.6, (0.63, 0.32, 0.0), 1.6), (0.4, (-0.95, -0.47, 0.19), 2.08))


def truncated_share(components, radius: float, dimension: int = 3) -> float:
    r"""The share of the energy dissipation of Maxwell molecules that the truncation of
    relative velocities at |g| <= R keeps, exact for a Gaussian mixture:

    .. math:: \frac{\sum_{ij} \rho_i \rho_j E[|g|^2 1_{|g| \le R}]}
                   {\sum_{ij} \rho_i \rho_j E[|g|^2]},\quad
              g \sim N(u_i - u_j, (T_i + T_j) I).

    With X = |g|^2 / s^2 non-central chi-square (d degrees, lambda = |u_i - u_j|^2 / s^2,
    s^2 = T_i + T_j): E[X 1_{X <= x}] = d F_{d+2,lambda}(x) + lambda F_{d+4,lambda}(x).
    """
    full = kept = 0.0
    for rho_i, u_i, t_i in components:
        for rho_j, u_j, t_j in components:
            mean = numpy.subtract(u_i, u_j)
            spread = t_i + t_j
            shift, x = mean @ mean / spread, radius ** 2 / spread
            full += rho_i * rho_j * spread * (dimension + shift)
            kept += rho_i * rho_j * spread * (
                dimension * scipy.stats.ncx2.cdf(x, dimension + 2, shift)
                + shift * scipy.stats.ncx2.cdf(x, dimension + 4, shift))
    return kept / full


def dissipation_error(**options):
    """|int Q |v|^2 / D_R - 1| on GRID_3D for MIXTURE, Maxwell molecules, e = 0.5, where
    D_R is the exact rate (:func:`maxwell_energy_dissipation`) times the share the
    operator's truncation at R = 10 keeps (1 - 2.6e-4, :func:`truncated_share`)."""
    f = sum(GRID_3D.maxwellian(*component) for component in MIXTURE)
    operator = gf.collision_operator("fast_spectral", GRID_3D, KERNEL, LAW, **options)
    rate = float(numpy.sum(operator(f) * GRID_3D.speed_squared())) * GRID_3D.cell_volume
    exact = (maxwell_energy_dissipation(GRID_3D, f, 0.5, KERNEL)
             * truncated_share(MIXTURE, GRID_3D.truncation_radius))
    return abs(rate / exact - 1)


def test_default_3d_n32_energy_dissipation_is_exact_to_1e6_and_the_review_rules_are_not():
    """Measured: 6.1e-8 with the defaults (N_rho = 20, Lebedev 35), 4.7e-5 with the review's
    rules (docs/accuracy-vs-cost.md, "Default quadratures")."""
    assert gf.VelocityGrid(3, 32, 5.0) == GRID_3D
    default = dissipation_error()
    review = dissipation_error(quadrature="review")
    assert default <= 1e-6
    assert review > 100 * default and review > 1e-5


HEATED_3D = """
title = "heated Maxwell molecules, 3D, default quadratures"
final_time = 2.0
time_step = 0.4
heat_bath = 0.1

[grid]
dimension = 3
n_modes = 32
support_radius = 5.0

[kernel]
name = "maxwell"

[restitution]
name = "constant"
value = 0.5

[initial]
name = "maxwellian"
temperature = 1.5

[operator]
name = "fast_spectral"
"""


def test_default_3d_n32_heated_maxwell_temperature_law_holds_to_2e5(tmp_path):
    """d_t f = Q(f, f) + 0.1 Delta f, Maxwell molecules, e = 0.5, T0 = 1.5, S = 5, RK4 with
    dt = 0.4 (the explicit limit of the heat bath is 0.43), operator and backend by default:
    T(t) of the run against the exact law (review, eq. (ext_temp)) at every step to t = 2."""
    description = RunDescription.from_toml(HEATED_3D)
    assert description.operator.params == {}          # every default left alone
    Simulation(description).run(tmp_path / "heated.zarr", progress=False)
    ds = xarray.open_zarr(tmp_path / "heated.zarr")
    times = ds.step_time.values
    exact = heated_maxwell_temperature(times, 1.5, 0.5, 0.1)
    assert times[-1] == pytest.approx(2.0) and len(times) == 6
    assert numpy.max(numpy.abs(ds.temperature.values / exact - 1)) <= 2e-5


# -- the presets ------------------------------------------------------------------------------
@pytest.mark.parametrize("dimension", [2, 3])
def test_review_preset_is_the_review_rules(dimension):
    grid = gf.VelocityGrid(dimension, 16, 5.0)
    op = gf.collision_operator("fast_spectral", grid, KERNEL, LAW, quadrature="review")
    expected = {2: (32, CircleTrapezoid(16), CircleTrapezoid(32)),
                3: (30, SphereProduct(4), SphereProduct(8))}[dimension]
    assert (op.radial_points, op.sphere, op.sigma) == expected
    assert (REVIEW_RADIAL[dimension], REVIEW_SPHERE[dimension],
            REVIEW_SIGMA[dimension]) == expected
    assert op.quadrature == "review" and QUADRATURES == ("auto", "review")
    assert op.transform_pairs == (32 * 8 if dimension == 2 else 30 * 16)


def test_auto_rules_grow_with_the_grid_and_are_the_default():
    rules = {n: default_quadratures(gf.VelocityGrid(3, n, 5.0)) for n in (8, 16, 32, 48)}
    for small, large in zip((8, 16, 32), (16, 32, 48)):
        assert rules[small][0] < rules[large][0]
        assert rules[small][1].degree < rules[large][1].degree
    assert all(isinstance(r[1], Lebedev) for r in rules.values())
    two = [default_quadratures(gf.VelocityGrid(2, n, 5.0)) for n in (16, 64)]
    assert two[0][1].n_points < two[1][1].n_points and two[0][0] < two[1][0]
    op = gf.collision_operator("fast_spectral", GRID_3D, KERNEL, LAW)
    assert op.quadrature == "auto"
    assert (op.radial_points, op.sphere, op.sigma) == rules[32]
    # the rules follow N R / L: a box twice as wide at the same N needs about half the degree
    wide = gf.VelocityGrid(3, 32, 5.0, half_width=2 * GRID_3D.half_width)
    assert default_quadratures(wide)[1].degree < rules[32][1].degree
    assert default_quadratures(GRID_3D, "review") == (30, SphereProduct(4), SphereProduct(8))


def test_explicit_rules_take_precedence_over_either_preset():
    grid = gf.VelocityGrid(2, 16, 5.0)
    for quadrature in QUADRATURES:
        op = gf.collision_operator("fast_spectral", grid, KERNEL, LAW, quadrature=quadrature,
                                   radial_points=12)
        assert op.radial_points == 12
        assert op.sphere == default_quadratures(grid, quadrature)[1]
        op = gf.collision_operator("fast_spectral", grid, KERNEL, LAW, quadrature=quadrature,
                                   sphere=CircleTrapezoid(8), sigma=CircleTrapezoid(12))
        assert (op.sphere, op.sigma) == (CircleTrapezoid(8), CircleTrapezoid(12))
        assert op.radial_points == default_quadratures(grid, quadrature)[0]


@pytest.mark.parametrize("value", ["Review", "fine", "", None, 3, ["auto"]])
def test_bad_quadrature_is_refused_naming_it(value):
    grid = gf.VelocityGrid(2, 16, 5.0)
    message = (rf"^fast_spectral: parameter 'quadrature' = {re.escape(repr(value))} is invalid; "
               r"must be "
               r"one of \['auto', 'review'\]")
    with pytest.raises(ValueError, match=message):
        gf.collision_operator("fast_spectral", grid, KERNEL, LAW, quadrature=value)
    with pytest.raises(ValueError, match=message):
        FastSpectral.estimate_memory(grid, KERNEL, LAW, gf.array_backend("numpy"),
                                     quadrature=value)


def test_estimate_memory_follows_the_preset():
    backend = gf.array_backend("numpy")
    for quadrature in QUADRATURES:
        op = gf.collision_operator("fast_spectral", GRID_3D, KERNEL, LAW, backend=backend,
                                   quadrature=quadrature)
        assert FastSpectral.estimate_memory(GRID_3D, KERNEL, LAW, backend,
                                            quadrature=quadrature) == op.memory_bytes
    assert (FastSpectral.estimate_memory(GRID_3D, KERNEL, LAW, backend, quadrature="review")
            < FastSpectral.estimate_memory(GRID_3D, KERNEL, LAW, backend))


def test_quadrature_round_trips_through_toml_and_reaches_the_operator():
    text = HEATED_3D.replace('name = "fast_spectral"',
                             'name = "fast_spectral"\nquadrature = "review"')
    description = RunDescription.from_toml(text)
    assert description.operator.params == {"quadrature": "review"}
    again = RunDescription.from_toml(description.to_toml())
    assert again == description and 'quadrature = "review"' in description.to_toml()
    grid = gf.VelocityGrid(3, 8, 5.0)
    operator = description.build("operator", grid=grid, kernel=KERNEL, restitution=LAW,
                                 backend=gf.array_backend("numpy"))
    assert (operator.quadrature, operator.radial_points, operator.sphere) == (
        "review", 30, SphereProduct(4))
    check_component("collision_operators", description.operator, grid=None, kernel=None,
                    restitution=None, backend=None)
    bad = RunDescription.from_toml(text.replace('"review"', '"reviewed"'))
    with pytest.raises(ValueError, match=r"parameter 'quadrature' = 'reviewed' is invalid"):
        Simulation(bad)
    assert math.isfinite(float(numpy.sum(operator(grid.maxwellian()))))


def test_bench_times_both_presets():
    from granframe.tools import bench

    records = bench.run([bench.parse_config("2:16")], "numpy", 1, 1,
                        quadratures=("auto", "review"))
    assert [(r["quadrature"], r["radial_points"], r["sphere_rule"]) for r in records] == [
        ("auto", 16, "circle 24"), ("review", 32, "circle 16")]
    assert records[0]["transform_pairs"] == 16 * 12 and records[1]["transform_pairs"] == 32 * 8
    assert "| auto | circle 24 | 16 | 24 |" in bench.table(records)
    with pytest.raises(ValueError, match=r"^bench: parameter 'quadrature' = 'fine' is invalid; "
                                         r"must be one of auto, review"):
        bench.run([(2, 16, 32, 16)], "numpy", 1, 1, quadratures=("fine",))
