"""Sweeps on Dask (granframe.run.sweep): expansion, the store, and a worker killed mid-sweep."""

import logging
import os
import signal
import threading
import time

import numpy
import pytest

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore, StoreError
from granframe.run.sweep import Sweep, apply, read_table, run_name, run_sweep

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
