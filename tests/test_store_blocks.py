"""A space run's store written block by block: the phases of a commit.

``begin_commit`` (one writer) resizes the arrays, ``write_block`` (the owner of a block of
cells) writes the chunk files of its cells of f and of the fields and nothing else,
``write_shared`` writes what no block owns and ``end_commit`` makes the commit visible.
Blocks in any order give the store ``commit`` gives; a commit cut short before
``end_commit`` is never seen and is dropped on resume; the fields are chunked by block,
and a store whose fields span all cells in one chunk still opens, resumes and appends.
"""

import random

import attrs
import numpy
import pytest
import zarr

import granframe
from granframe.run.storage import (STEP_RECORDS, CommitPlan, Layout, RecordArray, RunStore,
                                   StoreError, check, homogeneous_layout)

CELLS, BLOCK, N = 24, 8, 6           # three blocks of 8 cells, a 6 x 6 velocity grid
BLOCKS = [slice(b, b + BLOCK) for b in range(0, CELLS, BLOCK)]
#: the fields of a space run: shape and dimensions after (step_time, x)
FIELDS = {"density": ((), ()), "velocity": ((2,), ("axis",)), "temperature": ((), ()),
          "pressure_tensor": ((2, 2), ("axis", "axis2")), "heat_flux": ((2,), ("axis",))}
TOTALS = ("mass", "kinetic_energy", "min_f", "negative_mass_fraction")
WALLS = ("wall_mass", "wall_energy")
#: (snapshots, records) of each commit: f0 and its record first, then commits that
#: straddle the chunks of 4 records (the third starts in the committed part of chunk 0),
#: two snapshots at once, records alone
COMMITS = ((1, 1), (1, 2), (2, 6), (0, 2), (1, 5))


def layout(cells_chunk=BLOCK) -> Layout:
    """A space run's layout, 4 records per chunk; ``cells_chunk`` None: the fields chunked
    across all cells, as stores were written before they were chunked by block."""
    points = numpy.linspace(-3.0, 3.0, N, endpoint=False)
    fields = tuple(RecordArray(name, (CELLS,) + shape, ("x",) + dims, chunk=4,
                               cells_chunk=cells_chunk)
                   for name, (shape, dims) in FIELDS.items())
    records = (tuple(attrs.evolve(spec, chunk=4) for spec in STEP_RECORDS)
               + tuple(RecordArray(name, chunk=4) for name in TOTALS) + fields
               + tuple(RecordArray(name, (2,), ("wall",), chunk=4) for name in WALLS))
    centres = (numpy.arange(CELLS) + 0.5) / CELLS
    return Layout((("v1", points, ("v1",)), ("v2", points, ("v2",)), ("x", centres, ("x",))),
                  (CELLS, N, N), (BLOCK, N, N), ("x", "v1", "v2"), records,
                  space={"cells": CELLS, "length": 1.0, "block_cells": BLOCK})


def commits(seed: int = 3) -> list:
    """The (snapshots, records, progress) of each commit of :data:`COMMITS`: random data,
    steps numbered on, each commit's snapshots at its last step."""
    rng = numpy.random.default_rng(seed)
    shapes = {**{name: () for name in TOTALS}, **{name: (2,) for name in WALLS},
              **{name: (CELLS,) + shape for name, (shape, _) in FIELDS.items()}}
    out, first = [], 0
    for snapshots, count in COMMITS:
        steps = numpy.arange(first, first + count)
        first += count
        records = {"step_time": 0.01 * steps, "step": steps, "dt": numpy.full(count, 0.01),
                   **{name: rng.standard_normal((count,) + shape)
                      for name, shape in shapes.items()}}
        frames = [(0.01 * (first - 1), rng.standard_normal((CELLS, N, N)))
                  for _ in range(snapshots)]
        out.append((frames, records, {"status": "running", "step": first - 1,
                                      "time": 0.01 * (first - 1), "dt_next": 0.01}))
    return out


