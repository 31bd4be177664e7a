"""A real `granframe run` process interrupted (SIGINT) and killed (SIGKILL) mid-run, then resumed."""

import os
import signal
import subprocess
import sys
import time

import numpy
import xarray

from granframe.run.runner import Simulation
from granframe.run.storage import RunStore
from test_runner import heated

DESCRIPTION = heated(time_step=0.005, final_time=1.0, output={"snapshot_interval": 0.025})


def start(toml, store, *extra):
    return subprocess.Popen([sys.executable, "-m", "granframe.tools.cli", "run", str(toml), "--out",
                             str(store), "--no-progress", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def stop_mid_run(process, store, snapshots, sig):
    """Wait until ``store`` holds at least ``snapshots`` snapshots, then send ``sig``."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if RunStore.exists(store):
            try:
                progress = RunStore.open(store).progress
            except Exception:   # metadata being replaced this instant: look again
                progress = {}
            if progress.get("snapshots", 0) >= snapshots:
                assert progress["status"] == "running", progress
                process.send_signal(sig)
                process.communicate(timeout=60)
                return progress
        assert process.poll() is None, process.communicate()
        time.sleep(0.03)
    raise AssertionError("the run did not reach the snapshot in time")


def test_interrupted_and_killed_run_resumes_to_the_uninterrupted_result(tmp_path):
    toml, store = tmp_path / "run.toml", tmp_path / "run.zarr"
    toml.write_text(DESCRIPTION.to_toml())

    process = start(toml, store)
    stop_mid_run(process, store, 5, signal.SIGINT)                        # Ctrl-C
    assert process.returncode == 130
    process = start(toml, store, "--resume")
    stop_mid_run(process, store, 15, signal.SIGKILL)                      # kill -9
    assert process.returncode == -signal.SIGKILL
    killed_at = RunStore.open(store).progress
    assert killed_at["status"] == "running" and killed_at["snapshots"] < 41

    done = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "run", str(toml), "--out",
                           str(store), "--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    final = RunStore.open(store).progress
    assert final["status"] == "finished" and len(final["resumes"]) == 2, final

    Simulation(DESCRIPTION).run(tmp_path / "reference.zarr", progress=False)
    resumed, reference = xarray.open_zarr(store), xarray.open_zarr(tmp_path / "reference.zarr")
    # every record exactly once, in order
    assert list(resumed.step.values) == list(range(201))
    assert numpy.all(numpy.diff(resumed.step_time.values) > 0)
    numpy.testing.assert_array_equal(resumed.time.values, reference.time.values)
    # and the same numbers as the uninterrupted run, to round-off
    scale = reference.f.values.max()
    numpy.testing.assert_allclose(resumed.f.values, reference.f.values, rtol=0,
                                  atol=1e-13 * scale)
    for name in ("mass", "temperature", "kinetic_energy", "kurtosis"):
        numpy.testing.assert_allclose(resumed[name].values, reference[name].values, rtol=1e-12)
    leftovers = [p for p in store.rglob("*.partial")]
    assert os.path.isdir(store) and len(leftovers) <= 2, leftovers  # a write cut by the kill
