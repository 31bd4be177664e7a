"""Bad input gives a clear ValueError/TypeError, never a traceback, a hang, an
out-of-memory kill, a silent NaN or a wrong answer (one test per case)."""

import textwrap
import warnings

import numpy
import pytest

import granframe as gf
from granframe.tools import bench
from granframe.run.description import RunDescription
from granframe.model.initial import FromCallable
from granframe.run.runner import Simulation, load_study
from granframe.testing import evaluate_on_host
from granframe_spectral import DirectSpectral, FastSpectral

KERNEL = gf.collision_kernel("maxwell")
LAW = gf.restitution_law("constant", value=0.5)
NUMPY = gf.array_backend("numpy", threads=1)


def heated(**changes):
    """A small heated Maxwell-molecule run (2D N = 32) on the NumPy backend."""
    base = dict(
        grid={"dimension": 2, "n_modes": 32, "support_radius": 10.0},
        kernel="maxwell", restitution={"name": "constant", "value": 0.5},
        initial={"name": "maxwellian", "temperature": 8.0},
        operator={"name": "fast_spectral", "radial_points": 16,
                  "sphere": {"name": "circle_trapezoid", "n_points": 8}},
        backend={"name": "numpy", "threads": 1}, heat_bath=0.1, time_step=0.05,
        final_time=1.0)
    base.update(changes)
    return RunDescription(**base)


def small_operator(name="fast_spectral"):
    return gf.collision_operator(name, gf.VelocityGrid(2, 8, 2.0), KERNEL, LAW, NUMPY)


# -- 1. memory ------------------------------------------------------------------------
def test_memory_fast_3d_n1024_is_refused_before_allocating():
    with pytest.raises(ValueError, match=r"fast_spectral: parameter 'memory_budget' = \d+ is "
                                         r"invalid; is too small: .*needs [0-9.e+]+ GiB"):
        gf.collision_operator("fast_spectral", gf.VelocityGrid(3, 1024, 4.0), KERNEL, LAW,
                              NUMPY)


def test_memory_fast_2d_n65536_is_refused_before_allocating():
    with pytest.raises(ValueError, match=r"fast_spectral: parameter 'memory_budget'.*needs "
                                         r"[0-9.e+]+ GiB \(d = 2, N = 65536\)"):
        gf.collision_operator("fast_spectral", gf.VelocityGrid(2, 65536, 4.0), KERNEL, LAW,
                              NUMPY)


def test_memory_operators_estimate_without_building():
    grid = gf.VelocityGrid(3, 1024, 4.0)
    assert DirectSpectral.estimate_memory(grid, KERNEL, LAW, NUMPY) == 48 * 1023 ** 6
    small = gf.VelocityGrid(2, 32, 4.0)
    op = gf.collision_operator("fast_spectral", small, KERNEL, LAW, NUMPY)
    assert FastSpectral.estimate_memory(small, KERNEL, LAW, NUMPY) == op.memory_bytes > 0


def test_memory_run_3d_n1024_is_refused_with_its_estimate():
    d = heated(grid={"dimension": 3, "n_modes": 1024, "support_radius": 4.0},
               initial={"name": "maxwellian", "temperature": 1.0},
               operator={"name": "fast_spectral"})
    with pytest.raises(ValueError, match=r"Simulation: parameter 'grid.n_modes' = 1024 is "
                                         r"invalid; needs about [0-9.]+ GiB .* copies of f at 8 "
                                         r"GiB.*GRANFRAME_MEMORY_BUDGET"):
        Simulation(d)


def test_memory_budget_environment_variable_overrides_the_default(monkeypatch):
    from granframe.memory import run_memory

    d = heated()
    need = run_memory(d)["total"]
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", str(need // 2))
    with pytest.raises(ValueError, match="memory_budget|GRANFRAME_MEMORY_BUDGET"):
        Simulation(d)
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", "lots")
    with pytest.raises(ValueError, match="'GRANFRAME_MEMORY_BUDGET' = 'lots' is invalid"):
        Simulation(d)
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", "8e9")
    assert Simulation(d).operator.memory_bytes < 8e9


