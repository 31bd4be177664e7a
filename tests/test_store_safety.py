"""Stores that never lose or fake data: what --overwrite may replace, a kill inside a swap,
checksums and missing chunks, the writer lock, atomic creation, interruption, and the
smaller cases around them (run names, --resume with --overwrite, sweep --out, partial
files, a study's report that raises)."""

import errno
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import numpy
import pytest
import xarray
import zarr

from granframe.tools.cli import main
from granframe.run.runner import Simulation, Study
from granframe.run.storage import (RunStore, StoreDamagedError, StoreLockedError, WriterLock,
                               check, lock_path)
from granframe.run.sweep import run_point
from test_fault_injection import HARNESS, NEW, OLD, assert_same, contents, writes
from test_runner import heated


def tree(root) -> dict:
    """Every file under ``root`` and its bytes."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file()}


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """A directory of user files with a run description in it, the current directory."""
    d = tmp_path / "d"
    d.mkdir()
    (d / "base.toml").write_text(NEW.to_toml())
    (d / "notes.txt").write_text("my notes\n")
    monkeypatch.chdir(d)
    return d


def finished(path, description=NEW):
    Simulation(description).run(path, progress=False)
    return path


def flip(path: pathlib.Path, count: int = 16) -> None:
    """Flip ``count`` bytes in the middle of a file."""
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    for i in range(middle, middle + count):
        data[i] ^= 0xFF
    path.write_bytes(bytes(data))


# -- 1. --overwrite replaces only a granframe store or an empty directory ----------------
def test_overwrite_refuses_the_current_directory(workdir, capsys):
    before = tree(workdir)
    assert main(["run", "base.toml", "--out", ".", "--overwrite", "--no-progress"]) == 2
    assert "is the current directory" in capsys.readouterr().err
    assert tree(workdir) == before


def test_overwrite_refuses_a_directory_that_holds_the_source(workdir, tmp_path, capsys,
                                                            monkeypatch):
    monkeypatch.chdir(tmp_path)
    before = tree(workdir)
    assert main(["run", str(workdir / "base.toml"), "--out", str(workdir), "--overwrite",
                 "--no-progress"]) == 2
    assert "holds the source" in capsys.readouterr().err
    assert tree(workdir) == before


@pytest.mark.parametrize("kind", ["user files", "a file", "a foreign zarr group",
                                  "the source"])
def test_overwrite_refuses_anything_that_is_not_a_granframe_store(workdir, kind, capsys):
    target = {"user files": "mine", "a file": "data.csv", "a foreign zarr group": "x.zarr",
              "the source": "base.toml"}[kind]
    if kind == "user files":
        (workdir / "mine").mkdir()
        (workdir / "mine" / "results.txt").write_text("precious\n")
    elif kind == "a file":
        (workdir / "data.csv").write_text("1,2,3\n")
    elif kind == "a foreign zarr group":
        zarr.open_group("x.zarr", mode="w").create_array("a", shape=(3,), dtype="f8")[:] = 1.0
    before = tree(workdir)
    assert main(["run", "base.toml", "--out", target, "--overwrite", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert f"'{target}'" in err and "refused" in err and "Traceback" not in err
    assert tree(workdir) == before


def test_overwrite_refuses_a_run_store_that_also_holds_a_user_file(workdir, capsys):
    finished(workdir / "s.zarr")
    (workdir / "s.zarr" / "README").write_text("what this run is\n")
    before = tree(workdir)
    assert main(["run", "base.toml", "--out", "s.zarr", "--overwrite", "--no-progress"]) == 2
    assert "files granframe did not write (README)" in capsys.readouterr().err
    assert tree(workdir) == before


def test_overwrite_replaces_a_run_store_and_an_empty_directory(workdir):
    finished(workdir / "s.zarr", OLD)
    (workdir / "empty").mkdir()
    for target in ("s.zarr", "empty"):
        assert main(["run", "base.toml", "--out", target, "--overwrite", "--no-progress"]) == 0
        assert RunStore.open(target).metadata["description"] == NEW.to_dict()
    assert (workdir / "notes.txt").read_text() == "my notes\n"


# -- 2. a kill inside --overwrite never leaves a hybrid ------------------------------------
@pytest.mark.parametrize("name", ["s.zarr", "r[1].zarr", "granframe-new.zarr"])
def test_a_kill_between_the_two_renames_of_a_swap_is_completed_by_the_next_writer(
        workdir, capsys, name):
    """Also for names that are glob patterns or hold the staging marker: the next writer
    finds the swap of its own store, and leaves another store's staging alone."""
    finished(workdir / name, OLD)
    decoy = workdir / ".r1.zarr.granframe-new-0123456789ab"   # r1.zarr's, being created
    decoy.mkdir()
    arguments = ["run", "base.toml", "--out", name, "--overwrite", "--no-progress"]
    (workdir / "count").mkdir()
    (workdir / "count" / "base.toml").write_text(NEW.to_toml())
    finished(workdir / "count" / name, OLD)
    renames = [int(line.split()[0]) for line in writes(workdir / "count", arguments)
               if line.split()[1] == "rename"]
    killed = subprocess.run([sys.executable, str(HARNESS), str(renames[1]), "log", *arguments],
                            capture_output=True, text=True, timeout=120)
    assert killed.returncode == -signal.SIGKILL
    # the old store was moved aside and the new one not yet in place: nothing reads as data
    assert not (workdir / name).exists() and RunStore.exists(workdir / name)
    with pytest.raises(FileNotFoundError):
        xarray.open_zarr(workdir / name)
    assert main(["info", name]) == 2
    assert "replacement was cut short: run it again with --resume" in capsys.readouterr().err
    assert main(["run", "base.toml", "--out", name, "--resume", "--no-progress"]) == 0
    reference = contents(finished(workdir / "reference.zarr"))
    assert_same(contents(workdir / name), reference, "completed swap")
    assert not [p.name for p in workdir.iterdir() if p.name.startswith(f".{name}")]
    assert decoy.is_dir()


