"""Run descriptions, initial data, the run store, health checks and the CLI of the runner."""

import math
import pathlib

import numpy
import pytest
import xarray
import zarr

import granframe as gf
from granframe.tools.cli import main
from granframe.run.description import RunDescription
from granframe.velocity.heatbath import HeatBath
from granframe.model.initial import check_fits
from granframe.run.runner import HealthError, Simulation, health_problem, load_description
from granframe.run.storage import RunStore, StoreError

STUDY = pathlib.Path(__file__).parent.parent / "studies" / "heated_maxwell.py"


def heated(**changes):
    """A small heated Maxwell-molecule run (2D N = 32) on the NumPy backend."""
    base = dict(
        title="test", grid={"dimension": 2, "n_modes": 32, "support_radius": 10.0},
        kernel="maxwell", restitution={"name": "constant", "value": 0.5},
        initial={"name": "maxwellian", "temperature": 8.0},
        operator={"name": "fast_spectral", "radial_points": 16,
                  "sphere": {"name": "circle_trapezoid", "n_points": 8}},
        backend={"name": "numpy", "threads": 1}, heat_bath=0.1, time_step=0.05,
        final_time=1.0, output={"snapshot_interval": 0.25})
    base.update(changes)
    return RunDescription(**base)


def module_function(v1, v2):
    return numpy.exp(-(v1 ** 2 + v2 ** 2) / 4.0) / (4.0 * math.pi)


def negative_function(v1, v2):
    return module_function(v1, v2) - 1e-3


# -- descriptions ---------------------------------------------------------------------
def test_description_round_trips_through_toml():
    d = heated(initial={"name": "callable", "function": module_function, "mass": 1.0},
               kernel={"name": "vhs", "exponent": 0.5, "energy_exponent": 0.5})
    text = d.to_toml()
    assert "test_runner:module_function" in text
    again = RunDescription.from_toml(text)
    assert again.to_dict() == d.to_dict() and again.to_toml() == text
    study = load_description(STUDY)
    assert RunDescription.from_toml(study.to_toml()) == study
    assert load_description(STUDY, quick=True).grid.n_modes == 32


@pytest.mark.parametrize("changes,match", [
    ({"kernel": "maxwel"}, "collision_kernels: name 'maxwel' is not registered"),
    ({"restitution": {"name": "constant", "value": 1.5}}, "'value' = 1.5"),
    ({"time_step": None}, "'time_step' = None is invalid; is required by the fixed-step"),
    ({"integrator": "dopri54"}, "'tolerance' = None is invalid; is required by the adaptive"),
    ({"tolerance": 1e-6}, "'tolerance' = 1e-06 is invalid; applies to adaptive"),
    ({"heat_bath": -0.1}, "'heat_bath' = -0.1"),
    ({"knudsen": 0.0}, "'knudsen' = 0.0"),
    ({"output": {"snapshot_interval": 2.0}}, "snapshot_interval' = 2.0 is invalid; must be <= "
                                             "final_time"),
    ({"output": {"snapshot_interval": 1e-12}}, "'snapshot_interval' = 1e-12 is invalid; must be "
                                               r"a whole multiple \(>= 1\)"),
    ({"operator": {"name": "fast_spectral", "sphere": {"name": "circle_trapezoid",
                                                       "n_points": 0}}}, "'n_points' = 0"),
    ({"backend": {"name": "auto", "threads": 0}}, "'threads' = 0"),
    ({"initial": {"name": "maxwellian", "velocity": 1.0}}, "'velocity' = 1.0 is invalid"),
    ({"operator": {"name": "fast_spectral", "radial_point": 8}}, "unknown option"),
    ({"initial": {"name": "maxwellian", "temperature": -1.0}}, "'temperature' = -1.0"),
    ({"initial": {"name": "callable", "function": lambda v1, v2: v1 * 0}},
     "cannot be written to TOML or a store"),
    ({"grid": {"dimension": 2, "n_modes": 33, "support_radius": 1.0}}, "'n_modes' = 33"),
])
def test_bad_descriptions_are_rejected_with_the_parameter_named(changes, match):
    with pytest.raises((ValueError, TypeError), match=match):
        heated(**changes)


def test_unknown_keys_and_bad_toml_are_rejected():
    with pytest.raises(TypeError, match="'final_tme' .* is not a parameter"):
        RunDescription.from_dict({**heated().to_dict(), "final_tme": 1.0})
    with pytest.raises(TypeError, match="'n_mode' = 64 is invalid; is not a parameter of "
                                        "VelocityGrid; known: allow_aliasing, dimension"):
        heated(grid={"dimension": 2, "n_mode": 64, "support_radius": 1.0})
    with pytest.raises(TypeError, match="'temp' = 1.0 is invalid; is not a parameter of "
                                        "Maxwellian"):
        heated(initial={"name": "gaussian_mixture", "components": [{"temp": 1.0}]})
    with pytest.raises(ValueError, match="TOML text is invalid"):
        RunDescription.from_toml("final_time = = 1")