@pytest.mark.parametrize("command", ["limits", "run"])
def test_limits_refuse_a_run_the_memory_check_refuses_as_run_does(tmp_path, capsys,
                                                                  monkeypatch, command):
    """limits exited 0 with 'estimated cost: not estimated (ValueError ...)' for a run
    that granframe run refuses for its memory; both now refuse it by name, status 2."""
    from granframe.memory import run_memory

    d = heated()
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", str(run_memory(d)["total"] // 2))
    (tmp_path / "d.toml").write_text(d.to_toml())
    out = ["--out", tmp_path / "s.zarr"] if command == "run" else []
    status, err = _cli(tmp_path, capsys, command, tmp_path / "d.toml", *out)
    assert status == 2 and err.count("\n") == 1, err
    assert ("parameter 'grid.n_modes' = 32 is invalid; needs about" in err
            and "more than the memory budget" in err), err
    assert not (tmp_path / "s.zarr").exists()


# -- 2. steps, snapshots and sizes ------------------------------------------------------
def test_final_time_1e30_is_refused_not_hung():
    with pytest.raises(ValueError, match=r"'final_time' = 1e\+30 is invalid; must be at most "
                                         r"1e\+09 steps of time_step = 0.05"):
        heated(final_time=1e30)


def test_final_time_1e308_is_refused():
    with pytest.raises(ValueError, match=r"'final_time' = 1e\+308 is invalid; must lie in "
                                         r"\[1e-100, 1e\+100\]"):
        heated(final_time=1e308)


def test_time_step_1e_320_is_refused():
    with pytest.raises(ValueError, match=r"'time_step' = 1e-320 is invalid; must lie in "
                                         r"\[1e-100, 1e\+100\]"):
        heated(time_step=1e-320)
    with pytest.raises(ValueError, match=r"'final_time' = 1.0 is invalid; must be at most "
                                         r"1e\+09 steps of time_step = 1e-12"):
        heated(time_step=1e-12)


def test_snapshot_count_is_bounded():
    with pytest.raises(ValueError, match=r"'output.snapshot_interval' = 1e-09 is invalid; must "
                                         r"give at most 1e\+06 snapshots"):
        heated(integrator="dopri54", time_step=None, tolerance=1e-6,
               output={"snapshot_interval": 1e-9})


def test_huge_radial_points_are_refused():
    for name in ("fast_spectral", "direct_spectral"):
        with pytest.raises(ValueError, match=rf"{name}: parameter 'radial_points' = 1000000000 "
                                             r"is invalid; must be an integer >= 1 and <= 4096"):
            gf.collision_operator(name, gf.VelocityGrid(2, 8, 2.0), KERNEL, LAW, NUMPY,
                                  radial_points=10 ** 9)


def test_huge_quadrature_n_points_are_refused():
    for make, match in ((lambda: gf.CircleTrapezoid(10 ** 9), "'n_points' = 1000000000"),
                        (lambda: gf.GaussLegendre(10 ** 9), "'n_points' = 1000000000"),
                        (lambda: gf.SphereProduct(10 ** 5), "'n_polar' = 100000")):
        with pytest.raises(ValueError, match=match + r" is invalid; must be an integer >= 1 "
                                                     r"and <= \d+"):
            make()


def test_huge_angular_degree_is_refused():
    with pytest.raises(ValueError, match=r"'angular_degree' = 1000000 is invalid; must be an "
                                         r"integer >= 0 and <= 1024"):
        gf.collision_operator("direct_spectral", gf.VelocityGrid(2, 8, 2.0), KERNEL, LAW, NUMPY,
                              angular_degree=10 ** 6)


# -- 3. study modules ---------------------------------------------------------------------
def _study(tmp_path, text):
    path = tmp_path / "x.py"
    path.write_text(textwrap.dedent(text))
    return path


def test_study_with_a_syntax_error(tmp_path):
    path = _study(tmp_path, "import math\n\ndef description(quick=False)\n    return None\n")
    with pytest.raises(ValueError, match=r"run: study '.*x.py' could not be loaded: "
                                         r"SyntaxError: .* \(line 3\)"):
        load_study(path)


def test_study_with_a_missing_import(tmp_path):
    path = _study(tmp_path, "import math\nimport no_such_module_here\n")
    with pytest.raises(ValueError, match=r"could not be loaded: ModuleNotFoundError: No module "
                                         r"named 'no_such_module_here' \(line 2\)"):
        load_study(path)


