import importlib
import importlib.util
import pathlib
import signal
import textwrap

import pytest

import granframe as gf
from granframe.registry import Registries, get_plugin_manager
from granframe_cupy import gpu_available

FAKE_SITE = pathlib.Path(__file__).parent / "fake_site"

# A suite started in the background (``pytest &``, ``nohup pytest &`` from a script) has
# SIGINT ignored, as a shell sets for its background jobs, and every process it starts
# inherits that: the tests that Ctrl-C a granframe process would send a signal it never
# sees. They test Ctrl-C, so the suite sets it up: Python's handler here, which the
# processes started from here receive as the default disposition.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

#: Test files whose every test is marked ``slow`` (runs of studies, space
#: validation, resume and kill tests in subprocesses, sweeps on Dask, fuzzing): the fast
#: subset ``pytest -m "not slow"`` leaves them out (README, "Tests").
SLOW_FILES = frozenset({
    "test_bench_space.py", "test_cli_fuzz.py", "test_fault_injection.py",
    "test_resume.py", "test_space_validation.py", "test_store_safety.py", "test_studies.py",
    "test_sweep.py", "test_validation_fuzz.py",
})

#: Tests marked ``slow`` one by one (``file::name``, every parametrisation), from the
#: durations of ``pytest -m "not slow" --durations=80`` on this 2-core machine: those of
#: about 5 s of CPU time or more (runs to an exact law, 3D runs, plots of stores, CLI runs).
SLOW_TESTS = frozenset({
    "test_mpi.py::test_a_process_killed_mid_run_ends_the_run_and_the_store_resumes_on_any_count",
    "test_mpi.py::test_runs_on_two_and_three_processes_equal_the_serial_run",
    "test_advise.py::test_isotropic_3d_temperature_is_not_run_at_full_resolution",
    "test_default_quadrature.py::test_default_3d_n32_heated_maxwell_temperature_law_holds_to_2e5",
    "test_operators.py::test_float32_heated_maxwell_temperature",
    "test_operators.py::test_hard_sphere_dissipation_in_3d_against_the_exact_rate",
    "test_operators.py::test_heated_maxwell_limited_by_truncation_radius",
    "test_operators.py::test_heated_maxwell_temperature_of_the_review",
    "test_plotting.py::test_plot_dpi_sets_the_png_resolution",
    "test_plotting.py::test_plot_format_writes_vector_files",
    "test_plotting.py::test_the_figures_of_a_store_written_with_the_cupy_backend_are_drawn_on_a_cpu",
    "test_plugins.py::test_cli_bench_runs_and_reports_the_floor",
    "test_pressure_tensor.py::test_a_heated_2d_run_at_small_knudsen_follows_the_exact_pressure_law",
    "test_pressure_tensor.py::test_a_heated_3d_run_follows_the_exact_pressure_law",
    "test_pressure_tensor.py::test_a_store_without_pressure_records_opens_checks_plots_and_resumes",
    "test_rescaling.py::test_hard_spheres_rescaled_run_equals_the_unscaled_one",
    "test_rescaling.py::test_maxwell_molecules_follow_the_exact_cooling_law_in_physical_variables",
    "test_rescaling.py::test_plots_of_a_rescaled_run_are_in_physical_time_and_temperature",
    "test_runner.py::test_a_store_written_on_a_gpu_is_read_on_a_machine_without_one",
    "test_runner.py::test_cli_run_plot_info",
    "test_runner.py::test_resume_discards_a_commit_cut_short",
    "test_space_bad_input.py::test_fuzzed_space_initial_conditions_build_or_name_a_parameter",
    "test_space_collisions.py::test_the_edge_monitors_flag_the_worst_cell_of_a_narrow_box",
    "test_space_limits.py::test_energy_balance_between_diffuse_walls",
    "test_space_limits.py::test_sod_tube_reaches_the_euler_solution_as_eps_vanishes",
    "test_space_limits.py::test_uniform_granular_gas_cools_by_the_homogeneous_law_in_every_cell",
    "test_space_limits.py::test_uniform_heated_granular_gas_follows_the_heated_law_in_every_cell",
    "test_space_store.py::test_a_run_killed_at_any_write_opens_as_before_or_resumes_bitwise",
    "test_space_store.py::test_plot_draws_maps_profiles_and_totals",
    "test_store_blocks.py::test_blocks_in_any_order_give_the_store_commit_gives",
    "test_unbuilt_description.py::test_a_cupy_store_is_read_without_building_its_backend",
})