def new_store(path, cells_chunk=BLOCK) -> RunStore:
    return RunStore.create(path, {}, "", None, {}, layout=layout(cells_chunk))


def commit_by_blocks(store: RunStore, snapshots, records, progress, owners) -> None:
    """One commit in its phases, the cells of ``owners`` (slices) written in that order."""
    plan = store.begin_commit(len(snapshots), len(records["step_time"]))
    for cells in owners:
        store.write_block(plan, cells, f=[f[cells] for _, f in snapshots],
                          records={name: records[name][:, cells] for name in FIELDS})
    store.write_shared(plan, times=[t for t, _ in snapshots], step=progress["step"],
                       dt_next=progress["dt_next"],
                       records={n: v for n, v in records.items() if n not in FIELDS})
    store.end_commit(plan, progress)


def write(path, how, cells_chunk=BLOCK, data=None) -> None:
    """A store of :func:`commits`, each commit written by ``how(store, *commit)``."""
    store = new_store(path, cells_chunk)
    try:
        for k, commit in enumerate(data or commits()):
            how(store, *commit)
            if k == 0:
                store.publish()
    finally:
        store.close()


def whole(store, snapshots, records, progress):
    store.commit(snapshots, records, progress)


def files(path) -> dict:
    """Every file of a store and its bytes, but the root metadata (which holds the time it
    was created and last written)."""
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*"))
            if p.is_file() and str(p.relative_to(path)) != "zarr.json"}


def stats(path) -> dict:
    """Every file of a store, and its inode and mtime: a file written anew (zarr renames a
    temporary file into place) changes both."""
    return {str(p.relative_to(path)): (p.stat().st_ino, p.stat().st_mtime_ns)
            for p in path.rglob("*") if p.is_file()}


def changed(before: dict, after: dict) -> set:
    return {name for name, stat in after.items() if before.get(name) != stat}


def chunk_files(path, name: str) -> set:
    """The chunk files of the array ``name``, as their indices 'i/j/...'."""
    root = path / name / "c"
    return {str(p.relative_to(root)) for p in root.rglob("*") if p.is_file()}


