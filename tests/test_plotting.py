"""Plotting functions on the Dataset of a run store, and ``granframe plot``."""

import numpy
import pytest
import xarray
from matplotlib.colors import LogNorm
from matplotlib.contour import QuadContourSet
from matplotlib.figure import Figure

import granframe
from granframe.run.description import Hierarchy, RunDescription
from granframe.run.runner import Simulation
from granframe.tools import plotting
from granframe.tools.cli import main

from test_open_run import hierarchy_description
from test_runner import heated
from test_unbuilt_description import _refuse_building_cupy, write_gpu_store

#: Every plotting function that draws one panel, with the options it is drawn with.
PANELS = {"temperature": (plotting.temperature, {}),
          "temperature_error": (plotting.temperature_error, {}),
          "mass_drift": (plotting.mass_drift, {}),
          "kurtosis": (plotting.kurtosis, {}),
          "positivity": (plotting.positivity, {}),
          "entropy": (plotting.entropy, {}),
          "slices": (plotting.slices, {}),
          "slices_log": (plotting.slices, {"scale": "log"}),
          "contour_first": (plotting.contour, {"index": 0}),
          "contour_last": (plotting.contour, {})}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """A heated Maxwell-molecule run: 2D, N = 32, dt = 0.05 to t = 1, five snapshots."""
    path = tmp_path_factory.mktemp("plotting") / "run.zarr"
    Simulation(heated()).run(path, progress=False)
    return path


@pytest.fixture
def ds(store):
    with xarray.open_zarr(store, consolidated=False) as data:
        yield data


def _axes():
    return Figure(layout="constrained").subplots()


def _with_description(ds, **replace):
    """``ds`` with its stored description's TOML text edited (old -> new), where
    ``open_zarr`` shows it: at the root and in the ``granframe`` metadata."""
    text = ds.attrs["granframe"]["description_toml"]
    for old, new in replace.values():
        assert old in text
        text = text.replace(old, new)
    edited = ds.copy()
    edited.attrs = {**ds.attrs, "description_toml": text,
                    "granframe": {**ds.attrs["granframe"], "description_toml": text}}
    return edited


@pytest.mark.parametrize("name", PANELS)
def test_each_function_draws_into_the_given_axes_with_labelled_axes(ds, name):
    draw, options = PANELS[name]
    ax = _axes()
    assert draw(ds, ax=ax, **options) is ax
    assert ax.has_data()
    assert "(dimensionless)" in ax.get_xlabel() and "(dimensionless)" in ax.get_ylabel()
    assert ax.get_title()


def test_without_axes_a_function_makes_a_captioned_figure(ds):
    import matplotlib.pyplot as plt

    ax = plotting.kurtosis(ds)
    try:
        assert "N = 32" in ax.figure.get_suptitle() and "dt = 0.05" in ax.figure.get_suptitle()
    finally:
        plt.close(ax.figure)


def test_the_caption_states_the_parameters_and_that_quantities_are_dimensionless(ds):
    text = plotting.caption(ds)
    for part in ("test", "2D, N = 32", "dt = 0.05 (rk4)", "τ = 0.1", "ε = 1",
                 "fast_spectral(radial_points=16, sphere=circle_trapezoid(n_points=8))",
                 "e: constant(value=0.5)", "kernel maxwell, exponent λ = 0",
                 "all quantities dimensionless"):
        assert part in text
    drawn = plotting.figures(ds)
    assert set(drawn) == {"temperature", "entropy", "slices", "contour", "moments"}
    for fig in drawn.values():
        assert fig.get_suptitle() == text
        for ax in fig.axes:
            assert ax.get_ylabel(), (fig.get_suptitle(), ax.get_title())


def test_positivity_is_the_negative_share_on_a_log_axis(ds):
    ax = plotting.positivity(ds, ax=_axes())
    assert ax.get_yscale() == "log"
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert any("negative mass share" in label for label in labels)
    assert any("positivity_tolerance" in label for label in labels)
    for line in ax.get_lines():                 # zeros left out, not drawn at a floor
        values = numpy.asarray(line.get_ydata(), dtype=float)
        assert (values[~numpy.isnan(values)] > 0).all()


