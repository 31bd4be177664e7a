"""The DSMC reference of the hard-sphere shock (granframe.testing.dsmc) and the
Navier-Stokes shock profile (granframe.theory.shock): collision rate, conservation,
reservoir fluxes, Rankine-Hugoniot, the thickness estimator, a tiny shock run."""

from __future__ import annotations

import math

import numpy
import pytest
import scipy.integrate

from granframe.testing import dsmc
from granframe.theory import shock
from granframe.theory.euler import piston_speed, rankine_hugoniot


def _uniform_box(rng, particles: int, cells: int, temperature: float):
    """Particles uniform in [0, cells) (unit cells), Maxwellian at rest: sorted by cell."""
    x = numpy.sort(rng.random(particles) * cells)
    cell = x.astype(numpy.intp)
    counts = numpy.bincount(cell, minlength=cells)
    starts = numpy.concatenate(([0], numpy.cumsum(counts)[:-1]))
    v = dsmc.maxwellian(rng, particles, 0.0, temperature)
    return v, counts, starts


def test_the_mean_relative_speed_of_a_maxwellian_is_4_sqrt_t_over_pi():
    rng = numpy.random.default_rng(3)
    t = 2.5
    g = dsmc.maxwellian(rng, 400_000, 0.0, t) - dsmc.maxwellian(rng, 400_000, 0.0, t)
    speeds = numpy.linalg.norm(g, axis=1)
    error = speeds.std() / math.sqrt(speeds.size)
    assert abs(speeds.mean() - dsmc.mean_relative_speed(t)) < 4 * error
    assert dsmc.mean_relative_speed(t) == pytest.approx(4 * math.sqrt(t / math.pi))


def test_ntc_collision_rate_in_a_uniform_box_is_the_hard_sphere_rate():
    """n pi sigma_d^2 <|g|> per particle, the candidates' N (N - 1) with Poisson-like
    cell counts; the gas stays at its temperature."""
    rng = numpy.random.default_rng(4)
    cells, per_cell, t = 200, 100.0, 1.7
    v, counts, starts = _uniform_box(rng, int(cells * per_cell), cells, t)
    density = 1.3                        # real density: a = per_cell / (density * dx)
    per_length = per_cell / density      # dx = 1
    coefficient = dsmc.CROSS_SECTION / per_length
    nu = dsmc.collision_frequency(density, t)
    dt = 0.1 / nu
    gmax = numpy.full(cells, 5.0 * math.sqrt(2.0 * t))
    steps, done = 40, 0
    for _ in range(steps):
        done += dsmc.collide(rng, v, starts, counts, gmax, coefficient, dt)
    rate = 2.0 * done / (v.shape[0] * steps * dt)
    expected_collisions = 0.5 * v.shape[0] * nu * dt * steps
    assert rate / nu - 1 == pytest.approx(0.0, abs=4 / math.sqrt(expected_collisions))
    assert numpy.mean(v ** 2) == pytest.approx(t, rel=0.01)


def test_collisions_conserve_momentum_and_energy_to_round_off():
    """Cells of two particles each: every collision is one cell's pair."""
    rng = numpy.random.default_rng(5)
    cells = 5000
    v = dsmc.maxwellian(rng, 2 * cells, 0.3, 1.5)
    counts = numpy.full(cells, 2)
    starts = numpy.arange(0, 2 * cells, 2)
    before = v.copy()
    gmax = numpy.full(cells, 8.0)
    tally = numpy.zeros(cells, dtype=numpy.int64)
    done = dsmc.collide(rng, v, starts, counts, gmax, 0.5, 0.5, tally)
    collided = tally > 0
    assert done == tally.sum() and collided.sum() > 1000 and (~collided).sum() > 1000
    assert numpy.any(tally >= 2)              # the same pair twice: in two rounds
    pair = lambda a: a[0::2] + a[1::2]
    energy = lambda a: numpy.sum(a[0::2] ** 2 + a[1::2] ** 2, axis=1)
    momentum_error = numpy.abs(pair(v) - pair(before)).max(axis=1)
    energy_error = numpy.abs(energy(v) / energy(before) - 1.0)
    assert momentum_error.max() < 1e-13 * numpy.abs(before).max()
    assert energy_error.max() < 1e-14
    changed = numpy.abs(v - before).max(axis=1)
    assert numpy.all(changed[0::2][collided] > 0) and numpy.all(changed[0::2][~collided] == 0)
    # relative speeds kept, directions isotropic
    g = v[0::2][collided] - v[1::2][collided]
    g0 = before[0::2][collided] - before[1::2][collided]
    assert numpy.allclose(numpy.linalg.norm(g, axis=1), numpy.linalg.norm(g0, axis=1))
    cosine = g[:, 2] / numpy.linalg.norm(g, axis=1)
    assert abs(cosine.mean()) < 4 / math.sqrt(3 * cosine.size)


