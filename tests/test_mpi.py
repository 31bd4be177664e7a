"""Space runs spread over MPI processes: ``mpiexec -n K granframe run`` against the serial run.

Every run here is a real ``granframe run`` launched by the ``mpiexec`` installed with
mpi4py (the ``mpich`` wheel) in a subprocess, read back with :func:`granframe.open_run`:

- with 1, 2 and 3 processes (and an uneven ``--partition``) the store equals that of the
  serial run to round-off: f of every snapshot, the fields, the totals and the wall
  records, for periodic ends, specular and diffuse walls, stiff penalised collisions
  (conservative, knudsen 1e-4) and a heat bath. What is seen today: with the default
  ranges (12 or 8 of 24 cells) f, the fields and the wall records are bitwise equal;
  with ranges of 2, 4, 6 or 16 cells (the uneven partition, the resumed run on 3
  processes) they differ at round-off (f by under 1e-16 of max f, the fields by under
  1e-14 relative); the totals (sums of the processes' partial sums) by a few 1e-16
  relative;
- a health stop reaches every process at the step the serial run stops at;
- a process killed with SIGKILL mid-run ends the whole run (mpiexec reports it, with a
  non-zero status, in seconds), and the store it leaves resumes on 1, 2 or 3 processes
  to the uninterrupted result, and passes ``granframe check``;
- input the processes cannot run is refused with status 2, naming the parameter, before
  anything is written (or the existing store changes).

The module is skipped only when ``mpiexec`` cannot start two processes here.
"""

import hashlib
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time
import tomllib
import uuid

import numpy
import pytest

import granframe
from granframe.parallel import LAUNCHER_VARIABLES
from granframe.run.description import RunDescription
from granframe.run.problems.space import WALL_RECORDS
from granframe.run.storage import RunStore, WriterLock
from granframe.run.sweep import mpiexec
from granframe.tools.cli import main

from conftest import mutated


MPIEXEC = mpiexec()       # beside this Python (the mpich wheel's), else the one on PATH


def _environment(**extra) -> dict:
    """This process's environment without any launcher's variables (pytest itself may run
    under srun or mpiexec), plus ``extra``."""
    names = {name for pair in LAUNCHER_VARIABLES for name in pair}
    environ = {k: v for k, v in os.environ.items() if k not in names}
    environ.update(extra)
    return environ


def _cannot_start_two() -> str | None:
    """Why mpiexec cannot start two processes here, or None when it can."""
    if MPIEXEC is None:
        return "no mpiexec beside the Python or on PATH (pip install 'granframe[mpi]')"
    probe = "import os; print(os.environ.get('PMI_RANK', '?'))"
    try:
        done = subprocess.run([MPIEXEC, "-n", "2", sys.executable, "-c", probe],
                              capture_output=True, text=True, timeout=60, env=_environment())
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"'{MPIEXEC} -n 2' could not start two processes: {exc}"
    if done.returncode != 0:
        return (f"'{MPIEXEC} -n 2' could not start two processes (status {done.returncode}): "
                f"{(done.stderr or done.stdout).strip()[-300:]}")
    return None


_WHY_NOT = _cannot_start_two()
pytestmark = pytest.mark.skipif(_WHY_NOT is not None, reason=_WHY_NOT or "")

#: 2D N = 16, a Riemann problem on 24 cells (stored in chunks of 2: 12 chunks), inelastic
#: Maxwell molecules, a specular left wall and a diffuse right one; 6 steps, commits at
#: steps 2, 4 and 6 after f0
BASE = """\
final_time = 0.012
time_step = 0.002
[grid]
dimension = 2
n_modes = 16
support_radius = 3.2
[kernel]
name = "maxwell"
[restitution]
name = "constant"
value = 0.9
[initial]
name = "riemann"
left = {density = 1.0, temperature = 1.0}
right = {density = 0.5, temperature = 0.8}
[operator]
name = "fast_spectral"
radial_points = 8
sphere = {name = "circle_trapezoid", n_points = 8}
[backend]
name = "numpy"
threads = 1
[space]
cells = 24
left = "specular"
right = {name = "diffuse", temperature = 1.1, accommodation = 0.8}
[output]
snapshot_interval = 0.004
"""

