"""Sweeps on Dask (granframe.run.sweep): expansion, the store, and a worker killed mid-sweep."""

import logging
import math
import os
import signal
import threading
import time

import numpy
import pytest

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore, StoreError
from granframe.run.sweep import Sweep, apply, open_sweep, read_table, run_name, run_sweep

distributed = pytest.importorskip("distributed")

BASE = {
    "final_time": 2.0, "time_step": 0.02, "heat_bath": 0.1, "backend": "numpy",
    "grid": {"dimension": 2, "n_modes": 24, "support_radius": 4.0},
    "kernel": "maxwell", "restitution": {"name": "constant", "value": 0.5},
    "initial": {"name": "maxwellian", "temperature": 1.0},
    "operator": {"name": "fast_spectral", "radial_points": 12,
                 "sphere": {"name": "circle_trapezoid", "n_points": 12}},
    "output": {"snapshot_interval": 0.2},
}


def test_points_cover_the_product_and_the_zip():
    sweep = Sweep(BASE, product={"restitution.value": [0.2, 0.8], "kernel": ["maxwell",
                                                                            "hard_spheres"]},
                  zip={"grid.n_modes": [24, 32], "time_step": [0.02, 0.01]})
    points = sweep.points()
    assert len(points) == 8
    assert points[0] == {"restitution.value": 0.2, "kernel": "maxwell", "grid.n_modes": 24,
                         "time_step": 0.02}
    assert len({run_name(p) for p in points}) == 8
    table = apply(BASE, points[-1])
    assert table["kernel"] == "hard_spheres" and table["grid"]["n_modes"] == 32
    assert table["restitution"] == {"name": "constant", "value": 0.8}
    assert BASE["grid"]["n_modes"] == 24                   # the base is not modified
    RunDescription.from_dict(table)


@pytest.mark.parametrize("changes, parameter", [
    ({"zip": {"time_step": [0.1, 0.2], "grid.n_modes": [24]}}, "zip"),
    ({"product": {"kernel": []}}, "product"),
    ({"product": {}}, "product"),
    ({"base": "not a table"}, "base"),
])
def test_bad_sweeps_are_refused_by_name(changes, parameter):
    with pytest.raises((ValueError, TypeError), match=f"'{parameter}'"):
        Sweep.from_dict({"base": BASE, "product": {"kernel": ["maxwell"]}, **changes})


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0",
                                  silence_logs=logging.CRITICAL) as cluster, \
            distributed.Client(cluster) as client:
        yield client


def _running_worker(client, out):
    """(worker address, run path) of a run that has committed a snapshot past t = 0."""
    for address, keys in client.processing().items():
        for key in keys:
            path = out / "runs" / str(key).removeprefix("granframe-")
            try:
                progress = RunStore.open(path).progress
            except StoreError:          # not created yet, or being created
                continue
            if progress.get("status") == "running" and progress.get("snapshots", 0) >= 2:
                return address, path
    return None