# -- initial data ---------------------------------------------------------------------
def test_review_initial_data_fits_and_has_the_stated_moments():
    grid = gf.VelocityGrid(2, 64, 10.0)
    box = gf.initial_condition("box", half_width=2 * 6 ** 0.5)
    f = box.sample(grid)
    check_fits(grid, f, box, 1e-8, 1e-12)
    assert abs(grid.mass(f) - 1.0) < 1e-13 and abs(grid.temperature(f) - 8.0) < 0.1
    mixture = gf.initial_condition("gaussian_mixture", components=[
        {"density": 0.5, "velocity": [1.0, 0.0], "temperature": 2.0},
        {"density": 0.5, "velocity": [-1.0, 0.0], "temperature": 2.0}])
    check_fits(grid, mixture.sample(grid), mixture, 1e-8, 1e-10)


def test_smoothed_box_keeps_mass_and_centre_and_is_spectrally_resolved():
    """Box (*) Gaussian(sigma): mass rho, mean u, T = w0^2/3 + sigma^2; its Fourier
    coefficients at the highest modes fall to round-off where the sharp box's ring at 1e-3."""
    grid = gf.VelocityGrid(2, 128, 12.0)
    w0, sigma, u = 2 * 6 ** 0.5, 1.0, [0.5, -0.25]
    smooth = gf.initial_condition("box", half_width=w0, edge_width=sigma, velocity=u)
    f = smooth.sample(grid)
    check_fits(grid, f, smooth, 1e-8, 1e-12)
    assert grid.mass(f) == pytest.approx(1.0, abs=1e-13)
    assert grid.momentum(f) == pytest.approx(u, abs=1e-12)
    assert grid.temperature(f) == pytest.approx(w0 ** 2 / 3 + sigma ** 2, rel=1e-12)

    def highest_modes(g):
        spectrum = numpy.abs(numpy.fft.fft2(g))
        return spectrum[grid.n_modes // 2 - 4: grid.n_modes // 2, 0].max() / spectrum[0, 0]

    sharp = gf.initial_condition("box", half_width=w0, velocity=u).sample(grid)
    assert highest_modes(f) < 1e-12 < 1e-4 < highest_modes(sharp)


@pytest.mark.parametrize("initial,match", [
    ({"name": "maxwellian", "temperature": 60.0}, "faces of the box"),      # wraps around
    ({"name": "maxwellian", "temperature": 0.01}, "relative mass error"),    # narrower than h
    ({"name": "callable", "function": "test_runner:negative_function"}, "min f0"),
    ({"name": "callable", "function": "numpy:sin"}, "calling it raised ValueError"),
    ({"name": "maxwellian", "velocity": [0.0, 0.0, 0.0]}, "must have 2 components"),
])
def test_initial_data_that_does_not_fit_the_grid_is_refused(initial, match):
    with pytest.raises(ValueError, match=match):
        Simulation(heated(initial=initial))


def test_initial_data_are_projected_onto_the_modes_the_method_evolves(tmp_path):
    """Neither Q nor tau Delta acts on Nyquist modes: a Nyquist part of the (discontinuous)
    flat data would stay frozen as a checkerboard over the whole box. Unprojected, this run
    ends with a far field of 3e-4 and a negative-mass share of 7.6 %."""
    d = heated(initial={"name": "box", "half_width": 2 * math.sqrt(6)}, final_time=3.0,
               output={"snapshot_interval": 3.0}, health={"positivity_tolerance": 0.2})
    simulation = Simulation(d)
    spectrum = numpy.fft.rfftn(simulation.f0)
    assert numpy.abs(spectrum[d.grid.nyquist_mask()]).max() < 1e-15 * numpy.abs(spectrum).max()
    raw = d.build("initial").sample(d.grid)
    assert d.grid.mass(simulation.f0) == pytest.approx(d.grid.mass(raw), rel=1e-14)
    simulation.run(tmp_path / "flat.zarr", progress=False)
    ds = xarray.open_zarr(tmp_path / "flat.zarr")
    numpy.testing.assert_array_equal(ds.f.isel(time=0).values, simulation.f0)
    f, v = ds.f.isel(time=-1).values, ds.v1.values
    far = numpy.hypot(*numpy.meshgrid(v, v, indexing="ij")) > 14
    assert numpy.abs(f[far]).max() < 5e-5 and ds.negative_mass_fraction.values[-1] < 5e-3


# -- runs and stores ------------------------------------------------------------------
def test_run_store_opens_in_xarray_with_named_dimensions(tmp_path):
    result = Simulation(heated()).run(tmp_path / "run.zarr", progress=False)
    assert result.status == "finished" and result.steps == 20 and result.snapshots == 5
    ds = xarray.open_zarr(tmp_path / "run.zarr")
    assert ds.f.dims == ("time", "v1", "v2") and ds.temperature.dims == ("step_time",)
    assert ds.momentum.dims == ("step_time", "axis")
    numpy.testing.assert_allclose(ds.time.values, [0, 0.25, 0.5, 0.75, 1.0], atol=1e-14)
    assert ds.sizes["step_time"] == 21 and list(ds.step.values) == list(range(21))
    numpy.testing.assert_allclose(ds.v1.values, gf.VelocityGrid(2, 32, 10.0).points())
    meta = ds.attrs["granframe"]
    assert RunDescription.from_dict(meta["description"]) == heated()
    assert meta["provenance"]["operator"].startswith("fast_spectral (plugin 'spectral'")
    assert "numpy" in meta["provenance"]["backend"]
    # the moments are those of the stored snapshots
    last = ds.f.isel(time=-1).values
    grid = gf.VelocityGrid(2, 32, 10.0)
    assert ds.temperature.values[-1] == pytest.approx(grid.temperature(last), rel=1e-14)


def test_adaptive_run_lands_on_the_output_times(tmp_path):
    d = heated(integrator="dopri54", time_step=None, tolerance=1e-7, final_time=0.9,
               output={"snapshot_interval": 0.3})
    Simulation(d).run(tmp_path / "a.zarr", progress=False)
    ds = xarray.open_zarr(tmp_path / "a.zarr")
    assert list(ds.time.values) == pytest.approx([0.0, 0.3, 0.6, 0.9], abs=1e-12)
    assert ds.step_time.values[-1] == 0.9 and numpy.all(numpy.diff(ds.step_time.values) > 0)
    # same grid and quadrature with fixed-step RK4: the difference is the time error only
    Simulation(heated(final_time=0.9, time_step=0.01)).run(tmp_path / "r.zarr", progress=False)
    reference = xarray.open_zarr(tmp_path / "r.zarr")
    assert ds.sizes["step_time"] < reference.sizes["step_time"] / 5
    assert abs(ds.temperature.values[-1] / reference.temperature.values[-1] - 1) < 1e-8


def test_existing_store_is_refused_and_another_description_never_appended(tmp_path):
    store = tmp_path / "run.zarr"
    Simulation(heated(final_time=0.5)).run(store, progress=False)
    with pytest.raises(StoreError, match="exists; pass --resume"):
        Simulation(heated(final_time=0.5)).run(store, progress=False)
    with pytest.raises(StoreError, match=r"another description \(differs in: heat_bath\)"):
        Simulation(heated(final_time=0.5, heat_bath=0.2)).run(store, resume=True, progress=False)
    again = Simulation(heated(final_time=0.5)).run(store, resume=True, progress=False)
    assert again.status == "already finished"
    with pytest.raises(StoreError, match="is not a zarr group"):
        RunStore.open(tmp_path)
    zarr.open_group(tmp_path / "plain.zarr", mode="w")
    with pytest.raises(StoreError, match="not a granframe run store"):
        RunStore.open(tmp_path / "plain.zarr")


def test_resume_discards_a_commit_cut_short(tmp_path):
    """Data written beyond the last 'progress' (a kill inside a commit) is dropped on resume."""
    store_path = tmp_path / "run.zarr"
    d = heated()
    reference = Simulation(d).run(tmp_path / "reference.zarr", progress=False)
    Simulation(d).run(store_path, progress=False)
    # cut the finished run back to its third commit (t = 0.5), a torn fourth one left behind
    store = RunStore.open(store_path, mode="r+")
    group = store.group
    progress = dict(store.progress, snapshots=3, records=11, step=10, time=0.5, status="running")
    meta = store.metadata
    meta["progress"] = progress
    group.attrs["granframe"] = meta
    group["f"][3] = numpy.nan          # the torn snapshot: written, never committed
    group["mass"][11] = numpy.nan      # and a torn moment record
    cut = RunStore.resume(store_path, d.to_dict()).group    # resuming truncates to the commit
    assert cut["f"].shape[0] == 3 and cut["time"].shape[0] == 3
    assert all(cut[name].shape[0] == 11 for name in ("mass", "step", "momentum", "step_time"))
    Simulation(d).run(store_path, resume=True, progress=False)
    resumed, full = xarray.open_zarr(store_path), xarray.open_zarr(tmp_path / "reference.zarr")
    assert reference.steps == 20 and list(resumed.step.values) == list(range(21))
    assert numpy.isfinite(resumed.f.values).all() and numpy.isfinite(resumed.mass.values).all()
    numpy.testing.assert_allclose(resumed.f.values, full.f.values, rtol=0,
                                  atol=1e-13 * full.f.values.max())


# -- health ---------------------------------------------------------------------------
def test_health_problems_are_named():
    health = heated().health
    good = {"mass": 1.0, "kinetic_energy": 1.0, "min_f": 0.0, "negative_mass_fraction": 0.0}
    assert health_problem(good, 1.0, health) is None
    cases = [({"mass": math.nan}, "not finite"), ({"min_f": math.inf}, "not finite"),
             ({"mass": -1.0}, "mass is not positive"), ({"mass": 1.001}, "mass drift"),
             ({"negative_mass_fraction": 0.2, "min_f": -0.1}, "loss of positivity")]
    for change, match in cases:
        assert match in health_problem({**good, **change}, 1.0, health)


def test_a_blow_up_stops_the_run_and_keeps_a_valid_store(tmp_path):
    """Forward Euler far beyond the heat bath's stability limit (tau (pi N / 2L)^2 dt >> 2),
    with the up-front step check switched off: the step-by-step health check stops it."""
    d = heated(integrator="forward_euler", heat_bath=50.0, time_step=0.05, final_time=5.0,
               output={"snapshot_interval": 0.5}, health={"step_limit": False})
    with pytest.raises(HealthError, match=r"health check failed at step \d+, t = [0-9.]+: "
                                          r"(loss of positivity|f is not finite)"):
        Simulation(d).run(tmp_path / "bad.zarr", progress=False)
    store = RunStore.open(tmp_path / "bad.zarr")
    assert store.progress["status"] == "failed" and "health check" in store.progress["message"]
    ds = xarray.open_zarr(tmp_path / "bad.zarr")
    assert numpy.isfinite(ds.f.values).all()                 # snapshots: healthy states only
    assert ds.sizes["step_time"] == store.progress["step"] + 1  # moments up to the failure
    with pytest.raises(StoreError, match="stopped by a health check"):
        Simulation(d).run(tmp_path / "bad.zarr", resume=True, progress=False)


@pytest.mark.parametrize("integrator,changes,part,suggested", [
    ("forward_euler", {"heat_bath": 50.0, "time_step": 0.05}, "the heat bath tau Delta_v",
     "if_rk4, penalised_ars222, penalised_euler"),
    ("if_rk4", {"knudsen": 1e-3, "time_step": 0.01}, "the collision term Q/eps",
     "penalised_ars222, penalised_euler"),
    ("penalised_ars222", {"knudsen": 1e-3, "restitution": {"name": "constant", "value": 0.1},
                          "time_step": 0.01}, "the energy dissipation", None),
])
def test_a_time_step_above_the_explicit_limit_is_refused_before_the_run(
        tmp_path, integrator, changes, part, suggested):
    """The limit is dt <= interval / (sum of the explicit parts' spectral radii): the heat
    bath tau max|k|^2 (pi/L)^2, the collisions nu/eps (nu = 1 for these Maxwell molecules),
    the energy dissipation (1 - e^2)/(4 eps) for the penalised schemes."""
    d = heated(integrator=integrator, final_time=1.0, **changes)
    with pytest.raises(ValueError, match=r"parameter 'time_step' = [0-9.]+ is invalid; must be "
                                         rf"<= [0-9.e-]+, the explicit stability limit of "
                                         rf"'{integrator}', set by {part}") as error:
        Simulation(d)
    if suggested:
        assert str(error.value).endswith(f"implicitly or exactly: {suggested}")
    else:   # no registered fixed-step scheme treats the energy dissipation implicitly
        assert "use an integrator" not in str(error.value)
    assert not (tmp_path / "run.zarr").exists()


def test_step_limit_matches_the_observed_blow_up():
    """RK4 on the heat bath alone: stable just below dt = 2.7853 / (tau max|k|^2),
    unstable just above (the highest mode grows from round-off over 800 steps)."""
    from granframe.stepping.integrators import Equation
    from granframe.stepping.stability import step_limit

    grid = gf.VelocityGrid(2, 32, 4.0)
    heat = HeatBath(grid, 0.5, gf.array_backend())

    class Heat(Equation):
        def nonlinear(self, t, f):
            return 0.0 * f

        def linear(self, f):
            return heat(f)

        def propagate(self, f, dt):
            return heat.propagate(f, dt)

        def stiffness(self, f):
            return {"linear": heat.spectral_radius}

    rk4 = gf.time_integrator("rk4")
    limit = step_limit(rk4, Heat(), grid.maxwellian())
    growth = {}
    for factor in (0.98, 1.02):
        f = grid.maxwellian()
        for i in range(800):
            f = rk4.step(Heat(), 0.0, f, factor * limit.limit)
        growth[factor] = numpy.abs(f).max()
    assert growth[0.98] < 1.0 < 1e3 < growth[1.02], growth


# -- command line ---------------------------------------------------------------------
def test_cli_run_plot_info(tmp_path, capsys):
    store, figures = tmp_path / "quick.zarr", tmp_path / "figures"
    assert main(["run", str(STUDY), "--quick", "--out", str(store)]) == 0
    assert "finished, 100 steps to t = 2" in capsys.readouterr().out
    assert main(["plot", str(store), "--out", str(figures)]) == 0
    names = {p.name for p in figures.iterdir()}
    assert names == {"temperature.png", "entropy.png", "slices.png", "contour.png", "moments.png"}
    assert all((figures / n).stat().st_size > 10_000 for n in names)
    assert main(["info", str(store)]) == 0
    out = capsys.readouterr().out
    assert "status      finished" in out and "[restitution]" in out
    toml = tmp_path / "run.toml"
    toml.write_text(heated().to_toml())
    assert main(["run", str(toml), "--quick", "--out", str(tmp_path / "x.zarr")]) == 2
    assert "--quick applies to study modules" in capsys.readouterr().err
    toml.write_text(heated().to_toml().replace("snapshot_interval = 0.25",
                                               "snapshot_interval = 0.26"))
    assert main(["run", str(toml), "--out", str(tmp_path / "x.zarr")]) == 2
    assert "'snapshot_interval' = 0.26" in capsys.readouterr().err
    bad = heated(integrator="forward_euler", heat_bath=50.0, final_time=5.0)
    toml.write_text(bad.to_toml())
    assert main(["run", str(toml), "--out", str(tmp_path / "bad.zarr")]) == 2
    assert "the explicit stability limit of 'forward_euler'" in capsys.readouterr().err
    toml.write_text(heated(integrator="forward_euler", heat_bath=50.0, final_time=5.0,
                           health={"step_limit": False}).to_toml())
    assert main(["run", str(toml), "--out", str(tmp_path / "bad.zarr")]) == 3
    assert "run stopped: health check failed" in capsys.readouterr().err


def test_cli_resume_of_a_finished_run_checks_the_description(tmp_path, capsys):
    toml, store = tmp_path / "run.toml", tmp_path / "run.zarr"
    toml.write_text(heated(final_time=0.5).to_toml())
    assert main(["run", str(toml), "--out", str(store)]) == 0
    assert main(["run", str(toml), "--out", str(store), "--resume"]) == 0
    assert "already finished (t = 0.5, 10 steps" in capsys.readouterr().out
    toml.write_text(heated(final_time=0.5, heat_bath=0.2).to_toml())
    assert main(["run", str(toml), "--out", str(store), "--resume"]) == 2
    assert "another description (differs in: heat_bath)" in capsys.readouterr().err


@pytest.mark.skipif(__import__("importlib").util.find_spec("cupy") is not None,
                    reason="CuPy is installed")
def test_a_store_written_on_a_gpu_is_read_on_a_machine_without_one(tmp_path, capsys):
    """A run with backend = {name = "cupy"} (written here on the NumPy backend, its stored
    description then naming the GPU backend, as a GPU machine writes it): info, check, plot
    and the description work without CuPy; only building the run needs it."""
    from granframe.errors import BackendUnavailableError

    store = tmp_path / "gpu.zarr"
    Simulation(heated(final_time=0.5)).run(store, progress=False)
    written = RunStore.open(store, mode="r+")
    meta = written.metadata
    meta["description"]["backend"] = {"name": "cupy"}
    written.group.attrs["granframe"] = meta
    for command in (["info", str(store)], ["check", str(store)],
                    ["plot", str(store), "--out", str(tmp_path / "figures")]):
        assert main(command) == 0, capsys.readouterr().err
    assert (tmp_path / "figures" / "temperature.png").is_file()
    description = RunDescription.from_dict(meta["description"])
    assert description.backend.name == "cupy"
    with pytest.raises(BackendUnavailableError, match="needs the cupy package"):
        Simulation(description)