#: the ends and the collision terms each comparison runs with, as changes of BASE
CASES = {
    "periodic": [("space.left", "periodic"), ("space.right", "periodic")],
    "specular": [("space.right", "specular")],
    "diffuse": [("space.left", {"name": "diffuse", "temperature": 1.1, "accommodation": 0.6}),
                ("space.right", {"name": "diffuse", "temperature": 1.0, "velocity": 0.3})],
    # elastic: at knudsen 1e-4 an inelastic gas would cool to nothing within a step
    "penalised": [("integrator", "penalised_euler"), ("conservative", True),
                  ("knudsen", 1e-4), ("restitution.value", 1.0)],
    "heat_bath": [("heat_bath", 0.5)],
    # a hierarchy of collision models: the levels chosen from indicators of all cells
    "hierarchy": [("integrator", "penalised_euler"), ("conservative", True),
                  ("knudsen", 1e-3), ("restitution.value", 0.95),
                  ("space.hierarchy", {"realizability": [0.002, 0.01],
                                       "distance": [0.05, 0.1]})],
}


def description(changes=(), base=BASE) -> RunDescription:
    return RunDescription.from_dict(mutated(tomllib.loads(base), list(changes)))


def write_toml(path: pathlib.Path, changes=(), base=BASE) -> pathlib.Path:
    path.write_text(description(changes, base).to_toml())
    return path


def cli(*arguments, processes=None, timeout=240, env=None):
    """``granframe ARGUMENTS`` in a subprocess, under ``mpiexec -n PROCESSES`` if given."""
    command = [sys.executable, "-m", "granframe.tools.cli", *map(str, arguments)]
    if processes is not None:
        command = [MPIEXEC, "-n", str(processes), *command]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          env=_environment(**(env or {})))


def run(toml, out, *extra, processes=None):
    """``granframe run TOML --out OUT`` that must finish; the process's output."""
    done = cli("run", toml, "--out", out, "--no-progress", *extra, processes=processes)
    assert done.returncode == 0, f"status {done.returncode}\n{done.stdout}\n{done.stderr}"
    # one voice: only process 0 reports
    assert done.stdout.count(": finished,") == 1, done.stdout
    return done


def serial(toml, out, *extra):
    """The serial reference: the same command, in this process (no launcher: one process)."""
    assert main(["run", str(toml), "--out", str(out), "--no-progress", *extra]) == 0


def assert_same_run(store, reference):
    """The stores hold the same run to round-off: the same variables, coordinates, steps
    and snapshot times exactly; f of every snapshot within 1e-13 of max |f|; every other
    record (fields, totals) within 1e-12 of its largest magnitude, the wall records within
    1e-12 of the largest of them."""
    got, want = granframe.open_run(store), granframe.open_run(reference)
    assert sorted(got.data_vars) == sorted(want.data_vars)
    assert got.attrs["progress_status"] == want.attrs["progress_status"] == "finished"
    for name in want.coords:
        numpy.testing.assert_array_equal(got[name].values, want[name].values, err_msg=name)
    for name in ("step", "dt", "snapshot_step"):
        numpy.testing.assert_array_equal(got[name].values, want[name].values, err_msg=name)
    f, f_ref = got.f.values, want.f.values
    numpy.testing.assert_allclose(f, f_ref, rtol=0, atol=1e-13 * numpy.abs(f_ref).max())
    # what a wall exchanges in a step is measured against the largest exchange (the
    # pressure's momentum): the mass through a diffuse wall is zero up to round-off noise
    walls = max(numpy.abs(want[name].values).max() for name in WALL_RECORDS)
    for name in want.data_vars:
        a, b = got[name].values, want[name].values
        if a.dtype.kind in "iu":             # the levels of a hierarchy: exactly the same
            numpy.testing.assert_array_equal(a, b, err_msg=name)
        if name == "f" or a.dtype.kind not in "f":
            continue
        scale = walls if name in WALL_RECORDS else numpy.abs(b).max()
        numpy.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * (scale or 1.0), err_msg=name)
    return got, want