def test_study_that_raises(tmp_path):
    path = _study(tmp_path, """
        def description(quick=False):
            return {}["grid"]
        """)
    with pytest.raises(ValueError, match=r"could not make its runs: KeyError: 'grid' \(line 3\)"):
        load_study(path)
    raising = _study(tmp_path, "raise RuntimeError('not today')\n")
    with pytest.raises(ValueError, match=r"could not be loaded: RuntimeError: not today "
                                         r"\(line 1\)"):
        load_study(raising)


# -- 4. bench -----------------------------------------------------------------------------
def test_bench_config_2_15_is_refused():
    with pytest.raises(ValueError, match=r"bench: parameter 'n_modes' = 15 is invalid; must be "
                                         r"an even integer >= 4"):
        bench.parse_config("2:15")
    with pytest.raises(ValueError, match=r"^bench: parameter 'sphere_points' = 30 is invalid"):
        bench.run([(3, 16, 30, 30)], "numpy", 1, 1)


def test_bench_threads_0_is_refused():
    with pytest.raises(ValueError, match=r"^bench: parameter 'threads' = 0 is invalid; must be "
                                         r"an integer >= 1"):
        bench.run([(2, 16, 32, 16)], "numpy", 0, 1)


def test_bench_backend_foo_is_refused():
    with pytest.raises(ValueError, match=r"^bench: parameter 'backend' = 'foo' is invalid; "
                                         r"must be a registered array backend: .*numpy"):
        bench.run([(2, 16, 32, 16)], "foo", 1, 1)


def test_bench_repeats_0_is_refused():
    with pytest.raises(ValueError, match=r"^bench: parameter 'repeats' = 0 is invalid; must be "
                                         r"an integer >= 1"):
        bench.run([(2, 16, 32, 16)], "numpy", 1, 0)


# -- 5. the Python API --------------------------------------------------------------------
def test_api_none_grid_is_a_type_error():
    for name in ("fast_spectral", "direct_spectral"):
        with pytest.raises(TypeError, match=rf"{name}: parameter 'grid' = None is invalid; "
                                            r"must be a granframe.VelocityGrid"):
            gf.collision_operator(name, None, KERNEL, LAW, NUMPY)


def test_api_string_kernel_is_a_type_error():
    grid = gf.VelocityGrid(2, 8, 2.0)
    with pytest.raises(TypeError, match=r"parameter 'kernel' = 'maxwell' is invalid; must be a "
                                        r"collision kernel"):
        gf.collision_operator("fast_spectral", grid, "maxwell", LAW, NUMPY)
    with pytest.raises(TypeError, match=r"parameter 'restitution' = 'constant' is invalid"):
        gf.collision_operator("fast_spectral", grid, KERNEL, "constant", NUMPY)


def test_api_string_backend_is_a_type_error():
    with pytest.raises(TypeError, match=r"parameter 'backend' = 'numpy' is invalid; must be a "
                                        r"granframe.ArrayBackend"):
        gf.collision_operator("fast_spectral", gf.VelocityGrid(2, 8, 2.0), KERNEL, LAW, "numpy")


def test_api_list_f_is_a_type_error():
    op = small_operator()
    with pytest.raises(TypeError, match=r"fast_spectral: parameter 'f' = 'list' is invalid; "
                                        r"must be a numpy array"):
        op(op.grid.maxwellian().tolist())


def test_temperature_of_zero_f_is_refused():
    grid = gf.VelocityGrid(2, 8, 2.0)
    zero = numpy.zeros(grid.shape)
    for moment in (grid.temperature, grid.kurtosis, grid.sonine_a2, grid.bulk_velocity):
        with pytest.raises(ValueError, match=r"parameter 'mass of f' = 0.0 is invalid; must be "
                                             r"nonzero: the mass is zero"):
            moment(zero)
    point = zero.copy()
    point[4, 4] = 1.0                                           # all mass at one velocity
    with pytest.raises(ValueError, match=r"'int \|v - u\|\^2 f dv' = 0.0 is invalid"):
        grid.kurtosis(point)