@pytest.mark.parametrize("velocity, temperature", [(0.0, 1.0), (2.5, 1.0), (-1.3, 2.0),
                                                   (1.13, 1.49)])
def test_the_one_sided_flux_is_the_maxwellian_flux(velocity, temperature):
    def integrand(w):
        return w * math.exp(-(w - velocity) ** 2 / (2 * temperature))
    flux = scipy.integrate.quad(integrand, 0.0, math.inf)[0] / math.sqrt(2 * math.pi * temperature)
    assert dsmc.one_sided_flux(1.7, velocity, temperature) == pytest.approx(1.7 * flux,
                                                                          rel=1e-10)


@pytest.mark.parametrize("inward, velocity, temperature", [(+1.0, 2.58, 1.0),
                                                          (-1.0, 1.13, 2.08)])
def test_the_reservoir_sends_what_a_maxwellian_slab_sends_across_its_boundary(
        inward, velocity, temperature):
    """Particles of the reservoir's Maxwellian, uniform behind the boundary, moved
    ballistically for dt: the number crossing, their normal speeds and how far they got
    against the reservoir's inflow over many steps."""
    rng = numpy.random.default_rng(6)
    per_length, dt, density = 2000.0, 0.05, 1.4
    reservoir = dsmc.Reservoir(density, velocity, temperature, inward, per_length, dt)
    depth = 1.0                                       # behind the boundary at 0
    slab = int(density * per_length * depth * 100)    # 100 steps' worth
    v = dsmc.maxwellian(rng, slab, velocity, temperature)
    x = -depth * rng.random(slab)                     # behind, in the inflow direction
    crossed = (x + inward * v[:, 0] * dt) > 0
    x_in = (x + inward * v[:, 0] * dt)[crossed]
    w_slab = inward * v[crossed, 0]
    w_res, x_res, count = [], [], 0
    for _ in range(100):
        rows = reservoir.inflow(rng, 0.0, dt)
        xi, vi = rows[:, 0], rows[:, 1:]
        count += xi.size
        w_res.append(inward * vi[:, 0])
        x_res.append(inward * xi)
        assert numpy.all(inward * vi[:, 0] > 0)
    w_res, x_res = numpy.concatenate(w_res), numpy.concatenate(x_res)
    expected = dsmc.one_sided_flux(density, inward * velocity, temperature) * per_length * dt
    assert count == pytest.approx(100 * expected, abs=1.0)
    assert crossed.sum() == pytest.approx(100 * expected, rel=4 / math.sqrt(100 * expected))
    for a, b in ((w_slab, w_res), (w_slab ** 2, w_res ** 2), (x_in, x_res)):
        error = math.hypot(a.std() / math.sqrt(a.size), b.std() / math.sqrt(b.size))
        assert abs(a.mean() - b.mean()) < 4.5 * error
    # the tangential components are the Maxwellian's
    tangential = numpy.concatenate([reservoir.inflow(rng, 0.0, dt)[:, 2:]
                                    for _ in range(400)])
    assert tangential.var() == pytest.approx(temperature, rel=0.04)


@pytest.mark.parametrize("mach", [1.2, 1.5, 2.0, 3.0, 8.0])
def test_rankine_hugoniot_states_agree_and_conserve_the_fluxes(mach):
    a = dsmc.rankine_hugoniot(mach)
    b = shock.rankine_hugoniot(mach)
    gamma = 5.0 / 3.0
    piston = rankine_hugoniot(piston_speed(mach, gamma), gamma)   # the Riemann solver's
    assert a["n2"] == pytest.approx(piston["rho_2"], rel=1e-10)
    assert a["T2"] == pytest.approx(piston["T_2"], rel=1e-10)
    assert piston["mach"] == pytest.approx(mach, rel=1e-10)
    assert (b["rho2"], b["T2"], b["u2"]) == pytest.approx((a["n2"], a["T2"], a["u2"]))
    n1, u1, t1, n2, u2, t2 = (a[k] for k in ("n1", "u1", "T1", "n2", "u2", "T2"))
    assert n1 * u1 == pytest.approx(n2 * u2)
    assert n1 * (u1 ** 2 + t1) == pytest.approx(n2 * (u2 ** 2 + t2))
    assert u1 ** 2 / 2 + 2.5 * t1 == pytest.approx(u2 ** 2 / 2 + 2.5 * t2)
    assert u1 == pytest.approx(mach * math.sqrt(gamma))


