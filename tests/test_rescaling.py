"""The rescaled formulation of free cooling (granframe.equations.rescaled): physics and refusals."""

import math
import re

import numpy
import pytest

import granframe as gf
from granframe.run.description import RunDescription
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.equations.rescaled import RescaledBoltzmann, Rescaling
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore

RK4 = gf.time_integrator("rk4")


def _operator(kernel, n_modes, support, e=0.5, d=2):
    grid = gf.VelocityGrid(d, n_modes, support)
    return gf.collision_operator(
        "fast_spectral", grid, gf.collision_kernel(kernel), gf.restitution_law("constant", value=e),
        backend=gf.array_backend("numpy"), radial_points=n_modes // 2,
        sphere=gf.CircleTrapezoid(32))


def _march(equation, f, dt, steps):
    for i in range(steps):
        f = RK4.step(equation, i * dt, f, dt)
    return f


def test_drift_is_the_divergence_and_conserves_mass():
    operator = _operator("maxwell", 48, 4.0)
    grid = operator.grid
    f0 = grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    drift = equation.divergence(f0)
    # div(xi M) = (d - |xi|^2 / T) M where the taper is 1 (M is negligible elsewhere)
    exact = (2.0 - grid.speed_squared()) * f0
    assert numpy.max(numpy.abs(drift - exact)) < 1e-9 * numpy.max(numpy.abs(exact))
    assert abs(grid.mass(drift)) < 1e-14


def test_maxwell_molecules_follow_the_exact_cooling_law_in_physical_variables():
    """dT/dt = -(1-e^2) rho T / 4 (review's B): T falls 160-fold over s = t = 27 while the
    rescaled profile keeps its temperature; on the same grid the unscaled run would have a
    thermal speed of 0.2 h at the end."""
    e = 0.5
    operator = _operator("maxwell", 64, 6.0, e)
    grid = operator.grid
    f0 = grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    law = equation.rescaling
    assert law.degree == 0.0 and law.rate == pytest.approx((1 - e * e) / 8, rel=1e-8)
    g = f0
    worst = 0.0
    for k in range(9):
        g = _march(equation, g, 0.25, 12)
        s = 3.0 * (k + 1)
        exact = grid.temperature(f0) * math.exp(-(1 - e * e) * float(law.physical_time(s)) / 4)
        worst = max(worst, abs(float(law.temperature(s, grid.temperature(g))) / exact - 1))
    assert float(law.temperature(27.0, grid.temperature(g))) < grid.temperature(f0) / 150
    assert worst < 2e-3
    assert abs(grid.mass(g) / grid.mass(f0) - 1) < 1e-13


def test_hard_spheres_rescaled_run_equals_the_unscaled_one():
    """The map f = omega^d g(omega v), dt/ds = omega^kappa with kappa = 1 checked against a
    direct run while both are resolved (T falls to 0.67 T0)."""
    operator = _operator("hard_spheres", 48, 4.0)
    grid = operator.grid
    f0 = grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    law = equation.rescaling
    assert law.degree == 1.0
    g = _march(equation, f0, 0.05, 16)
    t = float(law.physical_time(0.8))
    f = _march(HomogeneousBoltzmann(operator), f0, t / 50, 50)
    rescaled_temperature = float(law.temperature(0.8, grid.temperature(g)))
    assert abs(rescaled_temperature / grid.temperature(f) - 1) < 2e-5
    assert abs(grid.kurtosis(g) / grid.kurtosis(f) - 1) < 2e-5
    # the physical f on its own grid: f(t, u + (xi - u)/omega) = omega^d g(xi)
    axes, physical = law.physical(grid, g, 0.8)
    cell = numpy.prod([a[1] - a[0] for a in axes])
    assert float(physical.sum()) * cell == pytest.approx(grid.mass(f), rel=1e-12)


def test_hard_spheres_reach_a_stationary_cooling_state():
    """In rescaled variables the homogeneous cooling state is a steady state. Its shape
    (kurtosis) settles within a few collision times. Its temperature T_g settles at the rate
    kappa a_0 that the fixed scaling rate predicts: the cooling rate a(T_g) grows like
    T_g^{kappa/2}, so d(T_g - T_*)/ds = -kappa a_0 (T_g - T_*) near the state. Then
    T = T_g / (1 + a_0 t)^2 is Haff's law."""
    operator = _operator("hard_spheres", 32, 3.5)
    grid = operator.grid
    f0 = grid.maxwellian(temperature=1.0)
    equation = RescaledBoltzmann(operator, f0)
    law = equation.rescaling
    g = _march(equation, f0, 0.1, 60)
    kurtosis, temperature = [grid.kurtosis(g)], [grid.temperature(g)]
    for _ in range(2):
        g = _march(equation, g, 0.1, 20)
        kurtosis.append(grid.kurtosis(g))
        temperature.append(grid.temperature(g))
    # over s in [6, 10] the kurtosis moves by less than 0.2 % of its change over [0, 6]
    assert abs(kurtosis[2] - kurtosis[0]) < 2e-3 * abs(kurtosis[0] - grid.kurtosis(f0))
    assert kurtosis[2] > 2.0 + 0.05      # a2 > 0 at e = 0.5: not the Maxwellian
    ratio = (temperature[2] - temperature[1]) / (temperature[1] - temperature[0])
    assert ratio == pytest.approx(math.exp(-law.degree * law.rate * 2.0), rel=2e-2)
    assert abs(grid.mass(g) / grid.mass(f0) - 1) < 1e-13
    # the operator conserves momentum to spectral accuracy; the anti-drift scales a deviation
    # of g's momentum by omega, the physical one (that divided by omega) does not grow
    deviation = numpy.max(numpy.abs(grid.momentum(g) - grid.momentum(f0)))
    assert deviation / float(law.scale(10.0)) < 1e-7