# -- 6. non-real and non-finite f ----------------------------------------------------------
def test_complex_f0_is_refused():
    grid = gf.VelocityGrid(2, 16, 4.0)

    def rotating(v1, v2):
        return numpy.exp(-(v1 ** 2 + v2 ** 2) / 2 + 1j * v1)

    with pytest.raises(ValueError, match=r"FromCallable: parameter 'function' = .* is invalid; "
                                         r"must return real values; .*max \|imaginary part\|"):
        FromCallable(rotating).sample(grid)


def test_complex_f0_with_a_round_off_imaginary_part_is_its_real_part():
    grid = gf.VelocityGrid(2, 16, 4.0)

    def nearly_real(v1, v2):
        return numpy.exp(-(v1 ** 2 + v2 ** 2) / 2) * (1 + 1e-15j)

    with warnings.catch_warnings():
        warnings.simplefilter("error")                          # no ComplexWarning
        f = FromCallable(nearly_real).sample(grid)
    assert f.dtype == float and numpy.array_equal(f, nearly_real(*grid.mesh()).real)


@pytest.mark.parametrize("name", ["fast_spectral", "direct_spectral"])
def test_non_finite_f_is_refused_by_the_operators(name, backend):
    grid = gf.VelocityGrid(2, 8, 2.0)
    op = gf.collision_operator(name, grid, KERNEL, LAW, backend)
    for bad in (numpy.nan, numpy.inf):
        f = grid.maxwellian()
        f[2, 3] = bad
        with pytest.raises(ValueError, match=rf"{name}: parameter 'f' = '1 non-finite values' "
                                             r"is invalid; must be finite everywhere"):
            evaluate_on_host(op, f)


# -- 7. adaptive tolerance ------------------------------------------------------------------
def test_dopri54_tolerance_below_round_off_is_refused():
    with pytest.raises(ValueError, match=r"'tolerance' = 1e-20 is invalid; must be >= 2.22e-14 "
                                         r"\(100 machine epsilons of the operator's float64\)"):
        heated(integrator="dopri54", time_step=None, tolerance=1e-20)
    single = {"name": "fast_spectral", "precision": "float32"}
    with pytest.raises(ValueError, match=r"'tolerance' = 1e-06 is invalid; must be >= 1.19e-05"):
        heated(integrator="dopri54", time_step=None, tolerance=1e-6, operator=single)
    heated(integrator="dopri54", time_step=None, tolerance=1e-10)


# -- 8. threads ----------------------------------------------------------------------------
def test_threads_100000_are_refused():
    with pytest.raises(ValueError, match=r"NumpyBackend: parameter 'threads' = 100000 is "
                                         r"invalid; must be an integer >= 1 and <= 1024"):
        gf.array_backend("numpy", threads=100000)
    with pytest.raises(ValueError, match=r"'threads' = 100000"):
        heated(backend={"name": "numpy", "threads": 100000})


# -- 9. the Nyquist projection of f0 --------------------------------------------------------
def test_nyquist_projection_changing_f0_is_refused():
    grid = {"dimension": 2, "n_modes": 12, "support_radius": 10.0}
    d = heated(grid=grid, health={"initial_mass_tolerance": 1e-4})
    with pytest.raises(ValueError, match=r"relative change of the temperature of f0 by the "
                                         r"Nyquist projection' = 0.09\d+ is invalid; must be <= "
                                         r"health.projection_tolerance = 0.02 \(temperature "
                                         r"7.9968\d* -> 7.2256\d*\): N = 12 modes do not resolve "
                                         r"f0; use a larger n_modes"):
        Simulation(d)
    # the case of 2D N = 16, S = 10: T 8 -> 7.957, kurtosis 2 -> 1.69, within the defaults
    small = heated(grid={**grid, "n_modes": 16})
    assert abs(Simulation(small).grid.temperature(Simulation(small).f0) - 7.9572) < 1e-4
    with pytest.raises(ValueError, match=r"temperature 8 -> 7.95721\)"):
        Simulation(small.replace(health={"projection_tolerance": 1e-3}))
    with pytest.raises(ValueError, match=r"kurtosis of f0 .* health.projection_kurtosis_tolerance"
                                         r" = 0.1 \(kurtosis 2 -> 1.6878"):
        Simulation(small.replace(health={"projection_kurtosis_tolerance": 0.1}))