def test_the_navier_stokes_profile_joins_the_rankine_hugoniot_states():
    for mach, band in ((1.5, (0.12, 0.25)), (2.0, (0.2, 0.45)), (3.0, (0.35, 0.75))):
        profile = shock.navier_stokes_shock(mach)
        state = profile["state"]
        assert profile["density"][0] == pytest.approx(1.0, abs=2e-3)
        assert profile["density"][-1] == pytest.approx(state["rho2"], rel=1e-4)
        assert profile["temperature"][0] == pytest.approx(1.0, abs=3e-3)
        assert profile["temperature"][-1] == pytest.approx(state["T2"], rel=1e-4)
        assert numpy.all(numpy.diff(profile["density"]) >= -1e-12)
        assert band[0] < profile["inverse_thickness"] < band[1]
        # the fluxes of mass and momentum: rho u uniform
        assert numpy.allclose(profile["density"] * profile["velocity"], state["u1"])


def test_the_weak_navier_stokes_shock_has_taylors_thickness():
    """M -> 1: delta = 8 b / ((gamma + 1) (u_1 - u_2)), b = (4/3) mu + kappa (1/c_v -
    1/c_p) = (7/3) mu (Prandtl 2/3): the Burgers (Taylor) shock; the relative difference
    is O(M - 1)."""
    mu = 5.0 / 16.0 * math.sqrt(2.0 * math.pi)
    for mach, tolerance in ((1.01, 0.01), (1.02, 0.02)):
        state = shock.rankine_hugoniot(mach)
        taylor = (8.0 / 3.0) * (state["u1"] - state["u2"]) / (8.0 * 7.0 / 3.0 * mu)
        assert shock.inverse_thickness(mach) == pytest.approx(taylor, rel=tolerance)


def test_the_thickness_estimator_on_smooth_and_noisy_profiles():
    x = numpy.arange(-20.0, 20.0, 0.17) + 0.05
    tanh = 0.5 * (1.0 + numpy.tanh(2.0 * x / 4.0))
    assert dsmc.maximum_slope(x, tanh)[0] * 4.0 == pytest.approx(1.0, abs=2e-3)
    profile = shock.navier_stokes_shock(3.0, points=20001, span=12.0)
    grid = numpy.arange(-10.0, 10.0, 1.0 / 9.0) + 0.03
    density = numpy.interp(grid, profile["x"], profile["density"])
    found = dsmc.inverse_density_thickness(grid, density, 1.0, 3.0)
    assert found == pytest.approx(profile["inverse_thickness"], rel=2e-3)
    rng = numpy.random.default_rng(8)
    noisy = [dsmc.inverse_density_thickness(grid, density + 0.006 * rng.standard_normal(
        grid.size), 1.0, 3.0) for _ in range(60)]
    assert numpy.mean(noisy) == pytest.approx(profile["inverse_thickness"], rel=0.01)


def test_a_tiny_shock_run_reaches_the_rankine_hugoniot_plateaus():
    settings = dsmc.ShockSettings(mach=2.0, length=14.0, particles_per_cell=20.0,
                                  cells_per_path=2.0, dt_fraction=0.3, transient=25.0,
                                  sampling=25.0, batches=4, seed=3)
    result = dsmc.run_shock(settings)
    state = result.state
    assert result.cell_over_local_path < 0.55 and result.dt_times_local_rate < 0.4
    for key, value in result.checks.items():
        if key[0] in "nuT":
            assert abs(value) < 0.03, (key, value)
    # the far ends of the profile: upstream 1, downstream RH within a few %
    assert result.density[-3:].mean() == pytest.approx(state["n2"], rel=0.04)
    assert result.temperature[-3:].mean() == pytest.approx(state["T2"], rel=0.04)
    assert result.density[:3].mean() == pytest.approx(1.0, rel=0.04)
    assert 0.15 < result.inverse_thickness < 0.45
    assert numpy.isfinite(result.inverse_thickness_error)
    assert result.inverse_thickness_error > 0


def test_a_short_run_at_the_study_resolution_finds_the_studys_thickness():
    """M = 2 at the study's cells and time step, half its particles per cell and a
    fiftieth of its sampling (about 6 s): lambda_1/delta within 3 of its error bars
    (here about 0.008) of the study's 0.2551 +- 0.0009 (studies/hard_sphere_shock.py,
    runs of 2.5 and 3.5 minutes)."""
    settings = dsmc.ShockSettings(mach=2.0, particles_per_cell=30.0, transient=50.0,
                                  sampling=150.0, batches=8, seed=1)
    result = dsmc.run_shock(settings)
    assert 0.002 < result.inverse_thickness_error < 0.015
    assert result.inverse_thickness == pytest.approx(0.2551, abs=0.03)
    assert result.cell_over_local_path < 0.34 and result.dt_times_local_rate < 0.21
    assert max(abs(v) for k, v in result.checks.items() if k[0] in "nuT") < 0.01