@pytest.mark.parametrize("scale", ["linear", "log"])
def test_slices_have_a_marker_at_each_grid_point(ds, scale):
    ax = plotting.slices(ds, ax=_axes(), scale=scale)
    drawn = [line for line in ax.get_lines() if len(line.get_xdata())]
    assert len(drawn) >= 5
    assert all(line.get_marker() not in ("None", "", None) for line in drawn)
    assert all(len(line.get_xdata()) == 32 for line in drawn)
    assert ax.get_yscale() == scale


def test_contour_levels_start_at_zero_with_round_ticks_and_negative_values_apart(ds):
    ax = plotting.contour(ds, ax=_axes(), index=0)
    filled = [c for c in ax.collections if isinstance(c, QuadContourSet) and c.filled]
    assert len(filled) == 1
    levels = filled[0].levels
    assert levels[0] == 0.0 and filled[0].extend == "min"
    assert all(float(f"{level:.2g}") == pytest.approx(level, abs=1e-15) for level in levels)
    assert "t = 0," in ax.get_title()


def test_entropy_against_the_last_snapshot_says_it_vanishes_there_by_construction(ds):
    ax = plotting.entropy(ds, ax=_axes())
    assert "last snapshot" in ax.get_title() and "by construction" in ax.get_title()
    assert ax.get_yscale() == "log"


def test_entropy_of_an_elastic_run_is_taken_against_the_exact_maxwellian(tmp_path):
    path = tmp_path / "elastic.zarr"
    Simulation(heated(restitution={"name": "constant", "value": 1.0}, heat_bath=0.0,
                      initial={"name": "bkw", "time": 0.0}, time_step=0.1, final_time=2.0,
                      grid={"dimension": 2, "n_modes": 32, "support_radius": 4.0},
                      output={"snapshot_interval": 0.5})).run(path, progress=False)
    with xarray.open_zarr(path, consolidated=False) as data:
        ax = plotting.entropy(data, ax=_axes())
    assert "exact equilibrium" in ax.get_title() and "by construction" not in ax.get_title()
    values = ax.get_lines()[0].get_ydata()
    assert len(values) == 5 and values[0] > values[-1] > 0


def test_a_run_without_an_exact_temperature_law_shows_the_mass_drift(ds):
    other = _with_description(ds, kernel=('[kernel]\nname = "maxwell"',
                                          '[kernel]\nname = "hard_spheres"'))
    with pytest.raises(ValueError, match="temperature_error: parameter 'ds' = 'test' .*exact "
                                         "temperature law"):
        plotting.temperature_error(other, ax=_axes())
    right = plotting.figures(other)["temperature"].axes[1]
    assert "mass drift" in right.get_ylabel()
    assert "exponent λ = 1" in plotting.caption(other)


def test_the_figures_of_open_run_match_those_of_open_zarr(ds, store):
    opened = granframe.open_run(store)
    assert "granframe" not in opened.attrs          # flat attributes only
    assert plotting.caption(opened) == plotting.caption(ds)
    for name, draw in (("slices", plotting.slices), ("positivity", plotting.positivity)):
        ours, theirs = draw(opened, ax=_axes()), draw(ds, ax=_axes())
        for a, b in zip(ours.get_lines(), theirs.get_lines()):
            numpy.testing.assert_array_equal(a.get_ydata(), b.get_ydata(), err_msg=name)


def test_only_committed_snapshots_and_records_are_drawn(ds):
    meta = ds.attrs["granframe"]
    cut = ds.copy()
    cut.attrs = {"description_toml": meta["description_toml"],
                 "progress_snapshots": 2, "progress_records": 6}
    assert "t = 0.25," in plotting.contour(cut, ax=_axes()).get_title()
    assert plotting.kurtosis(cut, ax=_axes()).get_lines()[0].get_xdata()[-1] == 0.25
    with pytest.raises(TypeError, match="plot: parameter 'ds' = 'Dataset' is invalid; must be "
                                        "the Dataset of a granframe run store"):
        plotting.caption(xarray.Dataset())


def test_bad_options_of_the_functions_are_refused_by_name(ds, store, tmp_path):
    with pytest.raises(ValueError, match="slices: parameter 'scale' = 'symlog'"):
        plotting.slices(ds, ax=_axes(), scale="symlog")
    with pytest.raises(ValueError, match="contour: parameter 'index' = 5 .* from -5 to 4"):
        plotting.contour(ds, ax=_axes(), index=5)
    with pytest.raises(ValueError, match="plot: parameter 'format' = 'jpg' .* png, pdf, svg"):
        plotting.plot(store, tmp_path, format="jpg")
    with pytest.raises(ValueError, match="plot: parameter 'dpi' = 0 .* from 10 to 600"):
        plotting.plot(store, tmp_path, dpi=0)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("fmt, magic", [("pdf", b"%PDF"), ("svg", b"<?xml")])
