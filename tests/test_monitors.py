"""The run-time accuracy monitors (granframe.run.monitors): closed forms, warnings, the stop
option, their record in the store, old stores, and the rescaled Maxwell run-away they catch."""

import json
import math

import numpy
import pytest
import xarray
import zarr
from scipy.special import gammaincc

import granframe as gf
from granframe.run.description import Health, RunDescription
from granframe.run.monitors import (AccuracyMonitors, edge_radius, edge_shares,
                                    temperature_law)
from granframe.run.runner import HealthError, Simulation
from granframe.model.exact import heated_maxwell_temperature
from granframe.run.storage import RunStore, consolidate, describe
from granframe.tools.cli import main
from granframe.tools.plotting import caption
from granframe.velocity.grid import AliasingWarning
from test_runner import heated

#: the heated run's operator with 16 points on the circle (converged to 1e-5 in T)
FINER = {"name": "fast_spectral", "radial_points": 16,
         "sphere": {"name": "circle_trapezoid", "n_points": 16}}

# -- closed forms ---------------------------------------------------------------------
@pytest.mark.parametrize("d,n,radius,tolerance", [(3, 48, None, 5e-3), (3, 48, 3.0, 2e-3),
                                                  (2, 96, 3.0, 1e-2)])
def test_edge_shares_of_a_maxwellian_are_incomplete_gamma_functions(d, n, radius, tolerance):
    """Beyond r around u: Q(d/2, r^2/2T) of the mass and Q(d/2 + 1, r^2/2T) of the energy,
    to the error of counting grid points in a ball."""
    grid = gf.VelocityGrid(d, n, 4.0)
    radius = edge_radius(grid) if radius is None else radius
    u, T = [0.3, -0.2, 0.1][:d], 1.3
    mass, energy = edge_shares(grid, grid.maxwellian(velocity=u, temperature=T), u, radius)
    x = radius ** 2 / (2 * T)
    assert mass == pytest.approx(gammaincc(d / 2, x), rel=tolerance)
    assert energy == pytest.approx(gammaincc(d / 2 + 1, x), rel=tolerance)
    with pytest.raises(ValueError, match="parameter 'radius' = -1.0"):
        edge_shares(grid, grid.maxwellian(), u, -1.0)


def test_the_edge_radius_is_where_velocities_meet_the_images_of_the_support():
    """2L - R - S: sqrt(2) S on the default box, larger on a wider one."""
    assert edge_radius(gf.VelocityGrid(3, 16, 4.0)) == pytest.approx(math.sqrt(2) * 4.0)
    assert edge_radius(gf.VelocityGrid(2, 16, 4.0, half_width=12.0)) == pytest.approx(12.0)
    # a box that allows aliasing down to r_e = 0 has no edge monitors
    with pytest.warns(AliasingWarning):
        description = _rescaled(grid=dict(dimension=2, n_modes=32, support_radius=4.0,
                                          half_width=6.0, allow_aliasing=True))
    assert edge_radius(description.grid) == 0.0
    monitors = AccuracyMonitors(description, None, {"mass": 1.0, "momentum": [0.0, 0.0],
                                                    "temperature": 1.0})
    f = description.grid.maxwellian()
    assert monitors.shape(f, {"mass": 1.0, "momentum": [0.0, 0.0]}, None) == {}


def _rescaled(**changes):
    base = dict(final_time=1.0, time_step=0.1, rescaled=True,
                grid=dict(dimension=2, n_modes=32, support_radius=4.0), kernel="maxwell",
                restitution=dict(name="constant", value=0.5),
                initial=dict(name="maxwellian", temperature=1.0), backend="numpy")
    base.update(changes)
    return RunDescription.from_dict(base)


def test_each_run_gets_the_exact_temperature_law_of_its_own_formulation():
    law = temperature_law(_rescaled())
    assert "T_g(s) = T_g(0)" in law.name and law(7.0, 1.5, 1.0) == 1.5
    assert temperature_law(_rescaled(kernel="hard_spheres")) is None   # Haff: no closed law
    heated_law = temperature_law(heated())
    assert "Maxwell-molecule law" in heated_law.name
    # dT/dt = -rho (1 - e^2) T / 4 + 2 tau at e = 0.5, tau = 0.1, T0 = 8, rho = 2
    limit = 8 * 0.1 / (0.75 * 2)
    assert heated_law(2.0, 8.0, 2.0) == pytest.approx((8 - limit) * math.exp(-0.75) + limit)
    elastic = temperature_law(heated(kernel="hard_spheres",
                                     restitution={"name": "constant", "value": 1.0}))
    assert "T0 + 2 tau t" in elastic.name and elastic(2.0, 8.0, 1.0) == pytest.approx(8.4)
    assert temperature_law(heated(kernel="hard_spheres")) is None


