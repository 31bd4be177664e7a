"""One commit to a run store: a snapshot of f with ten moment records, as a run commits at
an output point (compressed, checksummed chunks; metadata rewritten), to a store in
memory and to one on disk in a temporary directory.
"""

from __future__ import annotations

import atexit
import tempfile

from benchmarks._support import cached, require

#: velocity grids 'D:N' of the snapshot; the first is the smallest.
GRIDS = ["2:64", "3:32"]
PLACES = ["memory", "disk"]
#: the parameters the test suite (tests/test_benchmarks.py) runs each benchmark with
QUICK = {"grid": GRIDS[0]}
#: moment records per commit
RECORDS = 10


def records(grid, count: int) -> dict:
    """``count`` records of every array the space-homogeneous layout keeps after a step,
    with plausible values (step, time, dt, moments)."""
    import numpy

    storage = require("granframe.run.storage", "the run store")
    rows = {}
    for spec in storage.homogeneous_layout(grid).records:
        shape = (count,) + tuple(spec.shape)
        if spec.name == "step":
            rows[spec.name] = numpy.arange(count, dtype="i8")
        elif spec.name == "step_time":
            rows[spec.name] = 0.01 * numpy.arange(count)
        else:
            rows[spec.name] = numpy.ones(shape, dtype=spec.dtype)
    return rows


def build_store(grid_text: str, place: str):
    """(store, f, rows, counter) built once per process: a new store for a
    space-homogeneous run on the grid (on disk: in a temporary directory removed at exit),
    committed to once."""

    def build():
        import granframe as gf

        RunStore = require("granframe.run.storage", "the run store").RunStore

        dimension, n_modes = (int(p) for p in grid_text.split(":"))
        grid = gf.VelocityGrid(dimension, n_modes, 10.0)
        f = grid.maxwellian(temperature=8.0)
        if place == "memory":
            path = None
        else:
            folder = tempfile.TemporaryDirectory(prefix="granframe-asv-")
            atexit.register(folder.cleanup)
            path = f"{folder.name}/run.zarr"
        store = RunStore.create(path, {}, "", grid, {})
        rows = records(grid, RECORDS)
        counter = [0]
        commit(store, f, rows, counter)
        return store, f, rows, counter

    return cached(("store", grid_text, place), build)


def commit(store, f, rows, counter) -> None:
    """One commit of f at the next output point with ``rows``."""
    k = counter[0]
    counter[0] += 1
    store.commit([(0.1 * k, f)], rows, {"status": "running", "step": RECORDS * k,
                                        "dt_next": 0.01})


class StoreCommit:
    """Seconds per commit of one f snapshot and ten moment records."""

    params = [GRIDS, PLACES]
    param_names = ["grid", "store"]
    timeout = 120

    def setup(self, grid, store):
        self.store, self.f, self.rows, self.counter = build_store(grid, store)

    def time_commit(self, grid, store):
        commit(self.store, self.f, self.rows, self.counter)
