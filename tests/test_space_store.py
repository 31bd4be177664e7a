"""The store of a space run in the reading tools, and its resume and kill safety.

``granframe.open_run`` labels its x and wall dimensions and every new array (and writes
netCDF), ``granframe info`` describes it, ``granframe check`` finds a damaged block of f,
``granframe plot`` draws its x-t maps, profiles and totals; a run stopped after its
first commit, or killed (SIGKILL) at an arbitrary write, resumes to the uninterrupted
result bit for bit.
"""

import pathlib
import random
import subprocess
import sys

import numpy
import pytest
import xarray
import zarr

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation, StorageObserver
from granframe.run.storage import RunStore, StoreDamagedError, check, describe
from granframe.tools import plotting
from granframe.tools.cli import main

HARNESS = pathlib.Path(__file__).with_name("kill_at_write.py")

#: 2D N = 16, a Sod tube of 24 cells in 3 blocks of 8, elastic Maxwell molecules,
#: a specular left wall and a diffuse right one at T = 1.2; 8 steps, 4 commits after f0
TOML = """\
final_time = 0.024
time_step = 0.003
[grid]
dimension = 2
n_modes = 16
support_radius = 3.2
[kernel]
name = "maxwell"
[restitution]
name = "constant"
value = 1.0
[initial]
name = "riemann"
left = {density = 1.0, temperature = 1.0}
right = {density = 0.125, temperature = 0.8}
[operator]
name = "fast_spectral"
[backend]
name = "numpy"
threads = 1
[space]
cells = 24
block_cells = 8
left = "specular"
right = {name = "diffuse", temperature = 1.2, accommodation = 1.0}
[output]
snapshot_interval = 0.006
"""
DESCRIPTION = RunDescription.from_toml(TOML)
FIELDS = ("density", "velocity", "temperature", "pressure_tensor", "heat_flux")

#: runs the description in ARGV[2] into the store ARGV[3] (resumed when ARGV[4] is
#: "resume"), killed at write ARGV[1] by the harness of kill_at_write.py (0: none)
DRIVER = """\
import sys
sys.path.insert(0, {tests!r})
import kill_at_write
kill_at_write.install(int(sys.argv[1]), open(sys.argv[2] + ".log", "w", buffering=1))
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
description = RunDescription.from_toml(open(sys.argv[2]).read())
Simulation(description).run(sys.argv[3], resume=sys.argv[4] == "resume", progress=False)
"""


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("space") / "space.zarr"
    Simulation(DESCRIPTION).run(path, progress=False)
    return path


def contents(path) -> dict:
    """Every array of a store, read back whole."""
    group = zarr.open_group(str(path), mode="r", use_consolidated=False)
    return {name: group[name][:] for name in group.array_keys()}


def assert_same(got: dict, reference: dict, what: str) -> None:
    assert sorted(got) == sorted(reference), what
    for name in reference:
        numpy.testing.assert_array_equal(got[name], reference[name], err_msg=f"{what}: {name}")


# -- open_run ---------------------------------------------------------------------------
def test_open_run_labels_cells_walls_and_every_array_and_writes_netcdf(store, tmp_path):
    ds = granframe.open_run(store)
    assert list(ds["wall"].values) == ["left", "right"]
    assert "left at x = 0" in ds["wall"].attrs["long_name"]
    assert ds["x"].attrs == {"long_name": "cell centre", "units": "1"}
    numpy.testing.assert_allclose(ds["x"].values, (numpy.arange(24) + 0.5) / 24, rtol=1e-15)
    expected = {"density": "density rho = int f dv of each cell",
                "velocity": "bulk velocity u = int v f dv / rho of each cell",
                "temperature": "temperature int |v-u|^2 f dv / (d rho) of each cell",
                "pressure_tensor": "pressure tensor int (v-u)_i (v-u)_j f dv of each cell",
                "heat_flux": "heat flux int (v-u)_i |v-u|^2 f dv / 2 of each cell",
                "mass": "total mass int int f dv dx",
                "kinetic_energy": "total kinetic energy int int |v|^2/2 f dv dx",
                "f": "distribution function f(t, x, v), cell averages"}
    for name, long_name in expected.items():
        assert ds[name].attrs == {"long_name": long_name, "units": "1"}, name
    for name in ("wall_mass", "wall_energy"):
        assert ds[name].dims == ("step_time", "wall")
        assert "entered the interval through the wall over the step" in \
            ds[name].attrs["long_name"]
    # the totals are the integrals of the fields over x, to round-off
    numpy.testing.assert_allclose(ds["mass"].values, ds["density"].sum("x").values / 24,
                                  rtol=1e-14)
    # a Sod tube between a specular and a diffuse wall neither gains nor loses mass, and
    # what the walls let in balances the change of the total mass
    mass = ds["mass"].values
    entered = numpy.cumsum(ds["wall_mass"].sum("wall").values)
    assert numpy.abs(mass - mass[0] - entered).max() < 1e-14
    assert ds["wall_energy"].sel(wall="right").values[1:].min() > 0    # the warmer wall
    ds.to_netcdf(tmp_path / "space.nc")
    with xarray.open_dataset(tmp_path / "space.nc") as back:
        assert list(back["wall"].values) == ["left", "right"]
        assert back["density"].attrs["long_name"] == expected["density"]
        numpy.testing.assert_array_equal(back["f"].values, ds["f"].values)