# -- the monitors in runs -------------------------------------------------------------
def test_an_elastic_run_keeps_its_energy_and_momentum():
    """Elastic hard spheres without a heat bath: T and J are invariants. The monitors
    measure the operator's defect (4e-7 in T, 1e-7 in J by t = 1 at 2D N = 32 with 16
    points on the circle), and the run has no accuracy warning."""
    description = heated(kernel="hard_spheres", restitution={"name": "constant", "value": 1.0},
                         heat_bath=0.0, initial={"name": "maxwellian", "temperature": 8.0,
                                                 "velocity": [0.5, -0.25]}, operator=FINER)
    result = Simulation(description).run(None, progress=False)
    ds = result.dataset
    assert result.accuracy_warnings == ()
    assert ds.attrs["progress_accuracy_largest_temperature"] < 1e-6
    assert ds.attrs["progress_accuracy_largest_momentum"] < 1e-6
    J = ds.momentum.values
    shift = numpy.sqrt(((J - J[0]) ** 2).sum(axis=1)) / (ds.mass.values[0]
                                                         * numpy.sqrt(ds.temperature.values))
    assert ds.attrs["progress_accuracy_largest_momentum"] == pytest.approx(shift.max(),
                                                                           rel=1e-12)
    # the monitor is |T/T0 - 1| of the records
    drift = numpy.abs(ds.temperature.values / ds.temperature.values[0] - 1).max()
    assert ds.attrs["progress_accuracy_largest_temperature"] == pytest.approx(drift, rel=1e-12)


def test_the_heated_maxwell_monitor_measures_the_distance_from_the_exact_law():
    result = Simulation(heated(operator=FINER)).run(None, progress=False)
    ds = result.dataset
    t, T, rho = ds.step_time.values, ds.temperature.values, ds.mass.values[0]
    exact = heated_maxwell_temperature(t, T[0], 0.5, 0.1, rho)
    assert ds.attrs["progress_accuracy_largest_temperature"] == pytest.approx(
        numpy.abs(T / exact - 1).max(), rel=1e-12)
    assert ds.attrs["progress_accuracy_largest_temperature"] < 1e-5   # converged to 1e-5
    assert "progress_accuracy_warnings" not in ds.attrs                # no warning


def test_warnings_say_what_drifts_by_how_much_against_what_and_what_to_raise():
    description = _rescaled(operator=dict(name="fast_spectral", radial_points=8,
                                          sphere=dict(name="circle_trapezoid", n_points=6)))
    simulation = Simulation(description)
    monitors = AccuracyMonitors(description, simulation.operator,
                                {"mass": 1.0, "momentum": [0.0, 0.0], "temperature": 1.0})
    assert monitors.update({"temperature": 0.0125, "momentum": 0.5e-3}, 3, 0.75) is None
    monitors.update({"edge_energy": 2e-3, "edge_mass": 1e-4, "spectral_tail": 5e-3}, 4, 1.0)
    text = "\n".join(monitors.warnings())
    assert ("temperature drift |T / T_law - 1| against T_g(s) = T_g(0) (rescaled Maxwell "
            "molecules: a_0 is the exact cooling rate) = 0.0125 > health.accuracy_tolerance "
            "= 0.001; raise operator.sphere (now CircleTrapezoid(n_points=6, phase=0.0)) or "
            "operator.radial_points (now 8); if it persists, lower time_step (now 0.1)") in text
    assert ("share of the energy int |v - u|^2 f beyond the edge radius r_e = 2L - R - S = "
            "5.657 = 0.002 > health.accuracy_tolerance = 0.001; raise grid.support_radius "
            "(now S = 4)") in text
    assert "error predicted by the spectral tail" in text and "raise grid.n_modes (now N = 32)" \
        in text
    assert "momentum" not in text and "share of the mass" not in text   # below the tolerance
    assert len(monitors.warnings()) == 3
    report = monitors.report()
    assert report["flagged"] == {"monitor": "temperature", "step": 3, "time": 0.75,
                                 "value": 0.0125}
    # a tail the resolution report already warned of is not repeated
    monitors.update(monitors.shape(simulation.f0, {"mass": 1.0, "momentum": [0.0, 0.0]},
                                   {"tail_error": 5e-3}), 5, 1.25)
    assert not any("spectral tail" in w for w in monitors.warnings())
    assert monitors.values["edge_energy"] < 1e-3    # f0, a Maxwellian T = 1: Q(2, 16)