# -- 3. checksums; a missing chunk is never a zero ------------------------------------------
def test_a_damaged_chunk_raises_on_every_read(workdir, capsys):
    store = finished(workdir / "s.zarr")
    flip(store / "f" / "c" / "2" / "0" / "0")
    with pytest.raises(ValueError, match="checksum"):
        xarray.open_zarr(store).f.values
    assert main(["check", "s.zarr"]) == 3
    out = capsys.readouterr().out
    assert "damaged: f/c/2/0/0 (from entry 2)" in out and "DAMAGED" in out
    assert main(["plot", "s.zarr", "--out", "figures"]) == 2
    assert "is damaged: damaged chunk f/c/2/0/0" in capsys.readouterr().err
    assert not (workdir / "figures").exists() or not list((workdir / "figures").iterdir())
    flip(store / "mass" / "c" / "0")
    assert main(["info", "s.zarr"]) == 2
    assert "damaged chunk mass/c/0" in capsys.readouterr().err


def test_a_missing_chunk_is_never_read_as_a_zero(workdir, capsys):
    store = finished(workdir / "s.zarr")
    (store / "f" / "c" / "1" / "0" / "0").unlink()
    (store / "step" / "c" / "0").unlink()
    ds = xarray.open_zarr(store)
    assert numpy.isnan(ds.f.isel(time=1).values).all()          # NaN, not zeros
    assert (ds.step.values == -1).all()
    with pytest.raises(StoreDamagedError, match="missing chunk f/c/1/0/0"):
        RunStore.open(store)
    assert main(["info", "s.zarr"]) == 2
    assert main(["check", "s.zarr"]) == 3
    out = capsys.readouterr().out
    assert "missing: f/c/1/0/0" in out and "missing: step/c/0" in out
    assert main(["check", str(finished(workdir / "intact.zarr"))]) == 0