def test_a_homogeneous_store_keeps_its_long_names(tmp_path):
    from test_runner import heated

    path = tmp_path / "h.zarr"
    Simulation(heated(final_time=0.1, output={"snapshot_interval": 0.05})).run(
        path, progress=False)
    ds = granframe.open_run(path)
    assert "wall" not in ds.dims and "x" not in ds.dims
    assert ds["mass"].attrs["long_name"] == "mass int f dv"
    assert ds["f"].attrs["long_name"] == "distribution function f(t, v)"
    assert ds["axis"].attrs["long_name"].startswith("velocity component of momentum")


# -- info and check -------------------------------------------------------------------
def test_info_describes_cells_blocks_walls_fields_and_totals(store, capsys):
    text = describe(store)
    ds = granframe.open_run(store)
    assert "24 cells on [0, 1] (dx = 0.0416667), 3 blocks of 8 cells" in text
    assert "left specular, right diffuse(temperature=1.2, accommodation=1.0)" in text
    t0, t1 = ds["temperature"].isel(step_time=0).values, ds["temperature"].isel(
        step_time=-1).values
    assert (f"T(x)        in [{t0.min():.6g}, {t0.max():.6g}] -> [{t1.min():.6g}, "
            f"{t1.max():.6g}]") in text
    assert "rho(x)      in [0.125, 1] -> " in text
    right = ds["wall_energy"].sel(wall="right").sum().item()
    assert f"the right wall {right:+.6e}" in text
    records = text.split("f0 projection")[0]     # the projection lists f0's kurtosis
    assert "\n  mass        0.5625" in records and "\n  kurtosis" not in records
    assert main(["info", str(store)]) == 0
    assert capsys.readouterr().out.strip() == text
    assert main(["info", str(store), "--json"]) == 0
    assert '"kinetic_energy"' in capsys.readouterr().out


def test_check_reads_every_block_of_f_and_names_a_damaged_one(store, tmp_path):
    intact, lines = check(store)
    # f: 5 snapshots x 3 blocks; 15 record arrays, the 5 fields among them in 3 blocks of
    # cells each (their chunks never straddle blocks), 3 snapshot arrays, 3 coordinates
    assert intact and "5 snapshots, 9 records; 46 committed chunks read, 0 problems" in \
        lines[0], lines
    damaged = tmp_path / "damaged.zarr"
    subprocess.run(["cp", "-r", str(store), str(damaged)], check=True)
    chunk = damaged / "f" / "c" / "3" / "2" / "0" / "0"        # snapshot 3, block 2
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    intact, lines = check(damaged)
    assert not intact and "1 problems" in lines[0]
    assert lines[1].startswith("  damaged: f/c/3/2/0/0 (from entry 3, block 2: cells 16..23)")
    assert main(["check", str(damaged)]) == 3
    granframe.open_run(damaged)                       # f is read lazily: the rest is intact
    with pytest.raises(StoreDamagedError, match="f/c/3/2/0/0"):
        plotting.plot(damaged, tmp_path / "figures")


# -- plot -------------------------------------------------------------------------------
def test_plot_draws_maps_profiles_and_totals(store, tmp_path, capsys):
    assert main(["plot", str(store), "--out", str(tmp_path / "figures")]) == 0
    written = capsys.readouterr().out.split()
    assert sorted(pathlib.Path(p).name for p in written) == ["maps.png", "profiles.png",
                                                            "totals.png"]
    drawn = plotting.figures(granframe.open_run(store))
    maps = [ax for ax in drawn["maps"].axes if ax.get_label() != "<colorbar>"]
    assert [ax.get_title().split(":")[0] for ax in maps] == [
        r"density $\rho$(t, x)", "bulk velocity $u_1$(t, x)", "temperature $T$(t, x)",
        "pressure $P_{11}$(t, x)", "heat flux $q_1$(t, x)"]
    # each map is one quad per cell and record, holding the stored field
    ds = granframe.open_run(store)
    values = maps[0].collections[0].get_array().reshape(9, 24)
    numpy.testing.assert_array_equal(values, ds["density"].values)
    u1 = maps[1].collections[0]
    assert u1.norm.vmin == -u1.norm.vmax          # a signed field, centred at zero
    profiles = drawn["profiles"].axes
    assert len(profiles) == 5 and [line.get_label() for line in profiles[2].lines] == [
        f"t = {t:g}" for t in ds["time"].values]
    numpy.testing.assert_array_equal(profiles[2].lines[-1].get_ydata(),
                                     ds["temperature"].isel(step_time=-1).values)
    totals = drawn["totals"].axes
    assert totals[0].get_title().startswith("total mass")
    assert totals[1].get_title().startswith("total energy")
    assert "space: 24 cells on [0, 1]" in drawn["maps"].get_suptitle()
    with pytest.raises(ValueError, match="parameter 'ds'.*space-homogeneous"):
        plotting.kurtosis(ds)
    with pytest.raises(ValueError, match="parameter 'field' = 'pressure_11'"):
        plotting.field_map(ds, "pressure_11")