def test_plot_format_writes_vector_files(store, tmp_path, capsys, fmt, magic):
    out = tmp_path / "figures"
    assert main(["plot", str(store), "--out", str(out), "--format", fmt]) == 0
    names = {p.name for p in out.iterdir()}
    assert names == {f"{n}.{fmt}" for n in ("temperature", "entropy", "slices", "contour",
                                            "moments")}
    assert all((out / n).read_bytes().startswith(magic) for n in names)
    assert str(out / f"temperature.{fmt}") in capsys.readouterr().out


def test_plot_dpi_sets_the_png_resolution(store, tmp_path):
    def width(path):
        return int.from_bytes(path.read_bytes()[16:20], "big")      # the PNG IHDR width

    assert main(["plot", str(store), "--out", str(tmp_path / "a"), "--dpi", "40"]) == 0
    assert main(["plot", str(store), "--out", str(tmp_path / "b"), "--dpi", "80"]) == 0
    small, large = width(tmp_path / "a" / "moments.png"), width(tmp_path / "b" / "moments.png")
    assert large == pytest.approx(2 * small, rel=0.02)


@pytest.mark.parametrize("value", ["0", "-5", "9", "601", "nan", "inf", "high"])
def test_plot_refuses_a_bad_dpi_naming_the_option(store, tmp_path, capsys, value):
    with pytest.raises(SystemExit) as stop:
        main(["plot", str(store), "--out", str(tmp_path / "f"), "--dpi", value])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --dpi: must be a number from 10 to 600, got '{value}'" in err
    assert not (tmp_path / "f").exists()


def test_plot_refuses_an_unknown_format_naming_the_option(store, tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["plot", str(store), "--out", str(tmp_path / "f"), "--format", "jpg"])
    assert "argument --format: invalid choice: 'jpg'" in capsys.readouterr().err


def test_the_figures_of_a_store_written_with_the_cupy_backend_are_drawn_on_a_cpu(
        tmp_path, monkeypatch):
    path = tmp_path / "gpu.zarr"
    write_gpu_store(path)
    _refuse_building_cupy(monkeypatch)
    with xarray.open_zarr(path, consolidated=False) as data:
        assert RunDescription.from_toml(data.attrs["description_toml"]).backend.name == "cupy"
        drawn = plotting.figures(data)
    assert set(drawn) == {"temperature", "entropy", "slices", "contour", "moments"}
    assert "N = 32" in drawn["contour"].get_suptitle()
    assert [p.name for p in plotting.plot(path, tmp_path / "fig", format="svg")][0] == \
        "temperature.svg"


def test_the_caption_of_an_adaptive_run_gives_the_range_of_its_steps(ds):
    adaptive = _with_description(ds, integrator=('[integrator]\nname = "rk4"',
                                                 '[integrator]\nname = "dopri54"'),
                                 tolerance=("heat_bath = ", "tolerance = 1e-6\nheat_bath = "))
    assert "dt = 0.05..0.05 (adaptive dopri54, tolerance 1e-06)" in plotting.caption(adaptive)


@pytest.fixture(scope="module")
def hierarchy_store(tmp_path_factory):
    """A Sod tube with the default hierarchy of collision models: 5 records of 24 cells."""
    path = tmp_path_factory.mktemp("levels") / "levels.zarr"
    Simulation(hierarchy_description()).run(path, progress=False)
    return path


def _without_hierarchy(ds):
    """``ds`` as the store of the same run without a hierarchy shows it: no
    ``space.hierarchy`` in its description and no level records."""
    table = RunDescription.from_toml(ds.attrs["description_toml"]).to_dict()
    del table["space"]["hierarchy"]
    plain = ds.drop_vars(["level", "realizability", "distance", "reach"])
    plain.attrs = {**ds.attrs, "description_toml": RunDescription.from_dict(table).to_toml()}
    return plain