def test_resume_from_a_damaged_last_snapshot_says_so_and_rolls_back_on_request(workdir,
                                                                              capsys):
    reference = contents(finished(workdir / "reference.zarr"))
    store = finished(workdir / "s.zarr")
    # the run as a kill after its third commit (t = 0.2) leaves it, and that commit damaged
    cut = RunStore.open(store, mode="r+")
    meta = cut.metadata
    meta["progress"] = dict(meta["progress"], snapshots=3, records=5, step=4, time=0.2,
                            status="running")
    cut.group.attrs["granframe"] = meta
    flip(store / "f" / "c" / "2" / "0" / "0")
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "is damaged (damaged chunk f/c/2/0/0)" in err
    assert "last intact commit is snapshot 1 at t = 0.1 (step 2)" in err
    assert "--resume --rollback" in err
    assert RunStore.open(store).progress["status"] == "running"     # not blamed on physics
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--rollback",
                 "--no-progress"]) == 0
    resumed = contents(store)
    assert resumed["meta"]["progress"]["rollbacks"] == [2]
    assert_same(resumed, reference, "rolled back and resumed")
    assert check(store)[0]


# -- 4. one writer at a time -----------------------------------------------------------------
SLOW = heated(grid={"dimension": 2, "n_modes": 32, "support_radius": 10.0}, time_step=0.002,
              final_time=1.6, output={"snapshot_interval": 0.1})


def wait_for(condition, what, timeout=60):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if condition():
                return
        except (StoreDamagedError, ValueError, KeyError, OSError):
            pass                 # a store or its metadata being written this instant
        time.sleep(0.03)
    raise AssertionError(f"timed out waiting for {what}")


def test_a_second_writer_is_refused_by_name_and_the_first_run_is_intact(workdir, capsys):
    (workdir / "slow.toml").write_text(SLOW.to_toml())
    writer = subprocess.Popen([sys.executable, "-m", "granframe.tools.cli", "run", "slow.toml",
                               "--out", "s.zarr", "--no-progress"], stderr=subprocess.PIPE,
                              text=True)
    wait_for(lambda: RunStore.open("s.zarr").snapshot_count >= 2, "the first snapshots")
    for extra in (["--overwrite"], ["--resume"]):
        assert main(["run", "base.toml", "--out", "s.zarr", "--no-progress", *extra]) == 2
        err = capsys.readouterr().err
        assert f"is being written by pid {writer.pid} on host " in err and " since " in err
    writer.send_signal(signal.SIGINT)                       # Ctrl-C
    assert writer.wait(timeout=60) == 130
    assert "continue with --resume" in writer.stderr.read()
    assert RunStore.open("s.zarr").progress["status"] == "interrupted"
    group = RunStore.open("s.zarr").group
    n = RunStore.open("s.zarr").progress["records"]
    assert list(group["step"][:n]) == list(range(n))      # the first run, untouched