def test_a_step_that_blows_up_within_its_stages_is_a_health_stop(tmp_path):
    """A heat bath far beyond the step limit (the check switched off): Q meets an infinite
    stage inside an RK4 step; the run is stopped and marked failed like any blow-up."""
    from granframe.run.runner import HealthError
    from granframe.run.storage import RunStore
    from test_runner import heated

    d = heated(heat_bath=1e100, health={"step_limit": False}, final_time=0.5)
    with pytest.raises(HealthError, match=r"step 1, t = 0: f is not finite \(NaN or Inf\) "
                                          "within the step"):
        Simulation(d).run(tmp_path / "s.zarr", progress=False)
    assert RunStore.open(tmp_path / "s.zarr").progress["status"] == "failed"


def test_the_nyquist_projection_of_f0_is_reported_and_stored(tmp_path, capsys):
    """The case of 2D N = 16, S = 10, T0 = 8: within the default tolerance, so the run goes
    on, but the change of T0 is said and kept with the run."""
    from granframe.tools.cli import main
    from granframe.run.storage import RunStore, describe
    from test_runner import heated

    d = heated(grid={"dimension": 2, "n_modes": 16, "support_radius": 10.0}, final_time=0.1,
               output={"snapshot_interval": 0.1})
    (tmp_path / "d.toml").write_text(d.to_toml())
    assert main(["run", str(tmp_path / "d.toml"), "--out", str(tmp_path / "s.zarr"),
                 "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "without its Nyquist modes" in err and "temperature 8 -> 7.957" in err
    stored = RunStore.open(tmp_path / "s.zarr").metadata["f0_projection"]
    assert stored["temperature"]["before"] == pytest.approx(8.0, rel=1e-6)
    assert stored["temperature"]["after"] == pytest.approx(7.957, rel=1e-4)
    assert "f0 projection" in describe(tmp_path / "s.zarr")
    # a resolved f0 runs without the note
    (tmp_path / "e.toml").write_text(heated(final_time=0.1,
                                             output={"snapshot_interval": 0.1}).to_toml())
    assert main(["run", str(tmp_path / "e.toml"), "--out", str(tmp_path / "e.zarr"),
                 "--no-progress"]) == 0
    assert "Nyquist" not in capsys.readouterr().err


@pytest.mark.parametrize("changes,parameter", [
    ({"support_radius": 1e308}, "support_radius"), ({"support_radius": 1e-320}, "support_radius"),
    ({"support_radius": 10.0, "half_width": 1e308}, "half_width"),
    ({"support_radius": 10.0, "truncation_radius": 1e300}, "truncation_radius")])
def test_velocity_scales_beyond_floating_point_range_are_refused(changes, parameter):
    with pytest.raises(ValueError, match=f"parameter '{parameter}'"):
        gf.VelocityGrid(dimension=2, n_modes=16, **changes)


# -- 8. extreme values, size-driving parameters and what the command line says -------------
@pytest.mark.parametrize("changes,parameter,allowed", [
    ({"output": {"snapshot_interval": 1.7e308}}, "snapshot_interval", r"\[1e-100, 1e\+100\]"),
    ({"knudsen": 1e300}, "knudsen", r"\[1e-100, 1e\+100\]"),
    ({"knudsen": 5e-324}, "knudsen", r"\[1e-100, 1e\+100\]"),
    ({"heat_bath": 1e300}, "heat_bath", r"\[0, 1e\+100\]"),
    ({"integrator": "dopri54", "tolerance": 1e300}, "tolerance", r"\[1e-100, 1e\+100\]"),
    ({"final_time": 1.7e308}, "final_time", r"\[1e-100, 1e\+100\]")])
def test_every_float_of_a_description_has_a_range_that_keeps_the_arithmetic_finite(
        changes, parameter, allowed):
    with pytest.raises(ValueError, match=rf"parameter '{parameter}' = .* is invalid; must lie "
                                         rf"in {allowed}"):
        heated(**changes)


def test_a_huge_knudsen_number_runs_and_resumes(tmp_path):
    """eps = 9.2e18 (Q/eps negligible): the run finishes, and a resume of it says so."""
    from granframe.run.storage import RunStore
    from granframe.tools.cli import main

    d = heated(grid={"dimension": 2, "n_modes": 16, "support_radius": 10.0}, knudsen=9.2e18,
               final_time=0.1)
    (tmp_path / "d.toml").write_text(d.to_toml())
    arguments = ["run", str(tmp_path / "d.toml"), "--out", str(tmp_path / "s.zarr"),
                 "--no-progress"]
    assert main(arguments) == 0
    assert main(arguments + ["--resume"]) == 0
    assert RunStore.open(tmp_path / "s.zarr").progress["status"] == "finished"


def test_a_truncation_radius_beyond_the_box_is_refused_before_the_operator_is_built():
    """R = 1e30 made the default quadratures 4096 x 2048 points: minutes of building."""
    with pytest.raises(ValueError, match=r"parameter 'grid.truncation_radius' = 1e\+30 is "
                                         r"invalid; must be <= 2 sqrt\(d\) L = 62.4264"):
        heated(grid={"dimension": 2, "n_modes": 32, "support_radius": 10.0,
                     "truncation_radius": 1e30})
    heated(grid={"dimension": 2, "n_modes": 32, "support_radius": 10.0,
                 "truncation_radius": 62.0})


def _cli(tmp_path, capsys, *arguments):
    """``granframe ARGUMENTS`` run in ``tmp_path``: (status, stderr)."""
    from granframe.tools.cli import main

    status = main([str(a) for a in arguments])
    return status, capsys.readouterr().err


@pytest.mark.parametrize("command", ["run", "limits"])
def test_run_and_limits_refuse_a_precision_that_is_a_list_alike(tmp_path, capsys, command):
    (tmp_path / "d.toml").write_text(heated().to_toml())
    out = ["--out", tmp_path / "s.zarr"] if command == "run" else []
    status, err = _cli(tmp_path, capsys, command, tmp_path / "d.toml", *out,
                       "--set", "operator.precision=[1.0, 2.0]")
    assert status == 2 and "unhashable" not in err
    assert ("parameter 'operator.precision' = [1.0, 2.0] is invalid; must be one of "
            "['float64', 'float32']") in err
    assert not (tmp_path / "s.zarr").exists()


@pytest.mark.parametrize("initial", [
    {"name": "riemann", "left": {"density": 1.0}, "right": {"density": 0.5}},
    {"name": "sinusoidal_mode"}])
def test_space_initial_data_without_a_space_section_is_refused(initial):
    """It ran the average over the interval as a homogeneous run and said 'finished'."""
    with pytest.raises(ValueError, match=rf"parameter 'initial' = '{initial['name']}' is "
                                         r"invalid; applies to space runs only: add a \[space\]"):
        heated(initial=initial)


def test_a_toml_key_typo_gets_the_closest_key_and_private_state_is_not_listed():
    text = heated().to_toml().replace("heat_bath", "heat_bth")
    with pytest.raises(TypeError, match=r"'heat_bth' = 0.1 is invalid; is not a parameter of "
                                        r"RunDescription; known: .*; did you mean 'heat_bath'\?"
                       ) as info:
        RunDescription.from_toml(text)
    assert "_light" not in str(info.value) and "light" not in str(info.value)


@pytest.mark.parametrize("command", ["run", "limits", "sweep", "advise"])
def test_a_binary_file_is_refused_naming_it(tmp_path, capsys, command):
    (tmp_path / "bin.toml").write_bytes(bytes(range(128, 256)) * 4)
    out = ["--out", tmp_path / "s.zarr"] if command in ("run", "sweep") else []
    status, err = _cli(tmp_path, capsys, command, tmp_path / "bin.toml", *out)
    assert status == 2 and f"'{tmp_path / 'bin.toml'}' is invalid; it is not UTF-8 text" in err
    assert not (tmp_path / "s.zarr").exists()


@pytest.mark.parametrize("command", ["run", "limits"])
def test_a_study_that_exits_is_an_error_not_a_silent_success(tmp_path, capsys, command):
    (tmp_path / "exits.py").write_text("import sys\nsys.exit(0)\n")
    out = ["--out", tmp_path / "s.zarr"] if command == "run" else []
    status, err = _cli(tmp_path, capsys, command, tmp_path / "exits.py", *out)
    assert status == 2
    assert "is invalid; it called sys.exit(0) while granframe loaded it" in err


def test_space_keys_can_be_set_on_the_command_line(tmp_path, capsys):
    """space.collisions was 'not a key of the description'; the walls' parameters are keys."""
    from test_space_bad_input import BASE
    import tomli_w

    (tmp_path / "d.toml").write_text(tomli_w.dumps(BASE))
    status, err = _cli(tmp_path, capsys, "limits", tmp_path / "d.toml", "--set",
                       "space.collisions=false", "--set", "kernel.name=hard_spheres")
    assert status == 0, err
    status, err = _cli(tmp_path, capsys, "limits", tmp_path / "d.toml", "--set",
                       "space.right.accomodation=0.5")
    assert status == 2 and "did you mean 'space.right.accommodation'?" in err


# -- messages show what the user gave ------------------------------------------------------

def test_a_string_for_a_list_of_thresholds_is_shown_as_written():
    """It was shown as a tuple of its characters, ('0', '.', '1')."""
    from test_space_bad_input import table

    for key in ("realizability", "distance"):
        with pytest.raises(TypeError, match=rf"parameter 'hierarchy.{key}' = '0.1' is "
                                             r"invalid; must be a list of 2 numbers"):
            RunDescription.from_dict(table(("integrator", "penalised_euler"),
                                           ("conservative", True),
                                           ("space.hierarchy", {key: "0.1"})))


def test_a_hierarchy_without_the_correction_shows_what_conservative_is():
    """It showed conservative = None, a value the user cannot write."""
    from test_space_bad_input import table

    for value in (False, None):
        changes = [("integrator", "penalised_euler"), ("space.hierarchy", {})]
        if value is not None:
            changes.append(("conservative", value))
        with pytest.raises(ValueError, match=r"parameter 'conservative' = False is invalid; "
                                             r"must be set \(true, or a weight\)"):
            RunDescription.from_dict(table(*changes))


def test_numpy_scalars_are_shown_as_numbers():
    from granframe.parallel import partition
    from granframe.validators import reject

    with pytest.raises(ValueError, match=r"^partition: parameter 'partition' = \[21, 3\] is "):
        partition(24, 4, 2, 2, [numpy.int64(21), numpy.int64(3)])
    with pytest.raises(ValueError, match=r"parameter 'y' = \(0.5, 2\) is invalid"):
        reject("X", "y", (numpy.float64(0.5), numpy.int32(2)), "")
    with pytest.raises(ValueError, match=r"parameter 'y' = 0.25 is invalid"):
        reject("X", "y", numpy.float32(0.25), "")


@pytest.mark.parametrize("command", ["run", "limits", "advise", "sweep"])
def test_a_directory_is_refused_as_a_directory_and_a_store_as_a_store(tmp_path, capsys,
                                                                      command):
    """A store directory was 'no such file'."""
    store = tmp_path / "run.zarr"
    Simulation(heated(final_time=0.02, time_step=0.01)).run(store, progress=False)
    plain = tmp_path / "plain"
    plain.mkdir()
    out = ["--out", tmp_path / "s.zarr"] if command in ("run", "sweep") else []
    status, err = _cli(tmp_path, capsys, command, store, *out)
    assert status == 2 and "is a zarr store (a run's or a sweep's), not a file;" in err, err
    assert "granframe info" in err and err.count("\n") == 1
    status, err = _cli(tmp_path, capsys, command, plain, *out)
    assert status == 2 and "is a directory, not a file;" in err, err
    status, err = _cli(tmp_path, capsys, command, tmp_path / "missing.toml", *out)
    assert status == 2 and "no such file" in err, err
    assert not (tmp_path / "s.zarr").exists()


@pytest.mark.parametrize("method", ["mass", "momentum", "temperature", "kurtosis",
                                    "pressure_tensor", "heat_flux", "moments", "project"])
def test_the_grid_refuses_an_f_that_is_not_an_array_by_name(method):
    grid = gf.VelocityGrid(2, 8, 4.0)
    with pytest.raises(TypeError, match=r"^VelocityGrid: parameter 'f' = \[1, 2\] is invalid; "
                                        r"must be an array of the grid shape \(8, 8\)"):
        getattr(grid, method)([1, 2])
