"""Smoke tests: every study of the review's numerical section runs in its --quick variant and
writes its report (figures and summary.json). The full runs are made once (docs/reproduction.md)."""

import csv
import importlib.util
import json
import pathlib
import subprocess
import sys

import numpy
import pytest

from granframe.tools.cli import main

STUDIES = pathlib.Path(__file__).parent.parent / "studies"
REPORTS = {
    "review_test1.py": ({"a", "b", "c", "b_fine", "c_fine", "c_smooth"}, "max_T_error",
                        {"test1_a.png", "test1_c_fine.png"}),
    "review_test2.py": ({f"{k}_e{e}" for k in ("maxwell", "hard_spheres") for e in (0.3, 0.5, 0.7)},
                        "noise_floor", {"test2_tails.png"}),
    "review_test3.py": ({"haff_tanh0.8", "haff_const0.2", "lambda0.5", "heated_e0.95",
                         "lambda1_S5"}, "T_final",
                        {"test3_haff.png", "test3_lambda.png", "test3_heated.png",
                         "test3_resolution.png"}),
    "space.py": ({"sod_eps0.01", "sod_eps0.001", "sod_eps0.0001", "walls_heat",
                  "walls_balance"}, "cells",
                 {"space_sod_profiles.png", "space_walls_heat.png", "space_walls_balance.png"}),
}


@pytest.mark.parametrize("study", sorted(REPORTS))
def test_quick_study_runs_and_reports(study, tmp_path, capsys):
    runs, key, figures = REPORTS[study]
    assert main(["run", str(STUDIES / study), "--quick", "--out", str(tmp_path)]) == 0
    assert "report:" in capsys.readouterr().out
    summary = json.loads((tmp_path / "report" / "summary.json").read_text())
    assert runs <= set(summary) and all(key in summary[run] for run in runs)
    assert figures <= {p.name for p in (tmp_path / "report").iterdir()}


def test_flat_data_limits_test1_and_its_smoothing_restores_spectral_accuracy():
    """Test 1(c)'s claim in docs/reproduction.md: with M = 32 the discrete dissipation rate
    of the sharp box is off by ~1e-3, of the box with edges smoothed over one unit by ~2e-6."""
    study = _load_study("review_test1")
    [row] = study.flat_data_dissipation([(64, 10.0, 32)])
    assert row["smooth"] < 1e-5 and row["sharp"] > 1e-4, row