def test_a_lock_of_a_dead_process_does_not_block(workdir):
    holder = subprocess.Popen([sys.executable, "-c", textwrap.dedent("""
        import sys, time
        from granframe.run.storage import WriterLock
        lock = WriterLock("s.zarr").acquire()
        print("held", flush=True)
        time.sleep(600)
    """)], stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline() == "held\n"
    with pytest.raises(StoreLockedError, match=f"pid {holder.pid} on host"):
        WriterLock("s.zarr").acquire()
    holder.kill()
    holder.wait()
    assert f'"pid": {holder.pid}' in lock_path("s.zarr").read_text()   # its record stays
    start = time.monotonic()
    with WriterLock("s.zarr") as lock:
        assert lock.held and time.monotonic() - start < 1.0


def test_a_sweep_task_given_again_waits_for_the_live_worker_and_never_writes_twice(workdir):
    """Dask gives a task presumed dead to another worker while the first still runs it:
    the second waits for the first's writer lock, then returns the finished run's row."""
    path = workdir / "runs" / "point"
    first = subprocess.Popen([sys.executable, "-c", "import json, sys; from granframe.run.sweep "
                              "import run_point; run_point(json.loads(sys.argv[1]), "
                              "sys.argv[2])", __import__("json").dumps(SLOW.to_dict()),
                              str(path)])
    wait_for(lambda: RunStore.open(path).snapshot_count >= 2, "the first worker's snapshots")
    row = run_point(SLOW.to_dict(), str(path), poll=0.05)   # the second worker
    assert first.wait(timeout=120) == 0
    assert row["status"] == "finished" and row["steps"] == 800
    store = RunStore.open(path)
    assert store.progress["resumes"] == []                  # written by the first alone
    assert list(store.group["step"][:]) == list(range(801))


# -- 5. creation is atomic ------------------------------------------------------------------
def test_ctrl_c_during_creation_leaves_nothing_and_says_so(workdir, capsys, monkeypatch):
    def interrupted(self, *args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(RunStore, "publish", interrupted)
    assert main(["run", "base.toml", "--out", "s.zarr", "--no-progress"]) == 130
    err = capsys.readouterr().err
    assert "nothing was written to 's.zarr'" in err and "--resume" not in err
    assert sorted(p.name for p in workdir.iterdir()) == ["base.toml", "notes.txt"]


def test_a_full_disk_during_creation_leaves_nothing(workdir, capsys, monkeypatch):
    store_set, calls = zarr.storage.LocalStore.set, []

    async def full_after_twenty(self, key, value):
        calls.append(key)
        if len(calls) > 20:
            raise OSError(errno.ENOSPC, "No space left on device")
        return await store_set(self, key, value)
    monkeypatch.setattr(zarr.storage.LocalStore, "set", full_after_twenty)
    assert main(["run", "base.toml", "--out", "s.zarr", "--no-progress"]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert sorted(p.name for p in workdir.iterdir()) == ["base.toml", "notes.txt"]


# -- smaller cases ----------------------------------------------------------------------
@pytest.mark.parametrize("name", ["../x", "/tmp/x", "a/b", ".hidden", ""])
def test_study_run_names_stay_inside_out(name):
    runs = {name: NEW, "other": NEW} if name else {"": NEW, "other": NEW}
    with pytest.raises(ValueError, match="parameter 'runs'"):
        Study(runs)


def test_resume_and_overwrite_together_are_refused(workdir, capsys):
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--overwrite"]) == 2
    assert "--resume and --overwrite exclude each other" in capsys.readouterr().err
    assert main(["run", "base.toml", "--out", "s.zarr", "--rollback"]) == 2
    assert not (workdir / "s.zarr").exists()


def test_sweep_out_refuses_a_run_store_and_workers_must_be_positive(workdir, capsys):
    store = finished(workdir / "s.zarr")
    before = tree(workdir)
    (workdir / "sweep.toml").write_text(textwrap.dedent("""
        [base]
        final_time = 0.1
        [base.grid]
        dimension = 2
        n_modes = 16
        support_radius = 10.0
        [product]
        "restitution.value" = [0.5]
    """))
    before["sweep.toml"] = (workdir / "sweep.toml").read_bytes()
    assert main(["sweep", "sweep.toml", "--out", str(store)]) == 2
    assert "it is a granframe run store" in capsys.readouterr().err
    for workers in ("0", "-1"):
        assert main(["sweep", "sweep.toml", "--out", "new.zarr", "--workers", workers]) == 2
        assert "parameter 'workers'" in capsys.readouterr().err
    assert tree(workdir) == before


def test_partial_files_of_a_killed_write_are_reported_and_removed_on_resume(workdir, capsys):
    store = finished(workdir / "s.zarr")
    progress = dict(RunStore.open(store).progress, status="running")
    cut = RunStore.open(store, mode="r+")
    cut.group.attrs["granframe"] = dict(cut.metadata, progress=progress)
    partial = store / "f" / "c" / "9.0123abcd.partial"
    partial.write_bytes(b"half a chunk")
    assert main(["check", "s.zarr"]) == 0
    assert "1 file(s) of a write cut short" in capsys.readouterr().out
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--no-progress"]) == 0
    assert not partial.exists()


def test_a_study_report_that_raises_is_a_clear_error_and_keeps_the_runs(workdir, capsys):
    (workdir / "study.py").write_text(textwrap.dedent(f"""
        from granframe.run.description import RunDescription

        def runs(quick=False):
            d = RunDescription.from_toml({NEW.to_toml()!r})
            return {{"a": d, "b": d}}

        def report(stores, out):
            return 1 / 0
    """))
    assert main(["run", "study.py", "--out", "out", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "the report of study 'study.py' failed: ZeroDivisionError: division by zero" in err
    assert "study.py:9)" in err and "Traceback" not in err
    assert all(RunStore.open(workdir / "out" / f"{n}.zarr").progress["status"] == "finished"
               for n in "ab")


def test_ctrl_c_during_start_up_exits_130_without_a_traceback(workdir):
    process = subprocess.Popen([sys.executable, "-m", "granframe.tools.cli", "run", "base.toml",
                                "--out", "s.zarr", "--no-progress"], stderr=subprocess.PIPE,
                               text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    # start-up: main() has begun the run (NumPy, which the command line itself does not
    # import, is loaded) and the run has not started writing
    wait_for(lambda: "numpy" in pathlib.Path(f"/proc/{process.pid}/maps").read_text(),
             "the command to import NumPy", timeout=30)
    process.send_signal(signal.SIGINT)
    err = process.communicate(timeout=60)[1]
    assert process.returncode == 130 and "Traceback" not in err, err
    assert "interrupted" in err
    assert not (workdir / "s.zarr").exists() or RunStore.open("s.zarr").progress[
        "status"] in ("interrupted", "finished")


@pytest.mark.parametrize("quiet", [False, True])
def test_after_an_interrupt_failures_of_half_built_objects_at_exit_stay_silent(quiet):
    """Ctrl-C inside an event loop's constructor (zarr's, during start-up, on a loaded
    machine) left a loop whose destructor raised at exit, and Python printed it as
    "Exception ignored ... Traceback" after granframe's line. After the interrupt the
    command line silences such failures and the unawaited coroutines' warnings
    (``quiet_teardown``); without it they print."""
    code = ("import asyncio\n"
            "from granframe.tools.cli_run import quiet_teardown\n"
            "class HalfBuilt:\n"
            "    def __del__(self):\n"
            "        raise AttributeError('_signal_handlers')\n"
            "async def create_group():\n"
            "    pass\n"
            "left = [HalfBuilt(), create_group()]\n"
            + ("quiet_teardown()\n" if quiet else "")
            + "del left\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0
    if quiet:
        assert done.stderr == "", done.stderr
    else:
        assert "Exception ignored" in done.stderr and "never awaited" in done.stderr


def test_ctrl_c_during_any_import_is_sent_again_after_it(tmp_path, monkeypatch):
    """The command line's SIGINT handler, called as the signal would call it in a function
    of a module being imported (as NumPy's compiled core imports ``datetime`` while it
    initialises: a KeyboardInterrupt there became NumPy's ImportError and a traceback),
    schedules the signal again instead of raising; outside an import it raises."""
    from granframe.tools import cli

    sent = []

    class Timer:
        def __init__(self, delay, function, args):
            sent.append((delay, function, args))

        def start(self):
            pass

    monkeypatch.setattr("threading.Timer", Timer)
    (tmp_path / "being_imported.py").write_text(textwrap.dedent("""
        import signal
        import sys

        from granframe.tools import cli


        def deep():
            cli._interrupt(signal.SIGINT, sys._getframe())


        deep()
        """))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "being_imported", raising=False)
    try:
        __import__("being_imported")
    except KeyboardInterrupt:
        pytest.fail("the handler raised KeyboardInterrupt inside an import")
    assert [(delay, args) for delay, _, args in sent] == [(0.01, (os.getpid(), signal.SIGINT))]
    with pytest.raises(KeyboardInterrupt):
        cli._interrupt(signal.SIGINT, sys._getframe())
    assert len(sent) == 1


def test_ctrl_c_to_a_sweep_exits_130_and_leaves_its_runs_resumable(workdir):
    import tomli_w

    (workdir / "sweep.toml").write_text(tomli_w.dumps(
        {"base": SLOW.to_dict(), "product": {"restitution.value": [0.5, 0.6]}}))
    process = subprocess.Popen([sys.executable, "-m", "granframe.tools.cli", "sweep", "sweep.toml",
                                "--out", "s.zarr", "--workers", "1", "--no-progress"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for(lambda: any(RunStore.open(p).snapshot_count >= 2
                         for p in (workdir / "s.zarr" / "runs").iterdir()
                         if RunStore.exists(p)), "a run of the sweep")
    process.send_signal(signal.SIGINT)
    err = process.communicate(timeout=120)[1]
    assert process.returncode == 130 and "Traceback" not in err, err
    assert "run the same sweep again to continue" in err
    for path in (workdir / "s.zarr" / "runs").iterdir():
        if RunStore.exists(path):
            assert RunStore.open(path).progress["status"] in ("running", "interrupted")


def test_check_reads_every_run_and_the_table_of_a_sweep_store(workdir, capsys):
    from granframe.run.sweep import _summary, _write_table

    root = zarr.open_group("s.zarr", mode="w", zarr_format=3)
    root.attrs["granframe_sweep"] = {"schema": "granframe.run.sweep/1", "runs": ["a"]}
    finished(workdir / "s.zarr" / "runs" / "a")
    _write_table(root, ["a"], [{"restitution.value": 0.5}], {"a": _summary("s.zarr/runs/a")})
    assert main(["check", "s.zarr"]) == 0
    flip(workdir / "s.zarr" / "table" / "temperature" / "c" / "0", count=4)
    assert main(["check", "s.zarr"]) == 3
    assert "damaged: table/temperature" in capsys.readouterr().out


def test_a_ctrl_c_after_the_last_commit_leaves_the_store_finished(workdir, monkeypatch):
    write = RunStore._write_progress

    def then_ctrl_c(self, progress):
        write(self, progress)
        if progress["status"] == "finished":
            raise KeyboardInterrupt
    monkeypatch.setattr(RunStore, "_write_progress", then_ctrl_c)
    assert main(["run", "base.toml", "--out", "s.zarr", "--no-progress"]) == 130
    assert RunStore.open("s.zarr").progress["status"] == "finished"


def test_an_array_removed_whole_is_damage_and_never_a_traceback(workdir, capsys):
    import shutil

    finished(workdir / "s.zarr")
    progress = dict(RunStore.open("s.zarr").progress, status="running")
    cut = RunStore.open("s.zarr", mode="r+")
    cut.group.attrs["granframe"] = dict(cut.metadata, progress=progress)
    shutil.rmtree(workdir / "s.zarr" / "mass")
    assert main(["check", "s.zarr"]) == 3
    assert "missing array: mass" in capsys.readouterr().out
    for command in (["info", "s.zarr"],
                    ["run", "base.toml", "--out", "s.zarr", "--resume", "--no-progress"]):
        assert main(command) == 2
        assert "damaged: missing array mass" in capsys.readouterr().err


def test_a_sweep_task_on_a_damaged_finished_store_returns_a_failed_row(workdir):
    path = finished(workdir / "runs" / "point")
    (path / "f" / "c" / "1" / "0" / "0").unlink()
    row = run_point(NEW.to_dict(), str(path))
    assert row["status"] == "failed" and "cannot be read" in row["message"]


def test_a_resume_that_finds_the_store_made_meanwhile_continues_it(workdir, monkeypatch):
    """Another writer published the store between this run's look and its lock."""
    finished(workdir / "s.zarr")
    monkeypatch.setattr(RunStore, "exists", staticmethod(lambda path: False))
    result = Simulation(NEW).run(workdir / "s.zarr", resume=True, progress=False)
    assert result.status == "already finished"


def test_overwrite_refuses_a_sweep_store_whose_run_is_still_written(workdir, capsys):
    root = zarr.open_group("sweep.zarr", mode="w", zarr_format=3)
    root.attrs["granframe_sweep"] = {"schema": "granframe.run.sweep/1", "runs": ["a"]}
    finished(workdir / "sweep.zarr" / "runs" / "a")
    with WriterLock(workdir / "sweep.zarr" / "runs" / "a"):   # a worker that outlived its driver
        assert main(["run", "base.toml", "--out", "sweep.zarr", "--overwrite",
                     "--no-progress"]) == 2
    assert f"is being written by pid {os.getpid()}" in capsys.readouterr().err
    assert RunStore.exists(workdir / "sweep.zarr" / "runs" / "a")
    assert main(["run", "base.toml", "--out", "sweep.zarr", "--overwrite", "--no-progress"]) == 0


def test_check_calls_a_sweep_with_an_unreadable_run_damaged(workdir, capsys):
    root = zarr.open_group("s.zarr", mode="w", zarr_format=3)
    root.attrs["granframe_sweep"] = {"schema": "granframe.run.sweep/1", "runs": ["a"]}
    finished(workdir / "s.zarr" / "runs" / "a")
    (workdir / "s.zarr" / "runs" / "a" / "zarr.json").write_text("{not json")
    assert main(["check", "s.zarr"]) == 3
    assert "runs/a is not a readable run store" in capsys.readouterr().out


@pytest.mark.parametrize("damage", ["missing", "flipped"])
def test_a_finished_run_damaged_is_made_again_from_before_the_damage_by_rollback(
        workdir, capsys, damage):
    """``--resume --rollback`` on a finished store with a damaged chunk of f said "already
    finished" and left it damaged (``check`` listed the damage). Now the store is checked
    whole, taken back to the snapshot before the first damage and the run made again
    from there: finished, intact, equal to the undamaged store; a second --rollback
    finds nothing to take back."""
    reference = contents(finished(workdir / "reference.zarr"))
    finished(workdir / "s.zarr")
    chunks = sorted((workdir / "s.zarr" / "f" / "c").rglob("*"))
    chunk = [c for c in chunks if c.is_file()][1]               # the second snapshot's f
    chunk.unlink() if damage == "missing" else flip(chunk)
    assert main(["check", "s.zarr"]) == 3
    capsys.readouterr()
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--rollback",
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "s.zarr: finished," in out and "already finished" not in out, out
    assert main(["check", "s.zarr"]) == 0
    resumed = contents(workdir / "s.zarr")
    assert_same(resumed, reference, "rolled back and made again")
    assert resumed["meta"]["progress"]["status"] == "finished"
    assert resumed["meta"]["progress"]["rollbacks"]
    capsys.readouterr()
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--rollback",
                 "--no-progress"]) == 0
    assert "every chunk is intact: nothing to roll back" in capsys.readouterr().out


def test_resume_with_rollback_of_a_health_stop_exits_3(workdir, capsys):
    d = heated(integrator="forward_euler", heat_bath=50.0, time_step=0.05, final_time=5.0,
               output={"snapshot_interval": 0.5}, health={"step_limit": False})
    (workdir / "bad.toml").write_text(d.to_toml())
    assert main(["run", "bad.toml", "--out", "bad.zarr", "--no-progress"]) == 3
    assert main(["run", "bad.toml", "--out", "bad.zarr", "--resume", "--rollback",
                 "--no-progress"]) == 3
    assert "stopped earlier by a health check" in capsys.readouterr().err


# -- 10. what an interruption or a kill leaves, said in one line ---------------------------
def test_a_ctrl_c_just_after_the_store_is_published_says_resume(workdir, capsys, monkeypatch):
    """The store exists with status 'running' (cut before the run could mark it): the
    message points to --resume, which then finishes the run."""
    publish = RunStore.publish

    def then_ctrl_c(self, *args, **kwargs):
        publish(self, *args, **kwargs)
        raise KeyboardInterrupt
    monkeypatch.setattr(RunStore, "publish", then_ctrl_c)
    assert main(["run", "base.toml", "--out", "s.zarr", "--no-progress"]) == 130
    err = capsys.readouterr().err
    assert "holds every complete snapshot (status running): continue with --resume" in err
    assert "as it was before this run" not in err
    monkeypatch.setattr(RunStore, "publish", publish)
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--no-progress"]) == 0
    assert RunStore.open("s.zarr").progress["status"] == "finished"


def test_a_ctrl_c_while_the_process_exits_ends_it_without_a_traceback(workdir):
    """A Ctrl-C during the atexit callbacks (Dask, thread pools) after the command ends the
    process with the command's status, not with "Exception ignored in atexit callback"."""
    script = textwrap.dedent("""
        import atexit, os, signal, sys, time
        from granframe.tools import cli
        atexit.register(lambda: (os.kill(os.getpid(), signal.SIGINT), time.sleep(5)))
        sys.argv = ["granframe", "plugins", "restitution_laws"]
        cli.entry()
        """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert "Exception ignored" not in done.stderr and "Traceback" not in done.stderr
    assert "restitution_laws" in done.stdout


def test_stray_entries_left_in_a_store_give_no_zarr_warning(workdir):
    """A directory that is not a zarr node (a kill during an array's creation, a user's
    folder) is ignored by every read, without zarr's warning, and named by check in one
    line (a process of its own: pytest shows every warning)."""
    finished(workdir / "s.zarr")
    (workdir / "s.zarr" / "leftover").mkdir()
    command = "from granframe.tools.cli import entry; entry()"
    for arguments, status in ((["info", "s.zarr"], 0), (["check", "s.zarr"], 0)):
        done = subprocess.run([sys.executable, "-c", command, *arguments], capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == status, done.stderr
        assert "Warning" not in done.stderr, done.stderr
    assert "1 entry that no run writes (ignored; left by a write cut short, or added by " \
           "hand): leftover" in done.stdout


def test_a_damaged_moment_chunk_is_rolled_back_from_intact_f(workdir, capsys):
    """f is intact but the chunk of kurtosis records is damaged: --resume names the damage
    and the rollback; --rollback continues from the last snapshot, drops the damaged
    records (NaN), writes the step numbers again and says so."""
    store = finished(workdir / "s.zarr")
    cut = RunStore.open(store, mode="r+")
    meta = cut.metadata
    meta["progress"] = dict(meta["progress"], snapshots=3, records=5, step=4, time=0.2,
                            status="running")
    cut.group.attrs["granframe"] = meta
    flip(store / "kurtosis" / "c" / "0", 4)
    flip(store / "step" / "c" / "0", 4)
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "last intact commit is snapshot 2 at t = 0.2 (step 4)" in err
    assert "moment records of the damaged chunks (10 records) are dropped (NaN)" in err
    assert main(["run", "base.toml", "--out", "s.zarr", "--resume", "--rollback",
                 "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert ("the rollback dropped the moment records of damaged chunks: kurtosis 0 .. 4 (now "
            "NaN); step 0 .. 4 (written again: record i is step i)") in err
    assert check(store)[0]
    group = zarr.open_group(str(store), mode="r")
    kurtosis = group["kurtosis"][:]
    assert numpy.isnan(kurtosis[:5]).all() and numpy.isfinite(kurtosis[5:]).all()
    assert (group["step"][:] == numpy.arange(len(kurtosis))).all()
    assert main(["info", "s.zarr"]) == 0
    assert "rollback    dropped the moment records" in capsys.readouterr().out