def test_a_hierarchy_is_drawn_as_maps_of_levels_and_indicators_and_the_shares(
        hierarchy_store):
    ds = granframe.open_run(hierarchy_store)
    names = ["euler", "esbgk", "boltzmann"]
    drawn = plotting.figures(ds)
    assert set(drawn) == {"maps", "profiles", "totals", "levels"}
    panels = [ax for ax in drawn["levels"].axes if ax.get_label() != "<colorbar>"]
    level, shares, kappa, delta = panels
    # one quad per cell and record, one colour per level, named on the colour bar
    mesh = level.collections[0]
    numpy.testing.assert_array_equal(mesh.get_array().reshape(5, 24), ds.level.values)
    assert mesh.cmap.N == mesh.norm.Ncmap == 3
    assert [t.get_text() for t in mesh.colorbar.ax.get_yticklabels()] == names
    assert level.get_title() == "collision model of each cell (t, x)"
    # the shares are stacked up to one, and their means over the steps are in the title
    assert [t.get_text() for t in shares.get_legend().get_texts()] == names
    top = shares.collections[-1].get_paths()[0].vertices[:, 1]
    assert top.max() == pytest.approx(1.0)
    steps = ds.level.values[1:]
    assert ", ".join(f"{name} {(steps == k).mean():.0%}" for k, name in enumerate(names)) \
        in shares.get_title()
    # the indicators on a log scale, blank where not measured (t = 0), thresholds marked
    for ax, name in ((kappa, "realizability"), (delta, "distance")):
        mesh = ax.collections[0]
        assert isinstance(mesh.norm, LogNorm), name
        blank = numpy.ma.getmaskarray(mesh.get_array()).reshape(5, 24)
        assert blank[0].all() and not blank[1:].any(), name
        marks = [line.get_ydata()[0] for line in mesh.colorbar.ax.get_lines()]
        assert marks == list(getattr(Hierarchy(), name)), name
    assert kappa.get_title().startswith(r"Navier-Stokes realizability $\kappa$(t, x): max ")
    with xarray.open_zarr(hierarchy_store, consolidated=False) as data:     # the same
        same = plotting.level_map(data, ax=_axes()).collections[0].get_array()
    numpy.testing.assert_array_equal(same, ds.level.values)


def test_without_a_hierarchy_no_levels_are_drawn(hierarchy_store, ds):
    levels = granframe.open_run(hierarchy_store)
    plain = _without_hierarchy(levels)
    assert set(plotting.figures(plain)) == {"maps", "profiles", "totals"}
    for draw in (plotting.level_map, plotting.level_shares, plotting.indicator_map):
        with pytest.raises(ValueError, match=f"{draw.__name__}: parameter 'ds' .* hierarchy "
                                             "of collision models"):
            draw(plain, ax=_axes())
    with pytest.raises(ValueError, match="level_shares: parameter 'ds' .* must be a space run"):
        plotting.level_shares(ds, ax=_axes())
    with pytest.raises(ValueError, match="indicator_map: parameter 'indicator' = 'kappa' .* "
                                         "realizability, distance"):
        plotting.indicator_map(levels, "kappa", ax=_axes())


def test_a_figure_says_its_warnings_in_one_line(tmp_path):
    """The figures' caption names each warning's topic, cell and remedy in one line (the
    full warnings took a quarter of the level map); granframe info keeps them in full."""
    import granframe as gf
    from granframe.run.description import RunDescription
    from granframe.run.runner import Simulation

    description = RunDescription(
        title="short caption", grid={"dimension": 2, "n_modes": 24, "support_radius": 3.5},
        kernel="maxwell", restitution={"name": "constant", "value": 1.0},
        initial={"name": "riemann", "left": {"density": 1.0, "temperature": 1.0},
                 "right": {"density": 1.0, "temperature": 0.6}},
        time_step=0.01, final_time=0.02, output={"snapshot_interval": 0.01}, knudsen=0.1,
        space={"cells": 6, "left": {"name": "diffuse", "temperature": 1.0},
               "right": {"name": "diffuse", "temperature": 0.6}})
    result = Simulation(description).run(tmp_path / "r.zarr", progress=False)
    assert result.warnings
    ds = gf.open_run(tmp_path / "r.zarr")
    full, short = plotting.caption(ds), plotting.caption(ds, short=True)
    assert f"UNDER-RESOLVED: {result.warnings[0]}" in full.splitlines()
    last = short.splitlines()[-1]
    assert last.startswith("UNDER-RESOLVED velocity resolution (in cell ")
    assert "raise grid.n_modes" in last and last.endswith("the warnings in full)")
    assert len(short.splitlines()) == len(full.splitlines()) - len(result.warnings) \
        - len(result.accuracy_warnings) + 1
