"""What the store's checksums cost: a commit and a read of f with and without CRC-32C.

    python studies/store_overhead.py --out docs/figures/store     # about two minutes

Every chunk of a run store is compressed with zstd and then checksummed with CRC-32C
(granframe.run.storage.codecs). This study times, for f snapshots of 2D N = 64, 3D N = 32
and 3D N = 64 (a Maxwellian), the commit of one snapshot with its moment records
(RunStore.commit) and the read of one snapshot back, with the shipped codecs and with
zstd alone (the store as it was without checksums), median of repeated runs; and the wall
time of a whole run (the quick variant of the README's heated Maxwell problem) both ways.
"""

from __future__ import annotations

import contextlib
import pathlib
import shutil
import statistics
import tempfile
import time

import numpy
import zarr

import granframe.run.storage as storage
import granframe.run.storage.layout as layout
from granframe.velocity.grid import VelocityGrid
from granframe.run.runner import Simulation, load_description
from granframe.tools.studykit import command, finish, write_csv, write_summary

STUDY = pathlib.Path(__file__).with_name("heated_maxwell.py")
GRIDS = [(2, 64), (3, 32), (3, 64)]


@contextlib.contextmanager
def codecs(checksum: bool):
    """Stores created inside use the shipped codecs, or zstd alone (the codecs of every
    array the store layout creates, :func:`granframe.run.storage.layout.codecs`)."""
    shipped = layout.codecs
    if not checksum:
        layout.codecs = lambda: {"compressors": (zarr.codecs.ZstdCodec(level=0),),
                                  "config": {"write_empty_chunks": True}}
    try:
        yield
    finally:
        layout.codecs = shipped


def records(n: int) -> dict:
    """``n`` moment records of plausible values."""
    columns = {name: list(numpy.linspace(1.0, 2.0, n)) for name in storage.SCALAR_MOMENTS}
    columns.update(step_time=list(numpy.arange(n) * 0.01), step=list(range(n)),
                   dt=[0.01] * n, momentum=[[0.0] * 3] * n)
    return columns


def commit_and_read(dimension: int, n_modes: int, checksum: bool, repeats: int) -> dict:
    """Median seconds of a commit of one snapshot (+ 10 records) and of reading it back."""
    grid = VelocityGrid(dimension=dimension, n_modes=n_modes, support_radius=10.0)
    f = grid.maxwellian(temperature=8.0)
    commits, reads = [], []
    with tempfile.TemporaryDirectory() as folder, codecs(checksum):
        store = storage.RunStore.create(pathlib.Path(folder) / "s.zarr", {}, "", grid, {})
        rows = records(10)
        rows["momentum"] = [[0.0] * dimension] * 10
        try:
            for k in range(repeats):
                start = time.perf_counter()
                store.commit([(0.1 * k, f)], rows, {"status": "running", "step": 10 * k,
                                                    "dt_next": 0.01})
                commits.append(time.perf_counter() - start)
                start = time.perf_counter()
                numpy.asarray(store.group["f"][k])
                reads.append(time.perf_counter() - start)
        finally:
            store.discard()
    return {"commit_ms": 1e3 * statistics.median(commits),
            "read_ms": 1e3 * statistics.median(reads),
            "snapshot_mib": f.nbytes / 2 ** 20}


def whole_run(checksum: bool, repeats: int) -> float:
    """Median wall seconds of the heated Maxwell problem's quick variant into a new store."""
    description = load_description(STUDY, quick=True)
    simulation = Simulation(description)
    times = []
    for _ in range(repeats):
        folder = tempfile.mkdtemp()
        with codecs(checksum):
            start = time.perf_counter()
            simulation.run(pathlib.Path(folder) / "run.zarr", progress=False)
            times.append(time.perf_counter() - start)
        shutil.rmtree(folder)
    return statistics.median(times)


def run(out: pathlib.Path, quick: bool = False) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    repeats = 5 if quick else 21
    rows = []
    for dimension, n_modes in GRIDS[:1] if quick else GRIDS:
        both = {c: commit_and_read(dimension, n_modes, c, repeats) for c in (False, True)}
        rows.append({"grid": f"{dimension}D N={n_modes}",
                     "snapshot_mib": round(both[True]["snapshot_mib"], 3),
                     "commit_ms_zstd": round(both[False]["commit_ms"], 2),
                     "commit_ms_zstd_crc32c": round(both[True]["commit_ms"], 2),
                     "read_ms_zstd": round(both[False]["read_ms"], 2),
                     "read_ms_zstd_crc32c": round(both[True]["read_ms"], 2)})
    write_csv(out / "store_overhead.csv", rows)
    runs = 1 if quick else 5
    # alternate the two variants so that a slow spell of the machine hits both
    wall = {False: [], True: []}
    for _ in range(runs):
        for checksum in (False, True):
            wall[checksum].append(whole_run(checksum, 1))
    summary = {"repeats": repeats, "grids": rows,
               "heated_maxwell_quick_run_s": {
                   "zstd": statistics.median(wall[False]),
                   "zstd_crc32c": statistics.median(wall[True]), "runs": runs}}
    write_summary(out, summary)
    return summary


def show(summary: dict) -> None:
    print("| grid | snapshot | commit, zstd | commit, zstd + crc32c | read, zstd | "
          "read, zstd + crc32c |")
    print("|---|---|---|---|---|---|")
    for r in summary["grids"]:
        print(f"| {r['grid']} | {r['snapshot_mib']:.2f} MiB | {r['commit_ms_zstd']:.2f} ms | "
              f"{r['commit_ms_zstd_crc32c']:.2f} ms | {r['read_ms_zstd']:.2f} ms | "
              f"{r['read_ms_zstd_crc32c']:.2f} ms |")
    w = summary["heated_maxwell_quick_run_s"]
    print(f"heated Maxwell (quick) whole run, median of {w['runs']}: {w['zstd']:.2f} s "
          f"without, {w['zstd_crc32c']:.2f} s with checksums")


main = command(run, __doc__, "one grid, 5 repeats, one whole run", show=show)

if __name__ == "__main__":
    raise SystemExit(finish(main))