def test_a_killed_worker_loses_nothing_and_every_run_finishes_once(cluster, tmp_path):
    """Two worker processes; one is killed (SIGKILL) while its run is between snapshots.
    Dask gives the task to a worker again, the run resumes from its last snapshot, and every
    run ends finished exactly once, with records 0..steps and results equal to a serial run.
    A point with bad parameters is recorded as failed and the sweep goes on."""
    client = cluster
    sweep = Sweep(BASE, product={"restitution.value": [0.2, 0.5, 0.8, 0.95],
                                 "grid.n_modes": [24, 6]})
    out = tmp_path / "sweep.zarr"
    result = {}
    thread = threading.Thread(target=lambda: result.update(
        value=run_sweep(sweep, out, client=client, progress=False)))
    thread.start()
    killed = None
    deadline = time.monotonic() + 60
    while killed is None and thread.is_alive() and time.monotonic() < deadline:
        found = _running_worker(client, out)
        if found is not None:
            address, path = found
            pid = client.run(os.getpid, workers=[address])[address]
            os.kill(pid, signal.SIGKILL)
            killed = path
        time.sleep(0.05)
    thread.join(timeout=300)
    assert killed is not None, "no run was caught between snapshots"
    summary = result["value"]
    assert (summary.finished, summary.failed) == (4, 4)

    table = read_table(out)
    steps = round(BASE["final_time"] / BASE["time_step"])
    for name, status, n_modes in zip(table["name"], table["status"], table["grid.n_modes"]):
        if n_modes == 6:                     # refused: N = 6 cannot hold f0
            assert status == "failed"
            continue
        assert status == "finished"
        store = RunStore.open(out / "runs" / str(name))
        recorded = store.group["step"][:]
        assert list(recorded) == list(range(steps + 1))            # each step exactly once
        assert list(store.group["time"][:]) == pytest.approx(
            [0.2 * k for k in range(11)])                          # each snapshot once
    assert RunStore.open(killed).progress["resumes"], "the killed run was not resumed"
    messages = [m for m, n in zip(table["message"], table["grid.n_modes"]) if n == 6]
    assert all("n_modes" in m or "grid" in m or "h =" in m for m in messages), messages

    # the same results as a serial run, for the killed run and one other
    for path in (killed, out / "runs" / str(table["name"][0])):
        description = RunDescription.from_dict(RunStore.open(path).metadata["description"])
        serial = Simulation(description)
        serial.run(tmp_path / "serial.zarr", overwrite=True, progress=False)
        expected = RunStore.open(tmp_path / "serial.zarr").group["f"][-1]
        got = RunStore.open(path).group["f"][-1]
        assert numpy.max(numpy.abs(got - expected)) <= 1e-12 * numpy.max(numpy.abs(expected))

    # a second sweep over the same store skips every ended run
    again = run_sweep(sweep, out, client=client, progress=False)
    assert again.skipped == 4 and again.finished == 4


def test_a_sweep_runs_on_a_cluster_given_by_its_address(cluster, tmp_path):
    """--scheduler ADDRESS: the sweep connects to an existing scheduler (here the test's
    LocalCluster), and a sweep of another content is refused on the same store."""
    sweep = Sweep({**BASE, "final_time": 0.2, "output": {}},
                  product={"restitution.value": [0.3, 0.7]})
    result = run_sweep(sweep, tmp_path / "s.zarr", scheduler=cluster.scheduler.address,
                       progress=False)
    assert (result.finished, result.failed) == (2, 0)
    table = read_table(tmp_path / "s.zarr")
    assert list(table["restitution.value"]) == [0.3, 0.7]
    assert all(t == pytest.approx(0.2) for t in table["time"])
    other = Sweep(sweep.base, product={"restitution.value": [0.4]})
    with pytest.raises(ValueError, match="holds another sweep"):
        run_sweep(other, tmp_path / "s.zarr", client=cluster, progress=False)


def test_command_line_sweep(tmp_path, capsys):
    import tomli_w

    from granframe.tools.cli import main

    sweep = {"base": {**BASE, "final_time": 0.1, "output": {}},
             "product": {"restitution.value": [0.5]}, "zip": {}}
    path = tmp_path / "sweep.toml"
    path.write_text(tomli_w.dumps(sweep))
    assert main(["sweep", str(path), "--out", str(tmp_path / "s.zarr"), "--workers", "1"]) == 0
    assert "1 finished, 0 failed" in capsys.readouterr().out
    assert main(["sweep", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "t")]) == 2


def test_rerunning_a_sweep_resumes_a_run_cut_short_and_records_a_health_stop(cluster,
                                                                             tmp_path):
    """A run whose process was killed (the sweep's driver and its worker gone) is resumed by
    the next sweep over the store; a run stopped by a health check is recorded as failed with
    the check's message, and the sweep goes on."""
    import json
    import subprocess
    import sys

    sweep = Sweep(BASE, product={"health.mass_tolerance": [1e-6, 1e-300]})
    out = tmp_path / "s.zarr"
    point = sweep.points()[0]
    path = out / "runs" / run_name(point)
    script = ("import json, sys; from granframe.run.sweep import run_point; "
              "run_point(json.loads(sys.argv[1]), sys.argv[2])")
    process = subprocess.Popen([sys.executable, "-c", script,
                                json.dumps(apply(BASE, point)), str(path)])
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            if RunStore.open(path).progress.get("snapshots", 0) >= 3:
                break
        except StoreError:
            pass
        time.sleep(0.02)
    process.kill()
    process.wait()
    cut = RunStore.open(path).progress
    assert cut["status"] == "running" and cut["step"] < 100

    result = run_sweep(sweep, out, client=cluster, progress=False)
    assert (result.finished, result.failed, result.skipped) == (1, 1, 0)
    store = RunStore.open(path)
    assert store.progress["status"] == "finished" and store.progress["resumes"]
    assert list(store.group["step"][:]) == list(range(101))
    table = read_table(out)
    assert list(table["status"]) == ["finished", "failed"]
    assert "mass drift" in str(table["message"][1])