def _description(**changes):
    base = dict(final_time=2.0, time_step=0.1, rescaled=True,
                grid=dict(dimension=2, n_modes=32, support_radius=3.5),
                kernel="hard_spheres", restitution=dict(name="constant", value=0.5),
                initial=dict(name="maxwellian", temperature=1.0),
                operator=dict(name="fast_spectral", radial_points=16,
                              sphere=dict(name="circle_trapezoid", n_points=16)),
                backend="numpy", output=dict(snapshot_interval=1.0))
    return RunDescription.from_dict({**base, **changes})


def test_a_rescaled_run_stores_its_map_to_physical_variables(tmp_path):
    description = _description()
    assert "rescaled = true" in description.to_toml()
    assert RunDescription.from_toml(description.to_toml()) == description
    assert "rescaled" not in _description(rescaled=False).to_dict()
    result = Simulation(description).run(tmp_path / "run.zarr", progress=False)
    assert result.status == "finished"
    store = RunStore.open(tmp_path / "run.zarr")
    law = Rescaling.from_store(store)
    history = law.history(store)
    s = history["s"]
    assert s[-1] == pytest.approx(2.0)
    assert numpy.allclose(history["time"], numpy.expm1(law.rate * s) / law.rate)
    assert numpy.allclose(history["temperature"],
                          history["rescaled_temperature"] * numpy.exp(-2 * law.rate * s))
    assert history["temperature"][-1] < 0.5 * history["temperature"][0]


@pytest.mark.parametrize("changes, parameter, words", [
    ({"heat_bath": 0.1}, "heat_bath", "must be 0 in a rescaled run"),
    ({"restitution": dict(name="viscoelastic", strength=0.1)}, "restitution",
     "must not depend on the relative speed"),
    ({"kernel": dict(name="maxwell", energy_exponent=-0.5)}, "kernel", "lambda + 2 gamma = -1"),
])
def test_scenes_without_a_rescaled_formulation_are_refused(changes, parameter, words):
    with pytest.raises(ValueError, match=f"parameter '{parameter}'.*{re.escape(words)}"):
        _description(**changes)


@pytest.mark.parametrize("scheme", ["forward_euler", "ssp_rk2", "penalised_euler",
                                    "penalised_ars222"])
def test_schemes_unstable_for_the_drift_are_refused(scheme):
    with pytest.raises(ValueError, match="unstable at any step for the drift.*if_rk4, rk4, ssp_rk3"):
        Simulation(_description(integrator=scheme))


def test_a_step_above_the_drift_limit_is_refused_and_one_below_runs():
    with pytest.raises(ValueError, match="explicit stability limit of 'rk4', set by the drift"):
        Simulation(_description(time_step=0.5, final_time=2.0))
    simulation = Simulation(_description(integrator="ssp_rk3", time_step=0.05))
    assert simulation.equation.stiffness(simulation.f0)["drift"] > 0


def test_plots_of_a_rescaled_run_are_in_physical_time_and_temperature(tmp_path):
    """granframe plot reads the stored map: Maxwell molecules' T(t) against the exact law."""
    from granframe.tools.plot_data import RunData as _Run
    from granframe.tools.plotting import plot

    description = _description(kernel="maxwell", final_time=4.0, time_step=0.1,
                               grid=dict(dimension=2, n_modes=48, support_radius=5.0))
    Simulation(description).run(tmp_path / "run.zarr", progress=False)
    run = _Run(tmp_path / "run.zarr")
    exact = run.exact_temperature()
    assert run.step_time[-1] == pytest.approx(4.0)               # kappa = 0: t = s
    assert run.moments["temperature"][-1] < 0.55                 # it cools, in physical terms
    assert numpy.max(numpy.abs(run.moments["temperature"] / exact - 1)) < 1e-3
    assert "rescaled" in run.title
    assert len(plot(tmp_path / "run.zarr", tmp_path / "figures")) >= 1


def test_a_kernel_that_is_not_a_power_law_is_refused_by_name():
    from granframe.abc import CollisionKernel
    from granframe.equations.rescaled import check_rescalable

    class Softened(CollisionKernel):
        speed_exponent = 1.0

        def prefactor(self, dimension):
            return 1.0

        def speed_part(self, speed, xp=numpy):
            return xp.abs(speed) / (1.0 + xp.abs(speed))

    with pytest.raises(ValueError, match="parameter 'kernel' = 'Softened'.*power law"):
        check_rescalable(Softened(), gf.restitution_law("constant", value=0.5), 0.0, "rescaled")
