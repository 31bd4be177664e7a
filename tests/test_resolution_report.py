"""The resolution indicators reported at every output point and at the end of a run."""

import math

import numpy
import pytest

import granframe as gf
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore, describe
from granframe.tools.cli import main
from granframe.velocity.estimators import TAIL_ERROR_FACTOR, resolution_report


def _run(n_modes=32, support=4.0, temperature=1.0, **health):
    return RunDescription(
        title="resolution", grid={"dimension": 2, "n_modes": n_modes, "support_radius": support},
        kernel="maxwell", restitution={"name": "constant", "value": 0.9},
        initial={"name": "maxwellian", "temperature": temperature},
        operator={"name": "fast_spectral", "radial_points": 8,
                  "sphere": {"name": "circle_trapezoid", "n_points": 8}},
        backend={"name": "numpy", "threads": 1}, time_step=0.05, final_time=0.1,
        output={"snapshot_interval": 0.05}, health=health)


def test_indicators_of_a_maxwellian_are_its_closed_forms():
    grid = gf.VelocityGrid(2, 32, 4.0)
    t = 1.3
    report = resolution_report(grid, grid.maxwellian(temperature=t), 0.0, 1e-3)
    k = math.pi * (grid.n_modes / 2 - 1) / grid.half_width
    assert report["spectral_tail"] == pytest.approx(math.exp(-t * k * k / 2), rel=1e-2)
    assert report["tail_error"] == TAIL_ERROR_FACTOR * report["spectral_tail"]
    # 2D: the relative velocity is Maxwellian at 2T, share beyond R = exp(-R^2 / (4T)); the
    # lags are grid points, whose cells of h = 0.55 cut the circle |g| = R: 10 % at R = 8
    assert report["pairs_beyond_support"] == pytest.approx(math.exp(-(8.0 ** 2) / (4 * t)),
                                                           rel=0.15)
    assert report["warnings"] == []


def test_each_indicator_names_what_to_raise():
    grid = gf.VelocityGrid(2, 16, 4.0)
    narrow = grid.maxwellian(temperature=0.05)          # N = 16 does not resolve it
    warnings = resolution_report(grid, narrow, 2e-3, 1e-3)["warnings"]
    assert warnings[0].startswith("velocity resolution: spectral tail ")
    assert "> health.resolution_tolerance = 0.001; raise grid.n_modes (N = 16)" in warnings[0]
    assert warnings[1] == ("positivity: negative mass share 0.002 > health.resolution_tolerance"
                           " = 0.001; f oscillates, raise grid.n_modes (N = 16)")
    grid = gf.VelocityGrid(2, 64, 4.0)
    (support,) = resolution_report(grid, grid.maxwellian(temperature=2.0), 0.0, 1e-4)["warnings"]
    assert support == ("support: share 0.000361 of pairs with relative speed beyond R = 2S = 8 "
                       "> health.resolution_tolerance = 0.0001; raise grid.support_radius")


def test_an_under_resolved_run_warns_at_the_end_and_in_info(tmp_path, capsys):
    # T = 1 on N = 20, S = 4: a tail exp(-T (pi 9 / L)^2 / 2) = 6e-3 of hat f is cut off
    d = _run(n_modes=20)
    path = tmp_path / "coarse.zarr"
    result = Simulation(d).run(path, progress=False)
    assert result.status == "finished"
    assert result.warnings and "raise grid.n_modes (N = 20)" in result.warnings[0]
    progress = RunStore.open(path).progress
    assert progress["resolution"]["warnings"] == list(result.warnings)
    assert progress["resolution"]["tail_error"] > 1e-3
    text = describe(path)
    assert "resolution  at t = 0.1 (the last commit): spectral tail " in text
    assert f"  warning: {result.warnings[0]}" in text
    # the CLI prints it when the run ends
    (tmp_path / "coarse.toml").write_text(d.to_toml())
    assert main(["run", str(tmp_path / "coarse.toml"), "--out", str(tmp_path / "cli.zarr"),
                 "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "granframe: warning: f at t = 0.1 is under-resolved: velocity resolution:" in err


def test_a_resolved_run_has_no_warning_and_the_tolerance_is_a_setting(tmp_path):
    resolved = Simulation(_run()).run(tmp_path / "fine.zarr", progress=False)
    assert resolved.warnings == ()
    report = RunStore.open(tmp_path / "fine.zarr").progress["resolution"]
    assert report["tail_error"] < 1e-3 and report["warnings"] == []
    strict = Simulation(_run(resolution_tolerance=1e-12)).run(tmp_path / "strict.zarr",
                                                             progress=False)
    assert any(w.startswith("support: share ") for w in strict.warnings)
    with pytest.raises(ValueError, match="resolution_tolerance"):
        _run(resolution_tolerance=0.0)


def test_a_value_just_above_the_tolerance_is_not_rounded_onto_it():
    grid = gf.VelocityGrid(2, 32, 4.0)
    (warning,) = resolution_report(grid, grid.maxwellian(), 0.0010004, 1e-3)["warnings"]
    assert "negative mass share 0.0010004 > health.resolution_tolerance = 0.001;" in warning


def test_the_figures_of_an_under_resolved_run_say_so(tmp_path):
    import xarray

    from granframe.tools import plotting

    path = tmp_path / "coarse.zarr"
    result = Simulation(_run(n_modes=20)).run(path, progress=False)
    for ds in (gf.open_run(path), xarray.open_zarr(path, consolidated=False)):
        text = plotting.caption(ds)
        assert f"UNDER-RESOLVED: {result.warnings[0]}" in text.splitlines()
    resolved = tmp_path / "fine.zarr"
    Simulation(_run()).run(resolved, progress=False)
    assert "UNDER-RESOLVED" not in plotting.caption(gf.open_run(resolved))
