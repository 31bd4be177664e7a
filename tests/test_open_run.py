"""granframe.open_run: a run store as an xarray Dataset, checked, cut to its last commit,
with CF attributes that netCDF accepts; the same attributes in the zarr store itself."""

import numbers
import shutil

import numpy
import pytest
import xarray
import zarr

import granframe as gf
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore, StoreDamagedError, StoreError
from test_runner import heated
from test_store_safety import flip
from test_unbuilt_description import _refuse_building_cupy, write_gpu_store

VARIABLES = {"f", "snapshot_step", "snapshot_dt_next", "step", "dt", "mass", "temperature",
             "kinetic_energy", "min_f", "negative_mass_fraction", "kurtosis", "sonine_a2",
             "momentum", "pressure_tensor", "heat_flux"}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished 2D run: 20 steps of 0.05, snapshots every 0.25 (5 of them)."""
    store = tmp_path_factory.mktemp("open_run") / "run.zarr"
    Simulation(heated()).run(store, progress=False)
    return store


@pytest.fixture
def copy(finished, tmp_path):
    """A copy of the finished run to damage."""
    return shutil.copytree(finished, tmp_path / "copy.zarr")


def netcdf_value(value) -> bool:
    """True for what a netCDF attribute holds: a string, a number, or a list of either."""
    if isinstance(value, list):
        return all(isinstance(v, (str, numbers.Real)) for v in value)
    return isinstance(value, (str, numbers.Real)) and not isinstance(value, bool)


def test_open_run_labels_every_array_with_dimensions_coordinates_and_units(finished):
    ds = gf.open_run(finished)
    assert "open_run" in gf.__all__
    assert dict(ds.sizes) == {"time": 5, "step_time": 21, "v1": 32, "v2": 32, "axis": 2,
                              "axis2": 2}
    assert set(ds.coords) == {"time", "step_time", "v1", "v2", "axis", "axis2"}
    assert set(ds.data_vars) == VARIABLES
    assert ds.f.dims == ("time", "v1", "v2") and ds.momentum.dims == ("step_time", "axis")
    assert ds.temperature.dims == ds.step.dims == ("step_time",)
    assert ds.snapshot_step.dims == ("time",)
    assert list(ds.axis.values) == list(ds.axis2.values) == ["v1", "v2"]
    assert ds.pressure_tensor.dims == ("step_time", "axis", "axis2")
    assert ds.heat_flux.dims == ("step_time", "axis")
    assert ds.f.dtype == ds.time.dtype == ds.mass.dtype == numpy.float64
    assert ds.step.dtype == ds.snapshot_step.dtype == numpy.int64
    numpy.testing.assert_allclose(ds.time.values, [0, 0.25, 0.5, 0.75, 1.0], atol=1e-14)
    for name, variable in ds.variables.items():
        if name not in ("axis", "axis2"):
            assert variable.attrs["units"] == "1", name
        assert variable.attrs["long_name"], name
    assert ds.f.attrs["long_name"] == "distribution function f(t, v)"
    assert ds.v2.attrs["long_name"] == "velocity component v2"
    assert ds.momentum.sel(axis="v1").dims == ("step_time",)


def test_open_run_gives_flat_cf_root_attributes(finished):
    attrs = gf.open_run(finished).attrs
    assert attrs["Conventions"] == "CF-1.10" and attrs["title"] == "test"
    assert attrs["source"] == f"granframe {gf.__version__}"
    meta = RunStore.open(finished).metadata
    assert attrs["history"].startswith(meta["created"])
    assert "created by granframe run" in attrs["history"]
    assert "arXiv:2001.11206" in attrs["references"]
    assert "1/(2 pi) in 2D" in attrs["nondimensionalisation"]
    assert "|g|/(4 pi) in 3D" in attrs["nondimensionalisation"]
    assert RunDescription.from_toml(attrs["description_toml"]) == heated()
    assert attrs["provenance_operator"].startswith("fast_spectral (plugin 'spectral'")
    assert attrs["provenance_cpus"] == meta["provenance"]["cpus"]
    assert attrs["f0_projection_temperature_before"] == \
        meta["f0_projection"]["temperature"]["before"]
    assert attrs["progress_status"] == "finished"
    assert attrs["progress_snapshots"] == 5 and attrs["progress_records"] == 21
    assert "granframe" not in attrs and "rescaling_rate" not in attrs
    bad = {key: value for key, value in attrs.items() if not netcdf_value(value)}
    assert not bad


def test_open_run_values_are_the_stores_arrays(finished):
    ds = gf.open_run(finished)
    group = zarr.open_group(str(finished), mode="r")
    assert sorted(group.array_keys()) == sorted(set(ds.variables) - {"axis", "axis2"})
    for name in group.array_keys():
        numpy.testing.assert_array_equal(ds[name].values, group[name][:], err_msg=name)


def test_the_zarr_store_itself_carries_the_cf_attributes(finished):
    plain, ds = xarray.open_zarr(finished), gf.open_run(finished)
    for name, variable in plain.variables.items():
        assert variable.attrs == ds[name].attrs, name
    flat = {key: value for key, value in ds.attrs.items() if not key.startswith("progress_")}
    assert {key: value for key, value in plain.attrs.items() if key != "granframe"} == flat
    # granframe's own entry is kept as it was: the reader and --resume depend on it
    meta = plain.attrs["granframe"]
    assert meta["schema"] == "granframe.run/2" and meta["progress"]["status"] == "finished"
    assert RunDescription.from_dict(meta["description"]) == heated()


def test_the_dataset_round_trips_through_netcdf(finished, tmp_path):
    ds = gf.open_run(finished)
    ds.to_netcdf(tmp_path / "run.nc")
    assert (tmp_path / "run.nc").read_bytes()[:4] == b"\x89HDF"     # netCDF-4: holds int64
    with xarray.open_dataset(tmp_path / "run.nc") as back:
        xarray.testing.assert_identical(back.load(), ds.load())
        assert back.step.dtype == numpy.int64


def test_a_commit_cut_short_is_not_shown(copy):
    """A kill after the data of a commit but before its progress: the data beyond the
    last commit stays in the arrays and is cut off."""
    cut = RunStore.open(copy, mode="r+")
    meta = cut.metadata
    meta["progress"] = dict(meta["progress"], snapshots=3, records=11, step=10, time=0.5,
                            status="running")
    cut.group.attrs["granframe"] = meta
    ds = gf.open_run(copy)
    assert ds.sizes["time"] == 3 and ds.sizes["step_time"] == 11
    group = zarr.open_group(str(copy), mode="r")
    assert group["f"].shape[0] == 5 and group["mass"].shape[0] == 21
    numpy.testing.assert_array_equal(ds.f.values, group["f"][:3])
    numpy.testing.assert_array_equal(ds.momentum.values, group["momentum"][:11])
    assert ds.step_time.values[-1] == ds.time.values[-1] == 0.5
    assert ds.attrs["progress_status"] == "running"


@pytest.mark.parametrize("damage, match", [
    (lambda s: (s / "f" / "c" / "1" / "0" / "0").unlink(), "missing chunk f/c/1/0/0"),
    (lambda s: flip(s / "mass" / "c" / "0"), "damaged chunk mass/c/0"),
    (lambda s: (s / "step" / "c" / "0").unlink(), "missing chunk step/c/0"),
    (lambda s: shutil.rmtree(s / "dt"), "missing array dt"),
], ids=["missing snapshot", "damaged moments", "missing steps", "missing array"])
def test_a_damaged_store_is_refused(copy, damage, match):
    damage(copy)
    with pytest.raises(StoreDamagedError, match=match):
        gf.open_run(copy)


def test_a_damaged_snapshot_raises_when_it_is_read(copy):
    flip(copy / "f" / "c" / "2" / "0" / "0")
    ds = gf.open_run(copy)
    assert ds.f.isel(time=1).values.max() > 0
    with pytest.raises(ValueError, match="checksum"):
        ds.f.isel(time=2).values


def test_a_store_whose_creation_was_cut_short_is_refused(tmp_path):
    """What a kill before the first commit leaves: the staged store, with no commit."""
    description = heated()
    staged = RunStore.create(tmp_path / "new.zarr", description.to_dict(),
                             description.to_toml(), description.grid, {})
    try:
        with pytest.raises(StoreDamagedError, match="holds no commit: its creation was cut "
                                                    "short"):
            gf.open_run(staged.path)
    finally:
        staged.discard()


def test_a_replacement_cut_short_and_other_paths_are_refused(copy, tmp_path):
    copy.rename(copy.parent / f".{copy.name}.granframe-old-0123456789ab")
    with pytest.raises(StoreError, match="replacement was cut short"):
        gf.open_run(copy)
    with pytest.raises(StoreError, match="does not exist"):
        gf.open_run(tmp_path / "nothing.zarr")
    zarr.open_group(str(tmp_path / "other.zarr"), mode="w")
    with pytest.raises(StoreError, match="is not a granframe run store"):
        gf.open_run(str(tmp_path / "other.zarr"))
    with pytest.raises(TypeError, match="open_run: parameter 'path' = 42 is invalid; must be "
                                        "the path"):
        gf.open_run(42)


def test_a_cupy_store_opens_without_building_its_backend(tmp_path, monkeypatch):
    store = tmp_path / "gpu.zarr"
    write_gpu_store(store)
    _refuse_building_cupy(monkeypatch)
    ds = gf.open_run(store)
    assert ds.sizes["time"] == 3 and ds.attrs["provenance_backend"].startswith("cupy")
    ds.to_netcdf(tmp_path / "gpu.nc")


def test_a_rescaled_run_states_its_variables(tmp_path):
    from test_rescaling import _description

    Simulation(_description(final_time=1.0)).run(tmp_path / "r.zarr", progress=False)
    ds = gf.open_run(tmp_path / "r.zarr")
    law = RunStore.open(tmp_path / "r.zarr").metadata["rescaling"]
    assert ds.attrs["rescaling_rate"] == law["rate"]
    assert ds.attrs["rescaling_degree"] == law["degree"]
    assert ds.attrs["rescaling_velocity"] == law["velocity"]
    assert "time and step_time are the rescaled time s" in ds.attrs["nondimensionalisation"]
    ds.to_netcdf(tmp_path / "r.nc")
    with xarray.open_dataset(tmp_path / "r.nc") as back:
        numpy.testing.assert_array_equal(back.attrs["rescaling_velocity"], law["velocity"])


def test_a_space_run_opens_with_its_fields_on_the_time_axis(tmp_path):
    """``time_axis="steps"``: ``ds.temperature.sel(time=t)`` is the profile of the step at t,
    the snapshots of f are along ``snapshot_time``, and both agree where they meet."""
    from test_space_store import DESCRIPTION

    store = tmp_path / "sod.zarr"
    Simulation(DESCRIPTION).run(store, progress=False)
    default, steps = gf.open_run(store), gf.open_run(store, time_axis="steps")
    assert steps.temperature.dims == ("time", "x") and steps.f.dims[:2] == ("snapshot_time", "x")
    assert steps.sizes["time"] == default.sizes["step_time"] == 9
    assert steps.sizes["snapshot_time"] == default.sizes["time"] == 5
    t = float(default.time.values[2])
    profile = steps.temperature.sel(time=t, method="nearest")
    numpy.testing.assert_array_equal(profile.values,
                                     default.temperature.sel(step_time=t, method="nearest"))
    assert float(profile.time) == pytest.approx(t)
    numpy.testing.assert_array_equal(steps.f.sel(snapshot_time=t).values,
                                     default.f.sel(time=t).values)
    assert steps.time.attrs == default.step_time.attrs
    with pytest.raises(ValueError, match="'time_axis' = 'records' is invalid"):
        gf.open_run(store, time_axis="records")


def hierarchy_description() -> RunDescription:
    """The Sod tube of ``test_space_store`` (24 cells), 4 steps to t = 0.012, with the default
    hierarchy of collision models, euler, esbgk and boltzmann (and conservative, which a
    hierarchy needs)."""
    from test_space_store import TOML

    text = TOML.replace("final_time = 0.024", "final_time = 0.012")
    return RunDescription.from_toml("conservative = true\n" + text + "[space.hierarchy]\n")


@pytest.fixture(scope="module")
def hierarchy_store(tmp_path_factory):
    """A finished space run with a hierarchy: 5 records of 24 cells."""
    store = tmp_path_factory.mktemp("levels") / "levels.zarr"
    Simulation(hierarchy_description()).run(store, progress=False)
    return store


def test_the_levels_of_a_hierarchy_are_variables_named_by_their_models(hierarchy_store,
                                                                        tmp_path):
    ds = gf.open_run(hierarchy_store)
    group = zarr.open_group(str(hierarchy_store), mode="r")
    for name, dtype in (("level", numpy.int64), ("realizability", numpy.float64),
                        ("distance", numpy.float64)):
        assert ds[name].dims == ("step_time", "x") and ds[name].dtype == dtype, name
        assert ds[name].shape == (5, 24)
        numpy.testing.assert_array_equal(ds[name].values, group[name][:], err_msg=name)
        assert ds[name].attrs["units"] == "1"
        assert not ds[name].attrs["long_name"].startswith("velocity component"), name
    level = ds.level.attrs
    assert level["levels"] == ["euler", "esbgk", "boltzmann"]
    assert level["flag_meanings"] == "euler esbgk boltzmann"
    assert level["flag_values"].dtype == numpy.int64
    numpy.testing.assert_array_equal(level["flag_values"], [0, 1, 2])
    assert set(numpy.unique(ds.level.values)) <= {0, 1, 2}
    # the indicators are measured after the collision step: none at t = 0
    assert numpy.isnan(ds.realizability.isel(step_time=0)).all()
    assert numpy.isfinite(ds.distance.isel(step_time=-1)).all()
    assert gf.open_run(hierarchy_store, time_axis="steps").level.dims == ("time", "x")
    ds.to_netcdf(tmp_path / "levels.nc")
    with xarray.open_dataset(tmp_path / "levels.nc") as back:
        xarray.testing.assert_identical(back.load(), ds.load())
        assert back.level.dtype == numpy.int64
        assert list(back.level.attrs["levels"]) == level["levels"]