def _load_study(name):
    spec = importlib.util.spec_from_file_location(name, STUDIES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_pareto_front_keeps_exactly_the_non_dominated_configurations():
    study = _load_study("accuracy_vs_cost")
    records = [{"seconds": s, "error": e} for s, e in
               [(1, 1e-2), (2, 1e-4), (2, 1e-3), (3, 1e-4), (4, 1e-8), (0.5, 1.0), (4, 1e-8),
                (5, 1.05e-8), (6, 5e-9)]]
    # (2, 1e-3) and (3, 1e-4) are beaten by (2, 1e-4); (5, 1.05e-8) buys only 5 % of error
    assert study.pareto(records) == [True, True, False, False, True, True, True, False, True]


def test_accuracy_vs_cost_quick_writes_fronts(tmp_path):
    study = _load_study("accuracy_vs_cost")
    summary = study.run(tmp_path, quick=True)
    for scene in ("bkw_2d", "heated_2d"):
        assert {f"{scene}.csv", f"{scene}.png"} <= {p.name for p in tmp_path.iterdir()}
        front = summary[scene]["front"]
        assert front and all(a["seconds"] <= b["seconds"] and a["error"] > b["error"]
                             for a, b in zip(front, front[1:]))
    # float32 costs no accuracy where the discretisation error dominates (BKW, N = 32)
    rows = list(csv.DictReader((tmp_path / "bkw_2d.csv").read_text().splitlines()))
    errors = {r["precision"]: float(r["error"]) for r in rows
              if r["N"] == "32" and r["method"] == "fast_spectral"}
    assert errors["float32"] == pytest.approx(errors["float64"], rel=1e-3)
    assert json.loads((tmp_path / "summary.json").read_text()) == summary


def test_stability_map_quick_separates_explicit_and_penalised(tmp_path):
    """At eps = 1e-3, dt = 0.01 (above RK4's predicted limit 2.79e-3) RK4 blows up and the
    penalised Euler scheme stays stable; at eps = 1 both are accurate."""
    study = _load_study("stability_map")
    summary = study.run(tmp_path, quick=True)
    rows = list(csv.DictReader((tmp_path / "collisions.csv").read_text().splitlines()))
    verdict = {(r["scheme"], float(r["eps"]), float(r["dt"])): r["verdict"] for r in rows}
    assert verdict[("rk4", 1e-3, 0.01)] == "unstable"
    assert verdict[("penalised_euler", 1e-3, 0.01)] == "accurate"
    assert verdict[("rk4", 1.0, 0.1)] == verdict[("penalised_euler", 1.0, 0.1)] == "accurate"
    assert summary["collisions"]["unpredicted_blow_ups"] == []
    assert (tmp_path / "collisions.png").stat().st_size > 10_000


def test_aliasing_quick_shows_the_box_bound(tmp_path, capsys):
    """BKW 2D with R = 2S: L = 1.5 S aliases (error 7e-3), L = 2.21 S does not (2e-8);
    through the study's command line (granframe.tools.studykit.command)."""
    assert _load_study("aliasing").main(["--out", str(tmp_path), "--quick"]) == 0
    assert "L/S = 2.21" in capsys.readouterr().out
    rows = list(csv.DictReader((tmp_path / "aliasing.csv").read_text().splitlines()))
    errors = {float(row["L_over_S"]): float(row["error"]) for row in rows}
    assert errors[1.5] > 1e-3 and errors[2.21] < 1e-7, errors


def test_strong_inelasticity_quick_loses_more_positivity_as_e_falls(tmp_path):
    """N = 32 to t = 1: sticky collisions (e = 0) leave a larger negative-mass share than
    e = 0.9; both are reported with min f / max f and the temperature error."""
    rows = _load_study("strong_inelasticity").run(tmp_path, quick=True)["rows"]
    share = {row["e"]: row["negative_share"] for row in rows}
    assert share[0.0] > 2 * share[0.9] > 0, share
    assert all(row["T_error"] < 1e-2 for row in rows)
    assert (tmp_path / "inelasticity.png").exists()


def test_free_cooling_quick_unscaled_fails_where_rescaled_holds(tmp_path):
    """2D hard spheres to t = 10 on N = 32: the unscaled solution leaves the reference and
    loses positivity; the rescaled one keeps both. The cooling state is not a Maxwellian."""
    summary = _load_study("free_cooling").run(tmp_path, quick=True)
    rows = {row["formulation"]: row for row in summary["concentration"]}
    assert rows["direct"]["t_T_error_1e-3"] is not None
    assert rows["direct"]["t_negative_share_1e-2"] is not None
    assert rows["rescaled"]["t_T_error_1e-3"] is None
    assert rows["rescaled"]["final_negative_share"] < 1e-5
    assert summary["hcs"][0]["a2"] > 0.02               # e = 0.5: overpopulated tails
    assert summary["maxwell"][0]["max_T_error"] < 5e-3
    for name in ("concentration.png", "hcs.png", "maxwell_tails.png", "sonine.csv"):
        assert (tmp_path / name).exists()


def test_sonine_moments_reproduce_the_first_sonine_approximation():
    """The quadrature of the collisional moments gives van Noije & Ernst's closed form of the
    first Sonine a2 and their cooling-rate factor mu_2 = mu_2^0 (1 + 3 a2/16 + a3/64) in 3D;
    the second approximation lowers a2 where a3 < 0 (strong inelasticity)."""
    study = _load_study("free_cooling")
    for e in (0.3, 0.8):
        first, second, a3 = study.sonine_approximations(e)
        assert abs(first - study.sonine_a2(e, 3)) < 1e-12
    moments = study.sonine_collision_moments(0.5)
    assert abs(moments[(2, 2)] / moments[(2, 0)] - 3 / 16) < 1e-12
    assert abs(moments[(2, 3)] / moments[(2, 0)] - 1 / 64) < 1e-12
    first, second, a3 = study.sonine_approximations(0.3)
    assert a3 < 0 and second < first


def test_maxwell_moment_equations_match_the_operator():
    """The exact m_2 and m_4 equations of 2D inelastic Maxwell molecules (the reference of the
    kurtosis table in docs/stability.md) against the resolved spectral Q of a non-Maxwellian
    isotropic f (N = 64, S = 6); elastic limit: the Maxwellian kurtosis 2 is stationary."""
    import granframe as gf

    study = _load_study("free_cooling")
    operator = study._operator("maxwell", 2, 64, 6.0, 0.5, 32, gf.CircleTrapezoid(32))
    grid = operator.grid
    f = 0.5 * grid.maxwellian(temperature=0.6) + 0.5 * grid.maxwellian(temperature=1.4)
    q, speed2 = operator(f), grid.speed_squared()
    m2, m4, dm2, dm4 = ((speed2 ** k * g).sum() * grid.cell_volume
                        for g, k in ((f, 1), (f, 2), (q, 1), (q, 2)))
    rate, a, b = study.maxwell_moment_rates(0.5)
    assert abs(dm2 / (-rate * m2) - 1) < 1e-5
    assert abs(dm4 / (a * m4 + b * m2 * m2) - 1) < 1e-4
    assert abs(study.maxwell_kurtosis(50.0, 1.0) - 2.0) < 1e-12
    # the m_4 coefficient two ways; at e = 0.5 the scaled 6th moment settles, the 8th grows
    assert abs(study.maxwell_moment_growth(4, 0.5) - (a + 2 * rate)) < 1e-12
    assert study.maxwell_moment_growth(6, 0.5) < 0 < study.maxwell_moment_growth(8, 0.5)


def test_advise_validation_quick_meets_the_tolerance(tmp_path):
    """One scene: the advised run meets its tolerance against the converged reference, and the
    brute-force search finds a configuration that meets it too (the cost ratio is measured in
    docs/advise.md, not asserted)."""
    row = _load_study("advise_validation").run(tmp_path, quick=True)["rows"][0]
    assert row["advised_meets"] and row["advised_error"] <= row["tolerance"]
    assert row["cheapest_error"] <= row["tolerance"]
    assert (tmp_path / "advise_validation.png").exists()


def test_heated_state_sweep_quick_runs_on_one_and_two_workers(tmp_path):
    """The sweep study on LocalClusters of 1 and 2 workers: every run finishes, Maxwell
    molecules hold the exact steady temperature T = 1, and the sweep file is written."""
    pytest.importorskip("distributed")
    summary = _load_study("heated_state_sweep").run(tmp_path, quick=True)
    assert summary["finished"] == summary["runs"] == 4
    assert summary["maxwell_max_T_error"] < 1e-4
    assert set(summary["wall_seconds"]) == {"1", "2"}
    assert (tmp_path / "sweep.toml").exists() and (tmp_path / "heated_state.png").exists()


@pytest.mark.parametrize("study, argv, message", [
    ("euler_limit.py", ["--cells", "0"],
     "argument --cells: '0' is not allowed: must be an integer in [1, inf]"),
    ("euler_limit.py", ["--cells", "3"],
     "error: RunDescription: parameter 'space.cells' = 3 is invalid; must be >= 5"),
    ("space_transport.py", ["--dt", "-1"],
     "argument --dt: '-1' is not allowed: must be a number in (0, inf]"),
    ("space_transport.py", ["--modes", "16,x"],
     "argument --modes: 'x' is not allowed: must be an integer in [1, inf]"),
    ("scaling.py", ["--steps", "0"],
     "argument --steps: '0' is not allowed: must be an integer in [1, inf]"),
    ("hierarchy.py", ["--thresholds", "abc"],
     "argument --thresholds: 'abc' is not allowed: must be a number in (0, inf]"),
    ("hierarchy.py", ["--scenes", "sod_1e-3,bogus"],
     "argument --scenes: 'bogus' not allowed: choose from sod_1e-3, sod_1e-2, walls"),
    ("granular_hcs_2d.py", ["--cells", "6"],
     "--cells [6]: WENO5 needs at least 7 cells per side"),
    ("cavity_2d.py", ["--restitution", "1.5"],
     "--restitution [1.5]: each e must be in (0, 1]"),
    ("shock_reflection_2d.py", ["--cells", "16", "--reference", "100"],
     "--reference 100 must be a multiple of twice every --cells value ([16])"),
    ("hierarchy_2d.py", ["--hierarchy", '{"buffer": -1}'],
     "parameter 'buffer' = -1 is invalid; must be an integer >= 0 and <= 64"),
    ("hierarchy_2d.py", ["--hierarchy", "[1]"],
     "argument --hierarchy: '[1]' is not allowed: must be a JSON object"),
])
def test_study_commands_refuse_bad_options_by_name_without_a_traceback(tmp_path, study, argv,
                                                                      message):
    """A bad option ends a study's command with status 2 and a message naming the option,
    the value and what is allowed (argparse's, or granframe's refusal through
    ``studykit.finish``), never a traceback."""
    command = [sys.executable, str(STUDIES / study), "--out", str(tmp_path)] + argv
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert message in done.stderr


def test_the_plane_cooling_study_measures_what_it_names():
    """granular_hcs_2d's helpers: the structure factor puts a density mode's power in its
    shell (Parseval: the shell's points hold the variance times C^2); the vorticity of a
    lattice of vortices u = (-a sin 2 pi y, a sin 2 pi x) is 2 pi a (cos 2 pi x + cos 2 pi y)
    to the central differences' accuracy; the sine amplitude of a diagonal shear mode is its
    amplitude."""
    import math

    import xarray

    study = _load_study("granular_hcs_2d")
    cells = 16
    x = (numpy.arange(cells) + 0.5) / cells
    X, Y = numpy.meshgrid(x, x, indexing="ij")
    rho = 1.0 + 0.1 * numpy.sin(2 * math.pi * 2 * X)
    shells = study.structure_factor(rho[None])[0]
    assert numpy.argmax(shells) == 1 and shells[[0, 2, 3]].max() < 1e-28
    n = numpy.fft.fftfreq(cells, 1.0 / cells)
    count = (numpy.rint(numpy.hypot(n[:, None], n[None, :])) == 2).sum()
    assert shells[1] * count == pytest.approx(((rho - 1.0) ** 2).sum(), rel=1e-12)
    a = 0.2
    velocity = numpy.stack([-a * numpy.sin(2 * math.pi * Y), a * numpy.sin(2 * math.pi * X)],
                           axis=-1)
    wave = 0.05 * numpy.sin(2 * math.pi * (X + Y))
    shear = numpy.stack([-wave, wave], axis=-1) / math.sqrt(2.0)
    ds = xarray.Dataset(
        {"velocity": (("step_time", "x", "y", "axis"), numpy.stack([velocity, shear])),
         "temperature": (("step_time", "x", "y"), numpy.ones((2, cells, cells))),
         "density": (("step_time", "x", "y"), numpy.stack([rho, rho]))},
        coords={"x": x, "y": x, "time": ("step_time", [0.0, 1.0])})
    exact = 2 * math.pi * a * (numpy.cos(2 * math.pi * X) + numpy.cos(2 * math.pi * Y))
    factor = math.sin(2 * math.pi / cells) / (2 * math.pi / cells)     # central differences
    numpy.testing.assert_allclose(study.vorticity(ds, 0), factor * exact, atol=1e-12)
    s, amplitude = study.plane_amplitude(ds, "shear")
    assert amplitude[1] == pytest.approx(0.05, rel=1e-12)



def test_a_refinement_row_measures_against_the_reference_and_the_coarser_run():
    """studykit.refinement_row: the L1 error of a run against the fine reference averaged
    onto its cells, the reference's own bar (its coarse run against its fine one) and the
    change from the next coarser run, each checked against its hand-computed value on
    fields along one axis averaged in pairs."""
    from granframe.tools.studykit import refinement_row

    def average(fields, cells):
        return {k: v.reshape(cells, -1).mean(axis=1) for k, v in fields.items()}

    x8 = (numpy.arange(8) + 0.5) / 8
    fine = {"rho": numpy.repeat(1 + x8, 2)}                 # 16 cells, piecewise on 8
    coarse = {"rho": numpy.repeat(1 + x8 + 0.01, 2)}
    runs = {4: {"rho": average({"rho": 1 + x8}, 4)["rho"] + 0.1},
            8: {"rho": 1 + x8 - 0.02}}
    first = refinement_row({4: runs[4]}, 4, fine, coarse, average)
    assert set(first) == {"L1_rho", "reference_bar_rho"}
    assert first["L1_rho"] == pytest.approx(0.1) and first["reference_bar_rho"] == \
        pytest.approx(0.01)
    second = refinement_row(runs, 8, fine, coarse, average)
    assert second["L1_rho"] == pytest.approx(0.02)
    assert second["change_rho"] == pytest.approx(0.12)      # 0.1 - (-0.02), on 4 cells