@pytest.fixture(scope="module")
def mpi_sees_two():
    """mpi4py under this mpiexec sees the processes it started (else every process would
    run the whole problem alone, and granframe refuses to start)."""
    done = subprocess.run([MPIEXEC, "-n", "2", sys.executable, "-c",
                           "from mpi4py import MPI; assert MPI.COMM_WORLD.size == 2"],
                          capture_output=True, text=True, timeout=60, env=_environment())
    assert done.returncode == 0, ("mpiexec started two processes, but mpi4py does not see "
                                  f"them as one MPI world:\n{done.stdout}\n{done.stderr}")


# -- the same results on 1, 2 and 3 processes --------------------------------------------------

@pytest.mark.parametrize("case", list(CASES))
def test_runs_on_two_and_three_processes_equal_the_serial_run(tmp_path, case, mpi_sees_two):
    toml = write_toml(tmp_path / "run.toml", CASES[case])
    serial(toml, tmp_path / "serial.zarr")
    counts = (1, 2, 3) if case == "periodic" else (2, 3)
    for processes in counts:
        run(toml, tmp_path / f"p{processes}.zarr", processes=processes)
        got, want = assert_same_run(tmp_path / f"p{processes}.zarr", tmp_path / "serial.zarr")
    # the comparison is not vacuous: f moved, and the walls exchanged momentum
    assert numpy.abs(want.f.values[-1] - want.f.values[0]).max() > 1e-3 * want.f.values.max()
    if case != "periodic":
        assert numpy.abs(want.wall_momentum.values[1:]).max() > 0.0
    if case == "hierarchy":              # and the processes chose mixed levels
        assert len(numpy.unique(want.level.values[1:])) >= 2
    if case == "diffuse":
        assert numpy.abs(want.wall_energy.values[1:]).max() > 0.0


#: the same run on a rectangle of 12 x 8 cells (chunks of 2 x 2), Riemann data in four
#: quadrants; walls on every side or periodic across both axes
RECTANGLE = [("space.cells", [12, 8]), ("space.length", [1.0, 0.75]),
             ("space.block_cells", [2, 2]),
             ("space.bottom", {"name": "diffuse", "temperature": 0.9, "velocity": 0.2}),
             ("space.top", "specular"), ("time_step", 0.001),
             ("initial", {"name": "quadrants",
                          "upper_right": {"density": 1.0, "temperature": 1.0},
                          "upper_left": {"density": 0.5, "velocity": [-0.3, 0.0],
                                         "temperature": 0.8},
                          "lower_left": {"density": 1.0, "velocity": [-0.3, -0.3],
                                         "temperature": 1.0},
                          "lower_right": {"density": 0.5, "velocity": [0.0, -0.3],
                                          "temperature": 0.8},
                          "interface": [0.4, 0.6]})]


@pytest.mark.parametrize("ends", ["walls", "periodic"])
def test_a_rectangle_on_two_and_four_processes_equals_the_serial_run(tmp_path, ends,
                                                                      mpi_sees_two):
    """Blocks on a 1 x 2 and a 2 x 2 grid of processes, their ghost strips exchanged along
    both axes, and one store written by all of them in chunks of both axes: the serial
    run's, f and the fields to round-off, the wall records of the four sides too. With the
    walls, under a hierarchy: every process gathers the indicators of its block and puts
    them in the cells' order, and all choose the serial run's levels, exactly."""
    changes = RECTANGLE + ([("space.left", "periodic"), ("space.right", "periodic"),
                            ("space.bottom", "periodic"), ("space.top", "periodic")]
                           if ends == "periodic" else CASES["hierarchy"])
    toml = write_toml(tmp_path / "run.toml", changes)
    serial(toml, tmp_path / "serial.zarr")
    for processes in (2, 4):
        run(toml, tmp_path / f"p{processes}.zarr", processes=processes)
        _, want = assert_same_run(tmp_path / f"p{processes}.zarr", tmp_path / "serial.zarr")
        meta = RunStore.open(tmp_path / f"p{processes}.zarr").metadata
        assert meta["provenance"]["processes"] == processes
    assert want.f.dims == ("time", "x", "y", "v1", "v2")
    assert numpy.abs(want.f.values[-1] - want.f.values[0]).max() > 1e-3 * want.f.values.max()
    if ends == "walls":
        assert numpy.abs(want.wall_momentum.values[1:, 2:]).max() > 0.0
        assert want.level.dims == ("step_time", "x", "y")
        assert len(numpy.unique(want.level.values[1:])) >= 2