def _strict(**health):
    """The heated run with 8 points on the circle: its temperature drifts from the exact
    law by 1.6e-4 by t = 1 (its momentum by 3e-6), past a tolerance of 1e-5."""
    return heated(health={"accuracy_tolerance": 1e-5, **health})


def test_info_json_open_run_and_captions_show_the_monitors(tmp_path, capsys):
    out, toml = tmp_path / "run.zarr", tmp_path / "run.toml"
    toml.write_text(_strict().to_toml())
    assert main(["run", str(toml), "--out", str(out)]) == 0
    assert "granframe: warning: at t = 1: accuracy: temperature drift" in capsys.readouterr().err
    text = describe(out)
    assert "accuracy    at t = 1 (the last commit), against health.accuracy_tolerance = 1e-05" \
        in text
    assert "first above the tolerance: temperature" in text
    assert "  warning: accuracy: temperature drift" in text
    assert main(["info", str(out), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    entry = document["progress"]["accuracy"]
    assert entry["flagged"]["monitor"] == "temperature" and entry["warnings"]
    assert set(entry["values"]) == {"momentum", "temperature", "edge_mass", "edge_energy",
                                    "spectral_tail"}
    ds = gf.open_run(out)
    assert ds.attrs["progress_accuracy_flagged_monitor"] == "temperature"
    assert ds.attrs["progress_accuracy_warnings"] == entry["warnings"]
    ds.to_netcdf(tmp_path / "run.nc")            # the attributes stay netCDF-ready
    for data in (ds, xarray.open_zarr(out, consolidated=False)):
        assert "INACCURATE: accuracy: temperature drift" in caption(data)


def test_stop_on_accuracy_fails_the_run_at_the_step_the_monitor_exceeds(tmp_path, capsys):
    out = tmp_path / "run.zarr"
    with pytest.raises(HealthError) as raised:
        Simulation(_strict(stop_on_accuracy=True)).run(out, progress=False)
    message = str(raised.value)
    ds = gf.open_run(out)
    T, t = ds.temperature.values, ds.step_time.values
    exact = heated_maxwell_temperature(t, T[0], 0.5, 0.1, ds.mass.values[0])
    first = int(numpy.argmax(numpy.abs(T / exact - 1) > 1e-5))
    assert first > 0 and ds.sizes["step_time"] == first + 1       # the records end there
    assert message.startswith(f"health check failed at step {first}, t = {t[first]:g}: "
                              "accuracy: temperature drift")
    assert "> health.accuracy_tolerance = 1e-05; raise operator.sphere" in message
    assert ds.attrs["progress_status"] == "failed"
    assert ds.attrs["progress_accuracy_flagged_step"] == first
    toml = tmp_path / "run.toml"
    toml.write_text(_strict(stop_on_accuracy=True).to_toml())
    assert main(["run", str(toml), "--out", str(tmp_path / "cli.zarr")]) == 3
    assert "run stopped: health check failed" in capsys.readouterr().err


def test_health_options_are_checked_and_left_out_of_stores_at_their_default():
    with pytest.raises(ValueError, match="'accuracy_tolerance' = 0.0 is invalid"):
        heated(health={"accuracy_tolerance": 0.0})
    with pytest.raises(TypeError, match="'stop_on_accuracy'"):
        heated(health={"stop_on_accuracy": "yes"})
    assert "accuracy_tolerance" not in heated().to_dict()["health"]
    assert heated().health == Health()
    stored = _strict(stop_on_accuracy=True).to_dict()["health"]
    assert stored["accuracy_tolerance"] == 1e-5 and stored["stop_on_accuracy"] is True
    assert RunDescription.from_dict(_strict().to_dict()) == _strict()


def test_a_store_written_before_the_monitors_opens_resumes_and_is_described(tmp_path,
                                                                            monkeypatch):
    """A store without an ``accuracy`` entry (and whose description names no accuracy
    option): info, open_run and the captions work, and a resumed run records the monitors."""
    import granframe.run.runner as runner

    out = tmp_path / "old.zarr"
    original = runner.ProgressObserver.after_step

    def interrupt(self, state):
        original(self, state)
        if state.step == 7:                      # after the commit of t = 0.25 (step 5)
            raise KeyboardInterrupt

    monkeypatch.setattr(runner.ProgressObserver, "after_step", interrupt)
    with pytest.raises(KeyboardInterrupt):
        Simulation(heated(operator=FINER)).run(out, progress=False)
    monkeypatch.undo()
    group = zarr.open_group(str(out), mode="r+", use_consolidated=False)
    meta = dict(group.attrs["granframe"])
    meta["progress"] = {k: v for k, v in meta["progress"].items() if k != "accuracy"}
    assert "accuracy_tolerance" not in meta["description"]["health"]
    group.attrs["granframe"] = meta
    consolidate(out)
    assert "accuracy" not in describe(out)
    assert not any(k.startswith("progress_accuracy") for k in gf.open_run(out).attrs)
    assert "INACCURATE" not in caption(gf.open_run(out))
    result = Simulation(heated(operator=FINER)).run(out, resume=True, progress=False)
    assert result.status == "finished"
    entry = RunStore.open(out).progress["accuracy"]
    assert entry["warnings"] == []
    # measured from t = 0 (the store's first record), over the steps after the resume
    ds = gf.open_run(out)
    T, t = ds.temperature.values, ds.step_time.values
    drift = numpy.abs(T / heated_maxwell_temperature(t, T[0], 0.5, 0.1, ds.mass.values[0]) - 1)
    assert entry["largest"]["temperature"] == pytest.approx(drift[6:].max(), rel=1e-12)


# -- the acceptance case: a rescaled 3D Maxwell-molecule run with Lebedev 11 ----------------
def exact_sonine_a2(s, restitution: float, a2_initial: float = 0.0, density: float = 1.0):
    r"""a2(t) of inelastic Maxwell molecules in 3D, isotropic f, B = 1/(4 pi), constant e.

    Post-collisional relative velocity u' = a u + b |u| sigma, a = (1-e)/2, b = (1+e)/2;
    centre of mass G unchanged. With sigma averaged over S^2 (<sigma_i sigma_j> = delta/3),

        <|v'|^4 + |v'_*|^4> - |v|^4 - |v_*|^4 = k_1 |G|^2 |u|^2 + k_2 |u|^4 + k_3 (G.u)^2,
        k_1 = A - 1 + 2 b^2/3,  k_2 = (A^2 + 4 a^2 b^2 / 3 - 1)/8,  k_3 = 2 (a^2 - 1),

    A = a^2 + b^2. For an isotropic f of zero mean, with M_2 = int |v|^2 f, M_4 = int |v|^4 f,
    int int f f_* of |G|^2 |u|^2, |u|^4, (G.u)^2 are rho M_4/2 + M_2^2/6,
    2 rho M_4 + 10 M_2^2/3, rho M_4/2 - M_2^2/2. The weak form (factor 1/2) gives
    dM_4/dt = -alpha rho M_4 + beta M_2^2, with M_2 = 3 rho T, dT/dt = -gamma rho T,
    gamma = (1 - e^2)/4, so z = 1 + a2 = M_4 / (15 rho T^2) obeys

        dz/dt = rho (3 beta / 5 - mu z),   mu = alpha - 2 gamma:
        a2(t) = a2_inf + (a2(0) - a2_inf) exp(-mu rho t),  a2_inf = 3 beta / (5 mu) - 1.

    a2 is scale-free, so it is the same function of s in the rescaled run (t = s for
    kappa = 0). Checks: e = 1 gives mu = 1/3 (the BKW relaxation) and a2_inf = 0; e = 1/2
    gives mu = 21/128 and a2_inf = 2/7.
    """
    e = restitution
    a, b = (1 - e) / 2, (1 + e) / 2
    A = a * a + b * b
    k1, k2, k3 = A - 1 + 2 * b * b / 3, (A * A + 4 * a * a * b * b / 3 - 1) / 8, 2 * (a * a - 1)
    alpha = -0.5 * (k1 / 2 + 2 * k2 + k3 / 2)
    beta = 0.5 * (k1 / 6 + 10 * k2 / 3 - k3 / 2)
    mu = alpha - 2 * (1 - e * e) / 4
    limit = 3 * beta / (5 * mu) - 1
    return limit + (a2_initial - limit) * numpy.exp(-mu * density * numpy.asarray(s))


def test_the_exact_fourth_moment_law_has_the_known_limits():
    assert exact_sonine_a2(1e3, 0.5) == pytest.approx(2 / 7)
    assert exact_sonine_a2(24.0, 0.5) == pytest.approx(2 / 7 * (1 - math.exp(-21 / 128 * 24)))
    assert exact_sonine_a2(3.0, 1.0, a2_initial=0.3) == pytest.approx(0.3 * math.exp(-1.0))


#: The run-away case: 3D Maxwell molecules, e = 0.5, Maxwellian T0 = 1, rescaled, N = 32,
#: S = 4, N_rho = 16, Lebedev 11, RK4 ds = 0.25 (the largest stable step). Run on to s = 24
#: (python tests/test_monitors.py, 4.5 min) it gives a2 = 0.4056 against the exact
#: 0.2801, and a2 is 10 % above the exact law from s = 9.5 on.
RUNAWAY = dict(final_time=7.0, time_step=0.25, rescaled=True,
               grid=dict(dimension=3, n_modes=32, support_radius=4.0), kernel="maxwell",
               restitution=dict(name="constant", value=0.5),
               initial=dict(name="maxwellian", temperature=1.0),
               operator=dict(name="fast_spectral", radial_points=16,
                             sphere=dict(name="lebedev", order=11)),
               backend=dict(name="numpy", threads=2), output=dict(snapshot_interval=1.0))


@pytest.mark.slow
def test_the_rescaled_maxwell_run_away_is_flagged_before_a2_is_off_by_ten_percent():
    """With every health option at its default: the edge share flags the run first (tails
    reach the box), then the temperature of g, stationary in the exact dynamics, drifts
    past the tolerance and names the sphere rule, both while a2 is within 10 % of the
    exact law; a2 keeps running away."""
    result = Simulation(RunDescription.from_dict(RUNAWAY)).run(None, progress=False)
    ds = result.dataset
    s, a2, T = ds.step_time.values, ds.sonine_a2.values, ds.temperature.values
    error = numpy.abs(a2[1:] / exact_sonine_a2(s[1:], 0.5, a2[0]) - 1)
    assert error[3] < 1e-3                    # s = 1: the run agrees with the exact law
    assert error[-1] > 0.04                   # s = 7: a2 runs away (10 % by s = 9.5)
    flagged = ds.attrs["progress_accuracy_flagged_step"]
    assert ds.attrs["progress_accuracy_flagged_monitor"] == "edge_energy"
    assert error[flagged - 1] < 0.1
    drift = numpy.abs(T / T[0] - 1)
    crossing = int(numpy.argmax(drift > 1e-3))
    assert 0 < crossing and error[crossing - 1] < 0.1
    warnings = "\n".join(result.accuracy_warnings)
    assert "against T_g(s) = T_g(0)" in warnings
    assert "raise operator.sphere (now Lebedev(order=11))" in warnings
    assert "raise grid.support_radius (now S = 4)" in warnings
    print(f"flagged by {ds.attrs['progress_accuracy_flagged_monitor']} at s = "
          f"{s[flagged]:g} (a2 error {error[flagged - 1]:.4f}); temperature drift past 1e-3 "
          f"at s = {s[crossing]:g} (a2 error {error[crossing - 1]:.4f}); a2 error at s = "
          f"{s[-1]:g}: {error[-1]:.4f}")


if __name__ == "__main__":      # the long run behind RUNAWAY's numbers
    description = RunDescription.from_dict({**RUNAWAY, "final_time": 24.0})
    ds = Simulation(description).run(None, progress=True).dataset
    s, a2 = ds.step_time.values[1:], ds.sonine_a2.values
    error = a2[1:] / exact_sonine_a2(s, 0.5, a2[0]) - 1
    print(f"a2(24) = {a2[-1]:.4f}, exact {exact_sonine_a2(24.0, 0.5, a2[0]):.4f}; 10 % above "
          f"the exact law from s = {s[numpy.argmax(error > 0.1)]:g}")