# -- the gridded dataset, the store's conventions ------------------------------------------
SHORT = {**BASE, "final_time": 0.1, "output": {}}


@pytest.fixture(scope="module")
def gridded(cluster, tmp_path_factory):
    """A product x zip sweep store with one refused value of the product axis (N = 6)."""
    sweep = Sweep(SHORT, product={"grid.n_modes": [24, 6]},
                  zip={"restitution.value": [0.3, 0.7], "heat_bath": [0.1, 0.05]})
    out = tmp_path_factory.mktemp("gridded") / "s.zarr"
    result = run_sweep(sweep, out, client=cluster, progress=False)
    assert (result.finished, result.failed) == (2, 2)
    return out


def test_open_sweep_puts_the_results_on_the_grid_of_the_axes(gridded):
    from granframe import open_sweep

    ds = open_sweep(gridded)
    assert dict(ds.sizes) == {"grid_n_modes": 2, "restitution_value": 2}
    assert ds.grid_n_modes.dtype == numpy.int64 and list(ds.grid_n_modes.values) == [24, 6]
    assert ds.restitution_value.dtype == numpy.float64
    assert ds.heat_bath.dims == ("restitution_value",)          # zipped: the same dimension
    assert list(ds.heat_bath.values) == [0.1, 0.05]
    assert set(ds.indexes) == {"grid_n_modes", "restitution_value"}
    assert ds.grid_n_modes.attrs["parameter"] == "grid.n_modes"
    assert ds.heat_bath.attrs == {"long_name": "sweep parameter heat_bath (zip axis)",
                                  "parameter": "heat_bath", "units": "1"}
    assert ds.steps.dtype == numpy.int64 and ds.status.dtype.kind == "U"
    for name in ("temperature", "kurtosis", "time", "steps"):
        assert ds[name].dims == ("grid_n_modes", "restitution_value")
        assert ds[name].attrs["units"] == "1" and ds[name].attrs["long_name"]
    assert ds.wall_seconds.attrs["units"] == "s"

    table = read_table(gridded)
    row = list(table["name"]).index(ds.run.sel(grid_n_modes=24, restitution_value=0.7).item())
    point = ds.sel(grid_n_modes=24, restitution_value=0.7)
    assert point.status.item() == "finished" and point.message.item() == ""
    assert point.temperature.item() == table["temperature"][row]
    assert point.heat_bath.item() == 0.05 and point.steps.item() == 5
    assert RunStore.open(gridded / "runs" / point.run.item()).progress["status"] == "finished"

    refused = ds.sel(grid_n_modes=6)                              # N = 6 cannot hold f0
    assert list(refused.status.values) == ["failed", "failed"]
    assert all(m.startswith("refused: ") for m in refused.message.values)
    assert numpy.isnan(refused.temperature).all() and numpy.isnan(refused.kurtosis).all()
    assert numpy.isfinite(ds.temperature.sel(grid_n_modes=24)).all()

    assert ds.attrs["Conventions"] == "CF-1.10" and "granframe" in ds.attrs["source"]
    assert "created by granframe sweep" in ds.attrs["history"]
    assert Sweep.from_toml(ds.attrs["sweep_toml"]).points() == Sweep(
        SHORT, product={"grid.n_modes": [24, 6]},
        zip={"restitution.value": [0.3, 0.7], "heat_bath": [0.1, 0.05]}).points()