def test_an_uneven_partition_gives_the_serial_run(tmp_path, mpi_sees_two):
    """``--partition 2,16,6``: the first process owns exactly the ghost width of MUSCL (its
    ghost cells come from the next range alone), the second most of the interval."""
    toml = write_toml(tmp_path / "run.toml")
    serial(toml, tmp_path / "serial.zarr")
    run(toml, tmp_path / "uneven.zarr", "--partition", "2,16,6", processes=3)
    assert_same_run(tmp_path / "uneven.zarr", tmp_path / "serial.zarr")


def test_a_health_stop_reaches_every_process_at_the_same_step(tmp_path, mpi_sees_two):
    """An inelastic gas at knudsen 1e-4 cools to nothing the grid resolves within two
    steps: the health check of the reduced record stops the three processes at the step
    the serial run stops at (status 3, no process left waiting), and the store keeps what
    the serial run's keeps."""
    toml = write_toml(tmp_path / "run.toml", [("integrator", "penalised_euler"),
                                              ("conservative", True), ("knudsen", 1e-4)])
    assert main(["run", str(toml), "--out", str(tmp_path / "serial.zarr"),
                 "--no-progress"]) == 3
    done = cli("run", toml, "--out", tmp_path / "p3.zarr", "--no-progress", processes=3,
               timeout=120)
    assert done.returncode == 3, f"status {done.returncode}\n{done.stdout}\n{done.stderr}"
    assert done.stderr.count("granframe: run stopped: health check failed at step 2") == 1
    got, want = (granframe.open_run(tmp_path / name) for name in ("p3.zarr", "serial.zarr"))
    assert got.attrs["progress_status"] == want.attrs["progress_status"] == "failed"
    assert got.attrs["progress_step"] == want.attrs["progress_step"] == 2
    numpy.testing.assert_allclose(got.f.values, want.f.values, rtol=0,
                                  atol=1e-13 * numpy.abs(want.f.values).max())
    numpy.testing.assert_array_equal(got.step.values, want.step.values)
    numpy.testing.assert_allclose(got.negative_mass_fraction.values,
                                  want.negative_mass_fraction.values, rtol=1e-12)


# -- a process killed mid-run -----------------------------------------------------------------

#: 40 steps of 16 cells, a commit every 5 steps (8 after f0)
LONG = [("space.cells", 16), ("final_time", 0.08), ("output.snapshot_interval", 0.01)]
SNAPSHOTS = 9
#: the same schedule on the rectangle (its step is half the interval's: 41 steps)
LONG_RECTANGLE = RECTANGLE + [("final_time", 0.04), ("output.snapshot_interval", 0.005)]
#: the processes each shape resumes on after the kill (2 in place): on the rectangle a
#: 3 x 1 and a 2 x 2 grid of blocks
RESUMED = {"interval": (1, 3), "rectangle": (1, 3, 4)}