def pytest_collection_modifyitems(config, items):
    """Mark ``slow`` every test of :data:`SLOW_FILES` and those of :data:`SLOW_TESTS`."""
    for item in items:
        name = item.path.name
        if name in SLOW_FILES or f"{name}::{getattr(item, 'originalname', item.name)}" in (
                SLOW_TESTS):
            item.add_marker(pytest.mark.slow)

_GPU = [pytest.mark.gpu, pytest.mark.skipif(not gpu_available(),
                                            reason="needs CuPy and a CUDA GPU")]

#: Every array backend a backend-parametrised test body runs on: registry name, options,
#: marks. "cupy-host" is the CuPy backend's code path with NumPy on the host (module =
#: "numpy"); "cupy" and "cupy-generic" run on a GPU, with the fused kernels and with the
#: generic xp steps.
BACKENDS = {
    "numpy": ("numpy", {}, []),
    "pyfftw": ("pyfftw", {}, [pytest.mark.skipif(not importlib.util.find_spec("pyfftw"),
                                                 reason="pyfftw not installed")]),
    "cupy-host": ("cupy", {"module": "numpy"}, []),
    "cupy": ("cupy", {}, _GPU),
    "cupy-generic": ("cupy", {"fused": False}, _GPU),
}


@pytest.fixture(scope="session", params=[pytest.param(key, marks=marks, id=key)
                                         for key, (_, _, marks) in BACKENDS.items()])
def backend_table(request):
    """Run-description table of each array backend of :data:`BACKENDS`."""
    name, options, _ = BACKENDS[request.param]
    return {"name": name, **options}


@pytest.fixture(scope="session")
def backend(backend_table):
    """Each array backend of :data:`BACKENDS`, built (one test body for all of them)."""
    table = dict(backend_table)
    return gf.array_backend(table.pop("name"), **table)


@pytest.fixture
def fresh_registries():
    """Build registries from scratch (the process-wide cache is left alone)."""

    def build():
        importlib.invalidate_caches()
        return Registries(*get_plugin_manager())

    return build


@pytest.fixture
def make_distribution(tmp_path, monkeypatch):
    """Create an installed-looking distribution (module + .dist-info) on sys.path."""

    def make(dist_name: str, module_name: str, source: str, entry_point: str | None = None):
        site = tmp_path / f"site_{dist_name}"
        # installers write the normalised name (PEP 491): "a-b" -> "a_b"
        info = site / f"{dist_name.replace('-', '_')}-0.1.dist-info"
        info.mkdir(parents=True)
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist_name}\nVersion: 0.1\n")
        (info / "entry_points.txt").write_text(
            f"[granframe]\n{entry_point or module_name} = {module_name}\n")
        (site / f"{module_name}.py").write_text(textwrap.dedent(source))
        monkeypatch.syspath_prepend(str(site))
        return site

    return make


def mutated(table: dict, changes) -> dict:
    """``table`` (a description table, changed in place) with dotted keys set (None: removed);
    a string where a table is needed becomes ``{name = ...}``."""
    for key, value in changes:
        *parents, last = key.split(".")
        node = table
        for part in parents:
            child = node.get(part)
            node[part] = child = child if isinstance(child, dict) else (
                {"name": child} if isinstance(child, str) else {})
            node = child
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return table