# -- resume and kill safety -----------------------------------------------------------
def test_a_run_stopped_after_its_first_commit_resumes_bitwise(store, tmp_path, monkeypatch):
    reference = contents(store)
    commit = StorageObserver.at_output

    def stop_after(self, state, final):       # a Ctrl-C right after the first commit
        commit(self, state, final)
        raise KeyboardInterrupt

    path = tmp_path / "stopped.zarr"
    monkeypatch.setattr(StorageObserver, "at_output", stop_after)
    with pytest.raises(KeyboardInterrupt):
        Simulation(DESCRIPTION).run(path, progress=False)
    monkeypatch.setattr(StorageObserver, "at_output", commit)
    progress = RunStore.open(path).progress
    assert (progress["status"], progress["snapshots"], progress["records"]) == \
        ("interrupted", 2, 3)
    assert granframe.open_run(path).sizes["time"] == 2
    Simulation(DESCRIPTION).run(path, resume=True, progress=False)
    assert RunStore.open(path).progress["resumes"] == [2]
    assert_same(contents(path), reference, "resumed")


def test_a_run_killed_at_any_write_opens_as_before_or_resumes_bitwise(store, tmp_path):
    reference = contents(store)
    toml, driver = tmp_path / "run.toml", tmp_path / "driver.py"
    toml.write_text(TOML)
    driver.write_text(DRIVER.format(tests=str(HARNESS.parent)))

    def launch(k, workdir, mode="fresh"):
        return subprocess.run([sys.executable, str(driver), str(k), str(toml),
                               str(workdir / "s.zarr"), mode], capture_output=True, text=True,
                              timeout=120)

    (tmp_path / "count").mkdir()
    done = launch(0, tmp_path / "count")
    assert done.returncode == 0, done.stderr
    lines = (tmp_path / "run.toml.log").read_text().splitlines()
    assert_same(contents(tmp_path / "count" / "s.zarr"), reference, "a run in a subprocess")
    published = max(int(line.split()[0]) for line in lines if line.split()[1] == "rename")
    rng = random.Random(19)
    # the last few writes are left out: the total varies by a write or two between runs
    # (a kill at write 824 of a counted 825 once found the run already ended)
    ks = sorted({published, published + 1, *rng.sample(range(2, published), 2),
                 *rng.sample(range(published + 2, len(lines) - 8), 4)})
    outcomes = {"nothing": 0, "resumed": 0}
    for k in ks:
        workdir = tmp_path / f"k{k}"
        workdir.mkdir()
        killed = launch(k, workdir)
        assert killed.returncode == -9, (k, killed.returncode, killed.stderr)
        path = workdir / "s.zarr"
        if not RunStore.exists(path):          # killed before the store was in place
            assert not path.exists(), k
            outcomes["nothing"] += 1
            continue
        ds = granframe.open_run(path)          # opens, cut to its last commit
        committed = ds.sizes["time"]
        numpy.testing.assert_array_equal(ds["f"].values, reference["f"][:committed])
        for name in FIELDS + ("mass", "wall_mass"):
            numpy.testing.assert_array_equal(ds[name].values,
                                             reference[name][:ds.sizes["step_time"]])
        resumed = launch(0, workdir, "resume")
        assert resumed.returncode == 0, (k, resumed.stderr)
        assert_same(contents(path), reference, f"resumed after a kill at write {k}")
        assert check(path)[0] and not list(path.rglob("*.partial"))
        outcomes["resumed"] += 1
    print(f"{len(lines)} writes, kills at {ks}: {outcomes}")
    # two kills before the store is put in place, one or two at the rename, four after it
    assert outcomes["nothing"] >= 2 and outcomes["resumed"] >= 4, outcomes
    assert outcomes["nothing"] + outcomes["resumed"] == len(ks)