def test_open_sweep_writes_to_netcdf_and_reads_back_the_same(gridded, tmp_path):
    import xarray

    from granframe import open_sweep

    pytest.importorskip("netCDF4")
    ds = open_sweep(gridded)
    ds.to_netcdf(tmp_path / "s.nc", engine="netcdf4")
    with xarray.open_dataset(tmp_path / "s.nc", engine="netcdf4") as back:
        xarray.testing.assert_identical(back.load(), ds)
        assert back.grid_n_modes.dtype == numpy.int64 and back.steps.dtype == numpy.int64


def test_open_sweep_and_info_refuse_what_is_not_a_sweep_store(tmp_path, capsys):
    from granframe import open_sweep
    from granframe.tools.cli import main

    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("mine\n")
    with pytest.raises(ValueError, match="parameter 'path'.*must be a sweep store"):
        open_sweep(tmp_path / "mine")
    with pytest.raises(TypeError, match="parameter 'path' = 3 is invalid"):
        open_sweep(3)
    assert main(["info", str(tmp_path / "mine")]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_open_sweep_and_info_name_a_damaged_table(gridded, tmp_path, capsys):
    import shutil

    from granframe import open_sweep
    from granframe.run.storage import StoreDamagedError
    from granframe.tools.cli import main

    copy = tmp_path / "s.zarr"
    shutil.copytree(gridded, copy)
    chunk = copy / "table" / "temperature" / "c" / "0"
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    with pytest.raises(StoreDamagedError, match="is damaged: table/temperature"):
        open_sweep(copy)
    assert main(["info", str(copy)]) == 2
    err = capsys.readouterr().err
    assert "is damaged: table/temperature" in err and "Traceback" not in err


def test_info_on_a_sweep_store_says_what_is_in_it(gridded, capsys):
    from granframe.tools.cli import main

    assert main(["info", str(gridded)]) == 0
    out = capsys.readouterr().out
    assert f"sweep store {gridded}" in out
    assert "grid_n_modes (product, 2 values): grid.n_modes = 24, 6" in out
    assert ("restitution_value (zip, 2 values): restitution.value = 0.3, 0.7; "
            "heat_bath = 0.1, 0.05") in out
    assert "points      4: 2 finished, 2 failed (2 refused for their parameters)" in out
    assert "failed    grid.n_modes-6__restitution.value-0.3__heat_bath-0.1: refused: " in out
    assert "grid_n_modes 2 x restitution_value 2: granframe.open_sweep(" in out
    assert "base (TOML)" in out and "final_time = 0.1" in out


def test_an_axis_of_whole_components_is_a_text_coordinate(cluster, tmp_path):
    """Values that are tables (a component with its parameters) are kept as JSON text, in
    the table and on the grid."""
    from granframe import open_sweep

    laws = [{"name": "constant", "value": 0.5}, {"name": "constant", "value": 0.7}]
    out = tmp_path / "s.zarr"
    result = run_sweep(Sweep(SHORT, product={"restitution": laws}), out, client=cluster,
                       progress=False)
    assert (result.finished, result.failed) == (2, 0)
    texts = ['{"name": "constant", "value": 0.5}', '{"name": "constant", "value": 0.7}']
    assert list(read_table(out)["restitution"]) == texts
    ds = open_sweep(out)
    assert ds.restitution.dtype.kind == "U" and list(ds.restitution.values) == texts
    assert "units" not in ds.restitution.attrs


def test_a_sweep_store_is_extended_by_new_axis_values_and_runs_only_them(cluster, tmp_path):
    sweep = Sweep(SHORT, product={"restitution.value": [0.3, 0.7]})
    out = tmp_path / "s.zarr"
    assert run_sweep(sweep, out, client=cluster, progress=False).finished == 2
    before = {p.name: (p / "zarr.json").read_bytes() for p in (out / "runs").iterdir()}

    wider = Sweep(SHORT, product={"restitution.value": [0.3, 0.5, 0.7]})
    result = run_sweep(wider, out, client=cluster, progress=False)
    assert (result.finished, result.failed, result.skipped) == (3, 0, 2)
    assert {p.name: (p / "zarr.json").read_bytes() for p in (out / "runs").iterdir()
            if p.name in before} == before                  # the ended runs untouched
    assert list(read_table(out)["restitution.value"]) == [0.3, 0.5, 0.7]
    from granframe import open_sweep

    ds = open_sweep(out)
    assert list(ds.restitution_value.values) == [0.3, 0.5, 0.7]
    assert list(ds.status.values) == ["finished"] * 3

    other = Sweep({**SHORT, "final_time": 0.2}, product={"restitution.value": [0.3, 0.9]})
    with pytest.raises(ValueError, match="holds another sweep: its base differs at final_time"):
        run_sweep(other, out, client=cluster, progress=False)
    narrower = Sweep(SHORT, product={"restitution.value": [0.3]})
    with pytest.raises(ValueError, match="2 of its 3 runs are not points of this one"):
        run_sweep(narrower, out, client=cluster, progress=False)


def test_refused_points_are_not_retried_unless_asked(cluster, tmp_path):
    """A point the description refuses is recorded once (it has no run store) and a
    rerun skips it; retry_failed submits it again."""
    import zarr

    refused = Sweep(SHORT, product={"grid.n_modes": [6]})
    out = tmp_path / "r.zarr"
    first = run_sweep(refused, out, client=cluster, progress=False)
    assert (first.failed, first.skipped, first.refused) == (1, 0, 0)
    again = run_sweep(refused, out, client=cluster, progress=False)
    assert (again.failed, again.skipped, again.refused) == (1, 0, 1)
    retried = run_sweep(refused, out, client=cluster, progress=False, retry_failed=True)
    assert (retried.failed, retried.skipped, retried.refused) == (1, 0, 0)
    name = run_name(refused.points()[0])
    recorded = zarr.open_group(str(tmp_path / "r.zarr"), mode="r").attrs["granframe_sweep"]
    assert recorded["refused"][name].startswith("refused: ")
    assert "refused: " in read_table(tmp_path / "r.zarr")["message"][0]
    assert not (tmp_path / "r.zarr" / "runs" / name).exists()


def test_a_health_stop_is_run_again_from_the_start_only_when_asked(cluster, tmp_path):
    """A rerun keeps a run stopped by a health check; retry_failed replaces its store by a
    new run from t = 0 (here stopped again, by the same check)."""
    stopped = Sweep(SHORT, product={"health.mass_tolerance": [1e-300]})
    out = tmp_path / "h.zarr"
    path = out / "runs" / run_name(stopped.points()[0])
    run_sweep(stopped, out, client=cluster, progress=False)
    created = RunStore.open(path).metadata["created"]
    run_sweep(stopped, out, client=cluster, progress=False)
    assert RunStore.open(path).metadata["created"] == created
    run_sweep(stopped, out, client=cluster, progress=False, retry_failed=True)
    store = RunStore.open(path)
    assert store.metadata["created"] != created and store.progress["resumes"] == []
    assert store.progress["status"] == "failed" and "mass drift" in store.progress["message"]


def test_command_line_sweep_overwrite_replaces_only_a_granframe_store(cluster, tmp_path,
                                                                    capsys):
    import tomli_w

    from granframe.tools.cli import main

    path = tmp_path / "sweep.toml"
    path.write_text(tomli_w.dumps({"base": SHORT, "product": {"grid.n_modes": [6]}}))
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "results.txt").write_text("precious\n")
    assert main(["sweep", str(path), "--out", str(mine), "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert "--overwrite refused" in err and "not a granframe store" in err
    assert [p.name for p in mine.iterdir()] == ["results.txt"]
    assert main(["sweep", str(path), "--out", str(tmp_path), "--overwrite"]) == 2
    assert "holds the source" in capsys.readouterr().err

    out = tmp_path / "s.zarr"
    old = Sweep({**SHORT, "final_time": 0.2}, product={"restitution.value": [0.3]})
    run_sweep(old, out, client=cluster, progress=False)
    stale = out / "runs" / run_name(old.points()[0])
    assert main(["sweep", str(path), "--out", str(out), "--scheduler",
                 cluster.scheduler.address, "--overwrite", "--retry-failed"]) == 3
    assert not stale.exists()
    assert list(read_table(out)["grid.n_modes"]) == [6]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine", "s.zarr", "sweep.toml"]


@pytest.mark.parametrize("killed_after", ["the rename", "the new directory"])
def test_an_overwrite_cut_short_leaves_the_old_store_or_the_new_one(cluster, tmp_path,
                                                                    killed_after):
    """--overwrite renames the old store aside, makes the new directory, then deletes the
    old store: killed after the rename, the next sweep puts the old store back; killed
    after the new directory exists, it deletes the old one."""
    sweep = Sweep(SHORT, product={"grid.n_modes": [6]})             # refused: no run to wait
    out = tmp_path / "s.zarr"
    run_sweep(sweep, out, client=cluster, progress=False)
    os.rename(out, tmp_path / ".s.zarr.granframe-old-0123abcd")
    if killed_after == "the new directory":
        out.mkdir()
    result = run_sweep(sweep, out, client=cluster, progress=False)
    assert result.refused == (1 if killed_after == "the rename" else 0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]


def test_the_documented_sweep_is_the_shipped_one_and_the_study_writes_it():
    import importlib.util
    import pathlib
    import tomllib

    root = pathlib.Path(__file__).resolve().parent.parent
    block = (root / "docs" / "scaling.md").read_text().split("```toml\n", 1)[1].split("```")[0]
    shipped = (root / "docs" / "figures" / "sweep" / "sweep.toml").read_text()
    assert tomllib.loads(block) == tomllib.loads(shipped)
    spec = importlib.util.spec_from_file_location(
        "heated_state_sweep", root / "studies" / "heated_state_sweep.py")
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    assert study.sweep().to_dict() == Sweep.from_toml(shipped).to_dict()


def test_a_client_the_sweep_connects_is_closed_after_it(cluster, tmp_path):
    """run_sweep(scheduler=...) closes the client it made: one left open reconnects to a
    closed scheduler when the process ends, and prints distributed's tracebacks."""
    def clients(dask_scheduler):
        return sorted(dask_scheduler.clients)

    before = cluster.run_on_scheduler(clients)
    sweep = Sweep(SHORT, product={"grid.n_modes": [6]})
    run_sweep(sweep, tmp_path / "s.zarr", scheduler=cluster.scheduler.address, progress=False)
    deadline = time.monotonic() + 10
    while cluster.run_on_scheduler(clients) != before and time.monotonic() < deadline:
        time.sleep(0.05)
    assert cluster.run_on_scheduler(clients) == before


def test_the_table_and_info_flag_the_runs_that_end_under_resolved(cluster, tmp_path, capsys):
    from granframe import open_sweep
    from granframe.tools.cli import main

    # N = 20 cuts off a tail exp(-T (pi 9 / L)^2 / 2) = 6e-3 of hat f; N = 32 resolves f
    sweep = Sweep(SHORT, product={"grid.n_modes": [20, 32]})
    out = tmp_path / "resolution.zarr"
    assert run_sweep(sweep, out, client=cluster, progress=False).finished == 2
    ds = open_sweep(out)
    coarse, fine = ds.sel(grid_n_modes=20), ds.sel(grid_n_modes=32)
    assert coarse.tail_error.item() > 1e-3 > fine.tail_error.item()
    assert "raise grid.n_modes (N = 20)" in coarse.resolution_warning.item()
    assert fine.resolution_warning.item() == ""
    assert ds.pairs_beyond_support.attrs["units"] == "1"
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "resolution  1 of the finished runs end under-resolved" in text
    assert "velocity resolution: spectral tail" in text


SPACE = {"cells": 8, "left": {"name": "diffuse", "temperature": 1.2}, "right": "specular"}
SPACE_BASE = {**BASE, "final_time": 0.02, "time_step": 0.005, "heat_bath": 0.0,
              "output": {"snapshot_interval": 0.01}, "space": SPACE}


def test_a_sweep_of_space_runs_makes_a_store_per_run_and_a_table(tmp_path, capsys):
    """space.cells (product) and the velocity grid (zip with the support): each run a
    store in the sweep, finished; the table holds the gas's temperature (sum rho T /
    sum rho, as the run store's fields give it), its mass and the largest change of a
    cell's fields without the outermost shell; kurtosis and a_2 are NaN; the CLI runs the
    same TOML and info describes it."""
    import tomli_w

    import granframe
    from granframe.tools.cli import main

    sweep = Sweep(SPACE_BASE, product={"space.cells": [8, 12]},
                  zip={"grid.n_modes": [16, 24], "grid.support_radius": [3.5, 4.0]})
    out = tmp_path / "space.zarr"
    result = run_sweep(sweep, out, workers=1, progress=False)
    assert (result.finished, result.failed) == (4, 0)
    table = read_table(out)
    assert list(table["status"]) == ["finished"] * 4
    ds = open_sweep(out)
    assert ds.temperature.dims == ("space_cells", "grid_n_modes")
    for index, name in enumerate(table["name"]):
        run = granframe.open_run(out / "runs" / str(name))
        mean = float((run.density[-1] * run.temperature[-1]).sum() / run.density[-1].sum())
        assert table["temperature"][index] == pytest.approx(mean, rel=1e-14)
        assert table["mass"][index] == pytest.approx(float(run.mass[-1]), rel=1e-14)
        assert math.isnan(table["kurtosis"][index]) and table["fields_shell"][index] > 0
    (tmp_path / "sweep.toml").write_text(tomli_w.dumps(sweep.to_dict()))
    assert main(["sweep", str(tmp_path / "sweep.toml"), "--out", str(tmp_path / "cli.zarr"),
                 "--workers", "1"]) == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "cli.zarr")]) == 0
    assert "points      4: 4 finished" in capsys.readouterr().out