#: ``granframe`` whose every step also sleeps 20 ms (the same numbers, slower), so that a
#: kill lands between two commits however fast this machine is
SLOW = """\
import sys, time
from granframe.run.problems import space
step = space.SpaceProblem.step
def slow(self, t, state, dt):
    time.sleep(0.02)
    return step(self, t, state, dt)
space.SpaceProblem.step = slow
from granframe.tools.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _process_of_rank(marker: str, rank: int) -> int | None:
    """The PID of the process launched with ``GRANFRAME_TEST_MARKER=marker`` whose
    launcher gave it ``PMI_RANK=rank`` (read from /proc/PID/environ), or None."""
    wanted = {f"GRANFRAME_TEST_MARKER={marker}".encode(), f"PMI_RANK={rank}".encode()}
    for entry in pathlib.Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            environ = set((entry / "environ").read_bytes().split(b"\0"))
        except OSError:         # gone, or not ours
            continue
        if wanted <= environ:
            return int(entry.name)
    return None


def _snapshots(store) -> int:
    try:
        return int(RunStore.open(store, complete=False).progress["snapshots"])
    except Exception:      # not there yet, or its metadata being replaced this instant
        return 0


@pytest.mark.skipif(not pathlib.Path("/proc/self/environ").exists(),
                    reason="finds the rank-1 process through /proc")
@pytest.mark.parametrize("shape", ["interval", "rectangle"])
def test_a_process_killed_mid_run_ends_the_run_and_the_store_resumes_on_any_count(
        tmp_path, shape, mpi_sees_two):
    toml = write_toml(tmp_path / "run.toml", LONG if shape == "interval" else LONG_RECTANGLE)
    store = tmp_path / "run.zarr"
    marker = uuid.uuid4().hex
    launched = subprocess.Popen(
        [MPIEXEC, "-n", "2", sys.executable, "-c", SLOW, "run", str(toml), "--out", str(store),
         "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env=_environment(GRANFRAME_TEST_MARKER=marker))
    try:
        deadline = time.monotonic() + 120
        while _snapshots(store) < 3:        # f0 and two commits
            assert launched.poll() is None, launched.communicate()[0]
            assert time.monotonic() < deadline, "the run made no second commit in 120 s"
            time.sleep(0.02)
        victim = _process_of_rank(marker, 1)
        assert victim is not None, "no process with PMI_RANK=1 and the marker"
        os.kill(victim, signal.SIGKILL)
        killed = time.monotonic()
        output, _ = launched.communicate(timeout=30)     # bounded: no process left waiting
    finally:
        if launched.poll() is None:
            launched.kill()
            launched.communicate()
    assert time.monotonic() - killed < 30
    assert launched.returncode != 0, output
    assert "BAD TERMINATION" in output and "Killed (signal 9)" in output, output
    progress = RunStore.open(store, complete=False).progress
    assert progress["status"] == "running" and 3 <= progress["snapshots"] < SNAPSHOTS, progress
    WriterLock.check_free(store)     # the dead holder's lock is free

    serial(toml, tmp_path / "reference.zarr")
    copies = {2: store, **{k: tmp_path / f"resumed{k}.zarr" for k in RESUMED[shape]}}
    for processes in RESUMED[shape]:
        shutil.copytree(store, copies[processes])
    for processes, path in copies.items():
        run(toml, path, "--resume", processes=processes)   # 2: in place, past the lock file
        got, _ = assert_same_run(path, tmp_path / "reference.zarr")
        assert list(got.step.values) == list(range(41))     # every step once, in order
        assert got.attrs["progress_snapshots"] == SNAPSHOTS
        assert main(["check", str(path)]) == 0, f"granframe check {path}"
        resumes = RunStore.open(path).progress["resumes"]
        assert len(resumes) == 1 and resumes[0] == progress["step"], resumes


# -- refused before anything is written ---------------------------------------------------------

def assert_refused(done, parameter, *words):
    """Status 2 and a message on stderr naming ``parameter`` (and ``words``)."""
    assert done.returncode == 2, f"status {done.returncode}\n{done.stdout}\n{done.stderr}"
    for word in (f"parameter '{parameter}'",) + words:
        assert word in done.stderr, done.stderr
    assert "Traceback" not in done.stderr, done.stderr


def files(path: pathlib.Path) -> dict:
    """Every file under ``path`` (and beside it: lock files) with its size, mtime and hash."""
    found = {}
    for item in sorted(path.parent.rglob("*")):
        if item.is_file():
            data = item.read_bytes()
            found[str(item)] = (len(data), item.stat().st_mtime_ns,
                                hashlib.sha1(data).hexdigest())
    return found


@pytest.mark.parametrize("processes, changes, extra, parameter, words", [
    (4, [("space.cells", 3), ("space.reconstruction", "upwind")], (), "processes",
     ("at most space.cells = 3",)),
    (3, [("space.block_cells", 12)], (), "processes",
     ("2 chunks of space.block_cells = 12",)),
    # MUSCL's ghost width is 2: one cell for a process is below the stencil (and not a
    # whole chunk of the default 2 cells)
    (2, [], ("--partition", "1,23"), "partition", ("multiples of space.block_cells = 2",)),
    (2, [], ("--partition", "8,8,8"), "partition", ("each of the 2 processes",)),
], ids=["more-processes-than-cells", "fewer-chunks-than-processes",
        "a-block-below-the-stencil", "a-partition-for-3-on-2"])
def test_runs_the_processes_cannot_share_are_refused_before_writing(
        tmp_path, processes, changes, extra, parameter, words, mpi_sees_two):
    toml = write_toml(tmp_path / "run.toml", changes)
    before = sorted(p.name for p in tmp_path.iterdir())
    done = cli("run", toml, "--out", tmp_path / "out.zarr", "--no-progress", *extra,
               processes=processes)
    assert_refused(done, parameter, *words)
    assert sorted(p.name for p in tmp_path.iterdir()) == before      # nothing at --out


def _interrupted_store(tmp_path, toml, *extra) -> pathlib.Path:
    """A store of ``toml`` written serially, left as an interrupted run leaves it."""
    store = tmp_path / "store.zarr"
    serial(toml, store, *extra)
    RunStore.open(store, "r+").mark("interrupted")
    return store


def test_resuming_a_store_whose_chunks_miss_the_processes_boundaries_is_refused(
        tmp_path, mpi_sees_two):
    """A store chunked by 8 cells along x, resumed on 2 processes whose ranges (by the
    default chunks of 2) start at 0 and 12: refused naming 'processes', the store unchanged
    (runner._check_chunks runs before the store is locked or cut back)."""
    toml = write_toml(tmp_path / "run.toml")
    store = _interrupted_store(tmp_path, toml, "--set", "space.block_cells=8")
    before = files(store)
    done = cli("run", toml, "--out", store, "--resume", "--no-progress", processes=2)
    assert_refused(done, "processes", "chunked by 8 cells", "[0, 12]")
    assert files(store) == before


def test_resuming_a_store_of_fewer_chunks_than_processes_is_refused(tmp_path, mpi_sees_two):
    toml = write_toml(tmp_path / "run.toml", [("space.block_cells", 12)])
    store = _interrupted_store(tmp_path, toml)
    before = files(store)
    done = cli("run", toml, "--out", store, "--resume", "--no-progress", processes=3)
    assert_refused(done, "processes", "2 chunks")
    assert files(store) == before


def test_other_commands_and_space_homogeneous_runs_are_refused_under_mpiexec(
        tmp_path, mpi_sees_two):
    done = cli("info", tmp_path / "any.zarr", processes=2)
    assert done.returncode == 2 and "granframe info runs in one process" in done.stderr, (
        done.stderr)
    homogeneous = tmp_path / "homogeneous.toml"
    homogeneous.write_text(BASE.split("[space]")[0].replace(
        'name = "riemann"\nleft = {density = 1.0, temperature = 1.0}\n'
        'right = {density = 0.5, temperature = 0.8}', 'name = "maxwellian"'))
    RunDescription.from_toml(homogeneous.read_text())         # a valid description
    done = cli("run", homogeneous, "--out", tmp_path / "out.zarr", "--no-progress",
               processes=2)
    assert_refused(done, "processes", "space-homogeneous")
    assert not (tmp_path / "out.zarr").exists()


RANK_FAILS = '''\
import os

import numpy


def f0(x, v1, v2):
    if os.environ.get("PMI_RANK", "0") == "1":
        raise RuntimeError("only in rank 1")
    return numpy.exp(-(v1 ** 2 + v2 ** 2) / 2) / (2 * numpy.pi) + 0.0 * x
'''


def test_an_error_in_one_process_ends_all_with_one_line(tmp_path, monkeypatch, mpi_sees_two):
    """A space function that raises in process 1 only hung the run (process 0 waited in
    the cost estimate's exchange); the initial data are now made in every process and an
    error in any ends all, said once by process 0 naming the process. A refusal every
    process meets together (a store that exists) printed the exception and an MPI_Abort
    line from every process; now one line, as serially."""
    (tmp_path / "rank_fails.py").write_text(RANK_FAILS)
    monkeypatch.syspath_prepend(str(tmp_path))
    toml = write_toml(tmp_path / "run.toml", [
        ("initial", {"name": "space_function", "function": "rank_fails:f0"})])
    done = cli("run", toml, "--out", tmp_path / "out.zarr", "--no-progress", processes=2,
               timeout=120, env={"PYTHONPATH": os.pathsep.join(
                   [str(tmp_path), os.environ.get("PYTHONPATH", "")])})
    assert_refused(done, "function", "calling it raised RuntimeError: only in rank 1 "
                                     "(in process 1 of 2)")
    assert done.stderr.count("granframe: error") == 1 and "Abort" not in done.stderr, (
        done.stderr)
    assert not (tmp_path / "out.zarr").exists()
    plain = write_toml(tmp_path / "plain.toml")
    run(plain, tmp_path / "s.zarr", processes=2)
    done = cli("run", plain, "--out", tmp_path / "s.zarr", "--no-progress", processes=2)
    assert done.returncode == 2 and "store '" in done.stderr and "exists" in done.stderr
    assert done.stderr.count("granframe: error") == 1 and "Abort" not in done.stderr, (
        done.stderr)


def test_a_sweep_runs_each_space_run_on_several_processes(tmp_path):
    """granframe sweep --processes 2: each point a ``mpiexec -n 2 granframe run`` on the
    worker that takes it, the same stores as one process each (every f and field equal
    to round-off); without mpiexec the option is refused by name."""
    import tomllib

    import granframe
    from granframe.run import sweep as sweeps

    base = tomllib.loads(BASE)
    sweep = sweeps.Sweep(base, product={"space.cells": [12, 24]})
    stores = {}
    for processes in (1, 2):
        out = tmp_path / f"p{processes}.zarr"
        result = sweeps.run_sweep(sweep, out, workers=1, progress=False, processes=processes)
        assert (result.finished, result.failed) == (2, 0)
        stores[processes] = out
    for name in sweeps.read_table(stores[1])["name"]:
        one, two = (granframe.open_run(stores[p] / "runs" / str(name)) for p in (1, 2))
        assert numpy.allclose(one.f.values, two.f.values, rtol=0, atol=1e-14)
        assert numpy.allclose(one.temperature.values, two.temperature.values, rtol=1e-13)


def test_a_sweep_without_mpiexec_refuses_processes(tmp_path, monkeypatch):
    import tomllib

    from granframe.run import sweep as sweeps

    monkeypatch.setattr(sweeps, "mpiexec", lambda: None)
    sweep = sweeps.Sweep(tomllib.loads(BASE), product={"space.cells": [12]})
    with pytest.raises(ValueError, match=r"^run_sweep: parameter 'processes' = 2 is invalid; "
                                         r"needs mpiexec"):
        sweeps.run_sweep(sweep, tmp_path / "s.zarr", workers=1, processes=2)
    assert not (tmp_path / "s.zarr").exists()