def contents(path) -> dict:
    group = zarr.open_group(str(path), mode="r", use_consolidated=False)
    return {name: group[name][:] for name in group.array_keys()}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The store of :func:`commits` written by ``commit``."""
    path = tmp_path_factory.mktemp("reference") / "s.zarr"
    write(path, whole)
    return path


# -- blocks in any order --------------------------------------------------------------------
@pytest.mark.parametrize("order", ["in order", "reversed", "shuffled", "two owners"])
def test_blocks_in_any_order_give_the_store_commit_gives(reference, tmp_path, order):
    rng = random.Random(7)

    def owners():
        if order == "in order":
            return BLOCKS
        if order == "reversed":
            return BLOCKS[::-1]
        if order == "two owners":                        # blocks 1 and 2 by one writer
            return [slice(BLOCK, CELLS), slice(0, BLOCK)]
        return rng.sample(BLOCKS, len(BLOCKS))

    path = tmp_path / "s.zarr"
    write(path, lambda store, *commit: commit_by_blocks(store, *commit, owners()))
    assert files(path) == files(reference)
    assert RunStore.open(path).progress == RunStore.open(reference).progress
    assert check(path)[0]
    ds = granframe.open_run(path)
    numpy.testing.assert_array_equal(ds["f"].values[-1], commits()[-1][0][0][1])
    numpy.testing.assert_array_equal(ds["velocity"].values[-5:], commits()[-1][1]["velocity"])


def test_the_fields_of_a_space_store_are_chunked_by_block(reference):
    store = RunStore.open(reference)
    assert store.cell_arrays == ("f",) + tuple(FIELDS)
    chunks = {name: store.group[name].chunks for name in store.group.array_keys()}
    assert chunks["f"] == (1, BLOCK, N, N)
    assert chunks["density"] == chunks["temperature"] == (4, BLOCK)
    assert chunks["velocity"] == chunks["heat_flux"] == (4, BLOCK, 2)
    assert chunks["pressure_tensor"] == (4, BLOCK, 2, 2)
    assert chunks["mass"] == (4,) and chunks["wall_mass"] == (4, 2)
    assert RecordArray("density", (CELLS,), ("x",), chunk=4, cells_chunk=BLOCK).chunks == \
        (4, BLOCK)


# -- each writer touches its own files ------------------------------------------------------
def test_each_phase_writes_only_its_own_files(tmp_path):
    path = tmp_path / "s.zarr"
    data = commits()
    write(path, whole, data=data[:2])                 # 2 snapshots and 3 records committed
    store = RunStore.resume(path, {})
    snapshots, records, progress = data[2]            # 2 snapshots, records 3..8
    before = stats(path)
    plan = store.begin_commit(2, 6)
    assert plan == CommitPlan(range(2, 4), range(3, 9))
    metadata = changed(before, stats(path))           # metadata only
    assert metadata and all(name.endswith("zarr.json") for name in metadata), metadata
    assert "f/zarr.json" in metadata and "density/zarr.json" in metadata

    cells = BLOCKS[1]
    before = stats(path)
    store.write_block(plan, cells, f=[f[cells] for _, f in snapshots],
                      records={name: records[name][:, cells] for name in FIELDS})
    # the chunks of block 1: snapshots 2 and 3 of f, records 3..8 (chunks 0 to 2 of 4)
    expected = {f"f/c/{k}/1/0/0" for k in (2, 3)}
    for name, (shape, _) in FIELDS.items():
        rest = "/0" * len(shape)
        expected |= {f"{name}/c/{t}/1{rest}" for t in (0, 1, 2)}
    assert changed(before, stats(path)) == expected

    before = stats(path)
    store.write_shared(plan, times=[t for t, _ in snapshots], step=progress["step"],
                       dt_next=progress["dt_next"],
                       records={n: v for n, v in records.items() if n not in FIELDS})
    shared = changed(before, stats(path))
    assert {name.split("/")[0] for name in shared} == {
        "time", "snapshot_step", "snapshot_dt_next", "step_time", "step", "dt", *TOTALS, *WALLS}
    assert all("/c/" in name for name in shared), shared   # chunks only, no metadata

    for cells in (BLOCKS[2], BLOCKS[0]):
        store.write_block(plan, cells, f=[f[cells] for _, f in snapshots],
                          records={name: records[name][:, cells] for name in FIELDS})
    store.end_commit(plan, progress)
    store.close()
    numpy.testing.assert_array_equal(RunStore.open(path).group["f"][3], snapshots[1][1])


# -- what is refused ----------------------------------------------------------------------
def test_a_misaligned_or_foreign_slice_is_refused(tmp_path):
    store = new_store(tmp_path / "s.zarr")
    snapshots, records, progress = commits()[0]
    plan = store.begin_commit(1, 1)
    for cells in (slice(4, 12), slice(0, 12), slice(BLOCK, 20)):
        with pytest.raises(ValueError, match=r"RunStore.write_block: parameter 'cells' = "
                           r"slice\(.*\) is invalid; is not aligned with the blocks of array "
                           r"'f', chunked by 8 cells along x \(24 cells\): a and b must be "
                           r"multiples of 8 \(b may be 24\)"):
            store.write_block(plan, cells, f=[snapshots[0][1][cells]])
    for cells in (slice(16, 32), slice(8, 8), slice(0, 8, 2), 3, slice(0.0, 8.0)):
        with pytest.raises(ValueError, match=r"parameter 'cells' = .* is invalid; must be a "
                           r"slice a:b of the 24 cells"):
            store.write_block(plan, cells, f=[snapshots[0][1][:8]])
    with pytest.raises(ValueError, match=r"parameter 'f' has shape \(16, 6, 6\); it must "
                       r"have shape \(8, 6, 6\)"):
        store.write_block(plan, BLOCKS[0], f=[snapshots[0][1][:16]])
    with pytest.raises(ValueError, match=r"parameter 'f' holds 0 snapshot\(s\); it must hold "
                       r"the 1 new snapshot\(s\) of the plan"):
        store.write_block(plan, BLOCKS[0])
    with pytest.raises(ValueError, match=r"parameter 'records' = \['mass'\] is invalid; must "
                       r"name arrays among \['density', "):
        store.write_block(plan, BLOCKS[0], f=[snapshots[0][1][:8]],
                          records={"mass": records["mass"]})
    with pytest.raises(ValueError, match=r"parameter 'records' = \['density'\] is invalid; "
                       r"must name arrays among \['step_time', .*write_block"):
        store.write_shared(plan, times=[0.0], step=0, dt_next=0.01,
                           records={"density": records["density"]})
    with pytest.raises(ValueError, match=r"parameter 'f' holds 1 snapshot\(s\); it must be "
                       r"None in a store with a cells axis"):
        store.write_shared(plan, times=[0.0], step=0, dt_next=0.01, f=[snapshots[0][1]])
    with pytest.raises(ValueError, match=r"parameter 'dt_next' = None is invalid; must be "
                       r"given with the 1 new snapshot\(s\) of the plan"):
        store.write_shared(plan, times=[0.0], step=0)
    with pytest.raises(ValueError, match=r"parameter 'snapshot_count' = -1 is invalid"):
        store.begin_commit(-1, 0)
    with pytest.raises(ValueError, match=r"parameter 'plan' = \(1, 1\) is invalid; must be "
                       r"the CommitPlan that begin_commit returned"):
        store.write_block((1, 1), BLOCKS[0])
    stale = CommitPlan(range(0, 2), range(0, 1))     # a plan this store did not make
    with pytest.raises(StoreError, match=r"array 'f' holds 1 entries, the plan ends at 2"):
        store.write_block(stale, BLOCKS[0], f=[snapshots[0][1][:8]] * 2)
    commit_by_blocks(store, snapshots, records, progress, BLOCKS)
    with pytest.raises(StoreError, match=r"RunStore.end_commit: parameter 'plan' = .* is not "
                       r"the open commit: the store holds 1 snapshots and 1 records"):
        store.end_commit(plan, progress)              # ended already
    store.discard()


def test_a_space_homogeneous_store_has_no_blocks(tmp_path):
    from granframe import VelocityGrid

    grid = VelocityGrid(dimension=2, n_modes=8, support_radius=3.0)
    store = RunStore.create(tmp_path / "h.zarr", {}, "", grid, {},
                            layout=homogeneous_layout(grid))
    assert store.cell_arrays == ()
    plan = store.begin_commit(1, 0)
    with pytest.raises(ValueError, match=r"parameter 'cells' = slice\(None, None, None\) is "
                       r"invalid; has no use: the store has no cells axis"):
        store.write_block(plan, slice(None), f=[grid.maxwellian()])
    store.write_shared(plan, times=[0.0], step=0, dt_next=0.1, f=[grid.maxwellian()])
    store.end_commit(plan, {"status": "running", "step": 0, "dt_next": 0.1})
    numpy.testing.assert_array_equal(store.group["f"][0], grid.maxwellian())
    store.discard()


def test_cells_chunk_needs_the_cells_axis_and_a_width_within_it():
    with pytest.raises(ValueError, match=r"RecordArray: parameter 'cells_chunk' = 8 is "
                       r"invalid; is only allowed for a record whose first dimension after "
                       r"step_time is the cells axis 'x'"):
        RecordArray("wall_mass", (2,), ("wall",), cells_chunk=8)
    for width in (0, 25, 2.5):
        with pytest.raises(ValueError, match=r"must be None or a whole number of cells from "
                           r"1 to 24"):
            RecordArray("density", (CELLS,), ("x",), cells_chunk=width)


# -- a commit cut short ---------------------------------------------------------------------
@pytest.mark.parametrize("cut", ["after begin_commit", "after one block", "before end_commit"])
def test_a_commit_cut_before_end_commit_is_never_seen_and_resume_drops_it(reference, tmp_path,
                                                                          cut):
    path, data = tmp_path / "s.zarr", commits()
    write(path, whole, data=data[:2])
    store = RunStore.resume(path, {})
    snapshots, records, progress = data[2]
    plan = store.begin_commit(2, 6)
    owners = {"after begin_commit": [], "after one block": [BLOCKS[2]],
              "before end_commit": BLOCKS[::-1]}[cut]
    for cells in owners:
        store.write_block(plan, cells, f=[f[cells] for _, f in snapshots],
                          records={name: records[name][:, cells] for name in FIELDS})
    if cut == "before end_commit":
        store.write_shared(plan, times=[t for t, _ in snapshots], step=progress["step"],
                           dt_next=progress["dt_next"],
                           records={n: v for n, v in records.items() if n not in FIELDS})
    store.close()                                      # the writer is killed here

    committed = RunStore.open(path)
    assert (committed.snapshot_count, committed.progress["records"]) == (2, 3)
    assert committed.group["f"].shape[0] == 4          # beyond the commit, not in it
    ds = granframe.open_run(path)
    assert (ds.sizes["time"], ds.sizes["step_time"]) == (2, 3)
    expected = contents(reference)
    for name in ("f", "time", "density", "pressure_tensor", "mass", "wall_energy"):
        numpy.testing.assert_array_equal(ds[name].values, expected[name][:ds.sizes[
            "time" if name in ("f", "time") else "step_time"]], err_msg=name)
    assert check(path)[0]

    store = RunStore.resume(path, {})
    assert store.group["f"].shape[0] == 2 and store.group["density"].shape[0] == 3
    assert chunk_files(path, "f") == {f"{k}/{b}/0/0" for k in (0, 1) for b in (0, 1, 2)}
    assert chunk_files(path, "density") == {"0/0", "0/1", "0/2"}
    for commit in data[2:]:
        store.commit(*commit)
    store.close()
    assert files(path) == files(reference)
    assert check(path)[0]


# -- a store written before the fields were chunked by block ----------------------------------
def test_a_store_with_fields_across_all_cells_opens_resumes_and_appends(reference, tmp_path):
    path, data = tmp_path / "old.zarr", commits()
    write(path, whole, cells_chunk=None, data=data[:2])
    old = RunStore.open(path)
    assert old.group["density"].chunks == (4, CELLS)
    assert old.group["pressure_tensor"].chunks == (4, CELLS, 2, 2)
    assert old.cell_arrays == ("f",) + tuple(FIELDS) and check(path)[0]

    store = RunStore.resume(path, {})
    snapshots, records, progress = data[2]
    plan = store.begin_commit(2, 6)
    with pytest.raises(ValueError, match=r"not aligned with the blocks of array 'density', "
                       r"chunked by 24 cells along x \(24 cells\)"):
        store.write_block(plan, BLOCKS[0], f=[f[BLOCKS[0]] for _, f in snapshots])
    store.close()                                       # a commit cut short, then resumed

    store = RunStore.resume(path, {})
    commit_by_blocks(store, *data[2], [slice(0, CELLS)])   # one owner of all cells
    for commit in data[3:]:
        store.commit(*commit)
    store.close()
    assert check(path)[0]
    got, expected = contents(path), contents(reference)
    assert sorted(got) == sorted(expected)
    for name in expected:
        numpy.testing.assert_array_equal(got[name], expected[name], err_msg=name)
    assert RunStore.open(path).group["density"].chunks == (4, CELLS)
    assert granframe.open_run(path).sizes["time"] == 5