def _shock_study():
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).parent.parent / "studies" / "hard_sphere_shock.py"
    spec = importlib.util.spec_from_file_location("hard_sphere_shock_study", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("cell", [1.0, 0.5])
def test_the_spline_thickness_of_granframes_runs_on_cell_averages(cell):
    """The Navier-Stokes profile of M = 1.5 (lambda_1/delta = 0.1752) averaged over cells
    of lambda_1 and lambda_1/2, as granframe's cells hold it, read by the spline of the
    primitive: within 1e-3 (a spline through the averages as point values is 1 % low at
    lambda_1); and the exact cell averages of a tanh profile of the same thickness."""
    study = _shock_study()
    profile = shock.navier_stokes_shock(1.5, points=40001, span=40.0)
    n2 = dsmc.rankine_hugoniot(1.5)["n2"]
    edges = numpy.arange(-30.0, 30.0 + cell / 2, cell) + 0.37 * cell
    primitive = numpy.concatenate(([0.0], numpy.cumsum(
        0.5 * (profile["density"][1:] + profile["density"][:-1]) * numpy.diff(profile["x"]))))
    averages = numpy.diff(numpy.interp(edges, profile["x"], primitive)) / cell
    centres = 0.5 * (edges[:-1] + edges[1:])
    found, middle = study.spline_inverse_thickness(centres, averages, 1.0, n2)
    tolerance = 1e-3
    assert found == pytest.approx(profile["inverse_thickness"], rel=tolerance)
    assert abs(middle) < 0.5 * cell
    delta = 1.0 / profile["inverse_thickness"]
    # cell averages of the tanh profile, exactly: (delta/2) log cosh(2x/delta) is its primitive
    primitive = 0.5 * edges + 0.25 * delta * numpy.log(numpy.cosh(2.0 * edges / delta))
    tanh = 1.0 + (n2 - 1.0) * numpy.diff(primitive) / cell
    assert study.spline_inverse_thickness(centres, tanh, 1.0, n2)[0] * delta == pytest.approx(
        1.0, rel=tolerance)


def test_granframes_shock_run_starts_from_navier_stokes_in_lambda_1():
    """The description of granframe's own shock: 3D hard spheres, elastic, eps = sqrt 2
    (lambda_1 = 1), the Navier-Stokes start, the upstream reservoir at -U of the Mach
    number, a whole number of steps at half the CFL limit or below, cells of the mean free
    paths asked, the default hierarchy; the start's moments are the Navier-Stokes
    profile's in the frame of the gas behind the shock."""
    from granframe.space.transport import step_limit
    from granframe.velocity.grid import VelocityGrid

    study = _shock_study()
    d = study.spectral_description(2.0, 24, 4.5, 2.0, 30.0, 5.0)
    assert d.grid.dimension == 3 and d.kernel.name == "hard_spheres"
    assert d.knudsen == pytest.approx(math.sqrt(2.0))
    assert d.space.cells == 60 and d.space.length == 30.0
    assert d.initial.params["params"] == {"mach": 2.0, "position": 15.0}
    right = d.space.right
    assert right.name == "reservoir"
    assert right.params["velocity"] == pytest.approx(-piston_speed(2.0, 5.0 / 3.0))
    assert (right.params["density"], right.params["temperature"]) == (1.0, 1.0)
    steps = d.final_time / d.time_step
    assert steps == pytest.approx(round(steps), abs=1e-9)
    grid = VelocityGrid(dimension=3, n_modes=24, support_radius=4.5)
    assert d.time_step <= step_limit(grid, 0.5, 0.5) * (1 + 1e-12)
    assert d.space.hierarchy is not None
    v = numpy.linspace(-9.0, 9.0, 91)
    h = v[1] - v[0]
    v1, v2, v3 = numpy.meshgrid(v, v, v, indexing="ij")
    profile = shock.navier_stokes_shock(2.0, points=8001, span=40.0)
    state = profile["state"]
    assert abs(profile["density"][0] - 1.0) < 1e-6
    assert abs(profile["density"][-1] - state["rho2"]) < 1e-6
    for x, s in ((0.0, 100.0), (15.0, 0.0), (19.0, -4.0), (60.0, -100.0)):
        f = shock.navier_stokes_maxwellian(x, v1, v2, v3, 2.0, 15.0)
        n = f.sum() * h ** 3
        rho = numpy.interp(s, profile["x"], profile["density"])
        u = state["u2"] - numpy.interp(s, profile["x"], profile["velocity"])
        assert n == pytest.approx(rho, rel=1e-9)
        assert (v1 * f).sum() * h ** 3 / n == pytest.approx(u, abs=1e-9)
