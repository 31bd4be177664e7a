"""A real ``granframe run`` process killed (SIGKILL) at its K-th write, K sampled over every
write of the run: the creation of its store, each commit, and the replacement of an existing
store by ``--overwrite``. Every outcome must be either the previous state (no store, or the
previous store bit for bit) or a store that resumes to the uninterrupted result bit for bit;
never a store that reads as finished with other data."""

import pathlib
import random
import shutil
import subprocess
import sys

import numpy
import pytest
import zarr

from granframe.tools.cli import main
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore, check
from test_runner import heated

HARNESS = pathlib.Path(__file__).with_name("kill_at_write.py")
SMALL = dict(grid={"dimension": 2, "n_modes": 16, "support_radius": 10.0},
             operator={"name": "fast_spectral", "radial_points": 8,
                       "sphere": {"name": "circle_trapezoid", "n_points": 8}},
             final_time=0.3, time_step=0.05, output={"snapshot_interval": 0.1})
NEW = heated(**SMALL)
OLD = heated(**{**SMALL, "heat_bath": 0.2, "final_time": 0.2})   # the store --overwrite replaces


def contents(path) -> dict:
    """Every array (committed part and all) and the root metadata of a store, read back."""
    group = zarr.open_group(str(path), mode="r", use_consolidated=False)
    data = {name: group[name][:] for name in group.array_keys()}
    meta = dict(group.attrs["granframe"])
    meta.pop("updated", None)
    return {"arrays": data, "meta": meta}


def assert_same(a: dict, b: dict, what: str) -> None:
    assert sorted(a["arrays"]) == sorted(b["arrays"]), what
    for name in a["arrays"]:
        numpy.testing.assert_array_equal(a["arrays"][name], b["arrays"][name],
                                         err_msg=f"{what}: {name}")


def writes(workdir, arguments) -> list[str]:
    """The writes of an uninterrupted run (K = 0), one 'index operation path' line each."""
    log = workdir / "count.log"
    done = subprocess.run([sys.executable, str(HARNESS), "0", str(log), *arguments],
                          cwd=workdir, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return log.read_text().splitlines()


def sample(lines, count, seed) -> list[int]:
    """K values: every rename (the swaps), the first write, and a seeded sample of the rest,
    a third of it in the creation of the store (up to the rename that puts it in place)."""
    renames = [int(line.split()[0]) for line in lines if line.split()[1] == "rename"]
    total, created = len(lines), renames[-1]
    rng = random.Random(seed)
    ks = set(renames) | {1, created + 1, total}
    ks |= set(rng.sample(range(2, created), count // 3))
    ks |= set(rng.sample(range(created + 2, total), count - count // 3))
    return sorted(ks)


def kill_at(k, workdir, arguments) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(HARNESS), str(k), str(workdir / "kill.log"),
                           *arguments], cwd=workdir, capture_output=True, text=True,
                          timeout=120)


def assert_resumes_to(store, reference, toml) -> None:
    """``--resume`` continues the store to the reference result, bit for bit."""
    assert main(["run", str(toml), "--out", str(store), "--resume", "--no-progress"]) == 0
    got = contents(store)
    assert got["meta"]["progress"]["status"] == "finished"
    assert got["meta"]["description"] == reference["meta"]["description"]
    assert_same(got, reference, f"resumed {store}")
    assert check(store)[0]
    leftovers = [p.name for p in store.parent.iterdir() if p.name.startswith(f".{store.name}.")]
    assert not leftovers, leftovers
    assert not list(store.rglob("*.partial"))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    path = tmp_path_factory.mktemp("reference") / "reference.zarr"
    Simulation(NEW).run(path, progress=False)
    return contents(path)


def test_a_run_killed_at_any_write_of_its_creation_or_commits_resumes_bitwise(
        tmp_path, reference):
    (tmp_path / "count").mkdir()
    toml = tmp_path / "run.toml"
    toml.write_text(NEW.to_toml())
    arguments = ["run", str(toml), "--out", "s.zarr", "--no-progress"]
    lines = writes(tmp_path / "count", arguments)
    outcomes = {"nothing": 0, "resumed": 0}
    for k in sample(lines, 18, seed=16):
        workdir = tmp_path / f"k{k}"
        workdir.mkdir()
        killed = kill_at(k, workdir, arguments)
        assert killed.returncode == -9, (k, killed.returncode, killed.stderr)
        store = workdir / "s.zarr"
        if not RunStore.exists(store):       # killed before its store was in place
            assert not store.exists(), (k, list(workdir.iterdir()))
            outcomes["nothing"] += 1
            assert main(["run", str(toml), "--out", str(store), "--no-progress"]) == 0
            assert_same(contents(store), reference, f"fresh run after a kill at {k}")
            continue
        assert_resumes_to(store, reference, toml)
        outcomes["resumed"] += 1
    print(f"creation and commits: {len(lines)} writes, outcomes {outcomes}")
    assert outcomes["nothing"] >= 5 and outcomes["resumed"] >= 10, outcomes


def test_overwrite_killed_at_any_write_leaves_the_old_store_or_a_resumable_new_one(
        tmp_path, reference):
    template = tmp_path / "template"
    template.mkdir()
    Simulation(OLD).run(template / "s.zarr", progress=False)
    old = contents(template / "s.zarr")
    toml = tmp_path / "run.toml"
    toml.write_text(NEW.to_toml())
    arguments = ["run", str(toml), "--out", "s.zarr", "--overwrite", "--no-progress"]
    shutil.copytree(template, tmp_path / "count")
    lines = writes(tmp_path / "count", arguments)
    assert sum(1 for line in lines if line.split()[1] == "rename") == 2   # the swap
    outcomes = {"old": 0, "new": 0}
    for k in sample(lines, 18, seed=17):
        workdir = tmp_path / f"k{k}"
        shutil.copytree(template, workdir)
        killed = kill_at(k, workdir, arguments)
        assert killed.returncode == -9, (k, killed.returncode, killed.stderr)
        store = workdir / "s.zarr"
        assert RunStore.exists(store), (k, sorted(p.name for p in workdir.iterdir()))
        if store.exists() and contents(store)["meta"]["description"] == old["meta"][
                "description"]:
            assert_same(contents(store), old, f"old store after a kill at {k}")
            assert contents(store)["meta"] == old["meta"]
            outcomes["old"] += 1
            continue
        assert_resumes_to(store, reference, toml)
        outcomes["new"] += 1
    print(f"--overwrite: {len(lines)} writes, outcomes {outcomes}")
    assert outcomes["old"] >= 5 and outcomes["new"] >= 10, outcomes