def test_info_counts_a_failed_run_as_failed_and_names_inaccurate_runs(tmp_path, monkeypatch,
                                                                      capsys):
    """A failed run's resolution warning does not make it 'under-resolved'; the accuracy
    warnings of a finished run are counted as ``granframe run`` prints them."""
    import zarr

    from granframe.run import sweep as sweeps
    from granframe.run.storage import SWEEP_SCHEMA_KEY

    sweep = Sweep(BASE, product={"restitution.value": [0.5, 0.8, 0.9]})
    out = tmp_path / "s.zarr"
    root = zarr.open_group(str(out), mode="w")
    root.attrs[SWEEP_SCHEMA_KEY] = {"schema": sweeps.SCHEMA, "sweep": sweep.to_dict()}
    names = [run_name(p) for p in sweep.points()]
    rows = {names[0]: {**sweeps._PENDING, "status": "failed", "message": "health check",
                       "resolution_warning": "raise grid.n_modes"},
            names[1]: {**sweeps._PENDING, "status": "finished",
                       "accuracy_warning": "temperature law: |T/T_law - 1| = 0.3"},
            names[2]: {**sweeps._PENDING, "status": "finished"}}
    monkeypatch.setattr(sweeps, "_stored_rows", lambda path: rows)
    text = sweeps.describe_sweep(out)
    assert "points      3: 2 finished, 1 failed" in text
    assert "under-resolved" not in text
    assert "accuracy    1 of the finished runs end inaccurate" in text
    assert "|T/T_law - 1| = 0.3" in text


def test_a_sweep_without_dask_is_refused_in_a_sentence(tmp_path, monkeypatch, capsys):
    """granframe sweep and granframe refine need Dask (the sweep extra): without it they
    say so before any store is made, not with an ImportError's traceback."""
    import importlib.util

    from granframe.tools.cli import main

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "distributed" else real(name, *a))
    with pytest.raises(ValueError, match=r"^run_sweep: Dask \(distributed\) is not installed "
                                         r".*pip install 'granframe\[sweep\]'"):
        run_sweep(Sweep(BASE, product={"kernel": ["maxwell"]}), tmp_path / "s.zarr")
    (tmp_path / "d.toml").write_text(RunDescription.from_dict(BASE).to_toml())
    assert main(["refine", str(tmp_path / "d.toml"), "--vary", "time_step=0.02,0.01,0.005",
                 "--quantity", "temperature@t=2", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "pip install 'granframe[sweep]'" in err
    assert not (tmp_path / "s.zarr").exists() and not (tmp_path / "r" / "family.zarr").exists()
