"""What ``granframe check`` and ``granframe info`` print of a store.

:func:`check` reads every committed chunk of a run store, or of every run of a sweep
store, and reports the damage, the files of writes cut short and the entries no run
writes (:func:`stray_entries`); :func:`describe` summarises a run store: its progress,
snapshots and moments, a space run's cells and walls, a rollback's dropped records
(:func:`dropped_note`), the resolution at the last commit, the provenance and the
description.
"""

from __future__ import annotations

import os
import pathlib

import numpy
import zarr

from granframe.run.storage.errors import StoreDamagedError
from granframe.run.storage.integrity import chunk_grid, summarise
from granframe.run.storage.paths import store_kind
from granframe.run.storage.store import RunStore


# -- granframe check ------------------------------------------------------------------------
def check(path) -> tuple[bool, list[str]]:
    """Read every committed chunk of a run store, or of every run of a sweep store.

    Returns (intact, report lines); ``granframe check`` prints the lines and exits 3
    when the store is damaged.
    """
    path = pathlib.Path(path)
    if store_kind(path) == "sweep":
        return _check_sweep(path)
    try:
        store = RunStore.open(path)
    except StoreDamagedError:
        store = RunStore(path, zarr.open_group(str(path), mode="r", use_consolidated=False))
    problems = store.verify()
    progress = store.progress
    chunks = sum(sum(1 for _ in chunk_grid(store.group[n], store.extent(n)))
                 for n in store.array_names())
    lines = [f"{path}: status {progress.get('status')}, {store.snapshot_count} snapshots, "
             f"{progress.get('records')} records; {chunks} committed chunks read, "
             f"{len(problems)} problems"]
    block = (store.metadata.get("space") or {}).get("block_cells")
    lines += [_problem_line(p, block) for p in problems]
    return not problems, lines + _leftover_lines(path)


def _check_sweep(path: pathlib.Path) -> tuple[bool, list[str]]:
    """:func:`check` of the sweep store ``path``: its table and every run store."""
    runs = sorted(p for p in (path / "runs").iterdir() if not p.name.startswith(".")) \
        if (path / "runs").is_dir() else []
    lines, intact = [f"sweep store {path}: {len(runs)} run stores"], True
    for run in [r for r in runs if store_kind(r) != "run"]:
        intact = False
        lines.append(f"  damaged: runs/{run.name} is not a readable run store")
    runs = [r for r in runs if store_kind(r) == "run"]
    damaged = _damaged_table(path)
    intact &= not damaged
    lines += damaged
    for run in runs:
        ok, more = check(run)
        intact &= ok
        lines += ["  " + line for line in more]
    return intact, lines


def _damaged_table(path: pathlib.Path) -> list[str]:
    """A line for each array of the table of the sweep store ``path`` that cannot be read."""
    if not (path / "table" / "zarr.json").is_file():
        return []
    table = zarr.open_group(str(path / "table"), mode="r", use_consolidated=False)
    lines = []
    for name in sorted(table.array_keys()):
        try:
            table[name][:]
        except Exception as exc:   # any decoding failure is damage
            lines.append(f"  damaged: table/{name}: {exc}")
    return lines


def _problem_line(problem: dict, block: int | None) -> str:
    """A problem of :meth:`RunStore.verify` as a line of :func:`check`; ``block``: the cells
    per chunk of a space run's f (None for a space-homogeneous run)."""
    where = ""
    if problem["chunk"]:
        cells = _cells(problem["chunk"][1], block) if block and problem["array"] == "f" else ""
        where = (f"/c/{'/'.join(map(str, problem['chunk']))} (from entry {problem['first']}"
                 f"{cells})")
    detail = f": {problem['detail']}" if problem["detail"] else ""
    return f"  {problem['kind']}: {problem['array']}{where}{detail}"


def _cells(index: int, block: int) -> str:
    """The cells of block ``index`` of a space run's f (chunked by block), in words."""
    return f", block {index}: cells {index * block}..{(index + 1) * block - 1}"


def _leftover_lines(path: pathlib.Path) -> list[str]:
    """The lines of :func:`check` on the files of writes cut short and the entries that no
    run writes in the run store ``path``."""
    lines = []
    partial = sorted(str(p.relative_to(path)) for p in path.rglob("*.partial"))
    if partial:
        lines.append(f"  {len(partial)} file(s) of a write cut short (removed on --resume): "
                     + ", ".join(partial[:3]))
    stray = stray_entries(path)
    if stray:
        lines.append(f"  {len(stray)} entr{'y' if len(stray) == 1 else 'ies'} that no run "
                     f"writes (ignored; left by a write cut short, or added by hand): "
                     + ", ".join(stray[:3]))
    return lines


def stray_entries(path) -> list[str]:
    """The directories at the top of the run store ``path`` that are not zarr arrays or
    groups (no ``zarr.json``), which every read ignores."""
    path = pathlib.Path(path)
    return sorted(p.name for p in path.iterdir()
                  if p.is_dir() and not (p / "zarr.json").is_file())


# -- granframe info -------------------------------------------------------------------------
def dropped_note(metadata: dict) -> str | None:
    """The moment records a rollback dropped (the metadata's ``dropped_records``), in
    words; None when it dropped none."""
    dropped = metadata.get("dropped_records")
    if not dropped:
        return None
    return "dropped the moment records of damaged chunks: " + "; ".join(
        f"{d['array']} {d['first']} .. {d['first'] + d['count'] - 1} ("
        + ("written again: record i is step i" if d["array"] == "step" else "now NaN") + ")"
        for d in dropped)


def _named(component: dict) -> str:
    """A reconstruction or boundary of a description's ``space`` section as
    ``name(key=value, ...)``."""
    params = ", ".join(f"{key}={value}" for key, value in component.items() if key != "name")
    return component["name"] + (f"({params})" if params else "")


def _describe_space(meta: dict, group, n: int) -> list[str]:
    """The lines of :func:`describe` for the first ``n`` records of a space run's store:
    the interval, its blocks and walls; the range over the cells of T(x) and rho(x) at the
    first and the last record; the totals; what entered through each wall, and the
    balance m(t) - m(0) - (mass entered) of the records."""
    space, section = meta["space"], meta["description"]["space"]
    cells, length, block = space["cells"], space["length"], space["block_cells"]
    walls = ", ".join(f"{side} {_named(section.get(side, {'name': 'periodic'}))}"
                      for side in ("left", "right", "bottom", "top")[:2 * len(
                          cells if isinstance(cells, list) else [cells])])
    if isinstance(cells, list):         # a rectangle
        head = (f"space       {cells[0]} x {cells[1]} cells on [0, {length[0]:g}] x "
                f"[0, {length[1]:g}] (dx = {length[0] / cells[0]:.6g}, dy = "
                f"{length[1] / cells[1]:.6g}), chunks of {block[0]} x {block[1]} cells")
    else:
        head = (f"space       {cells} cells on [0, {length:g}] (dx = {length / cells:.6g}), "
                f"{cells // block} blocks of {block} cells")
    reconstruction = _named(section.get("reconstruction", {"name": "muscl"}))
    lines = [f"{head}, reconstruction {reconstruction}, walls: {walls}"]
    for name, label in (("temperature", "T(x)"), ("density", "rho(x)")):
        first, last = group[name][0], group[name][n - 1]
        lines.append(f"  {label:<12s}in [{numpy.nanmin(first):.6g}, {numpy.nanmax(first):.6g}] "
                     f"-> [{numpy.nanmin(last):.6g}, {numpy.nanmax(last):.6g}] (over the cells)")
    entered = {name: group[name][:n].sum(axis=0) for name in ("wall_mass", "wall_energy")}
    for name, wall, label in (("mass", "wall_mass", "mass"),
                              ("kinetic_energy", "wall_energy", "energy")):
        first, last = group[name][[0, n - 1]]
        inflow = entered[wall].sum()
        lines.append(f"  {label:<12s}{first:.10g} -> {last:.10g} (drift "
                     f"{last / first - 1:+.2e}; entered through the walls {inflow:+.3e}, "
                     f"balance {last - first - inflow:+.2e})")
    values = group["min_f"][[0, n - 1]]
    lines.append(f"  {'min_f':<12s}{values[0]:.10g} -> {values[1]:.10g}")
    names = ("left", "right", "bottom", "top")
    for wall, what in (("wall_mass", "mass"), ("wall_energy", "energy")):
        lines.append(f"  {what} entered through the " + ", the ".join(
            f"{side} wall {value:+.6e}" for side, value in zip(names, entered[wall]))
            + " (sums over the steps)")
    return lines


def describe(path) -> str:
    """Human-readable summary of a store (``granframe info``)."""
    store = RunStore.open(path)
    problems = store.verify([n for n in store.array_names() if n != "f"])
    if problems:
        raise StoreDamagedError(f"store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
    meta, progress = store.metadata, store.progress
    lines = _contents_lines(store)
    note = dropped_note(meta)
    if note:
        lines.append(f"rollback    {note}")
    lines += _resolution_lines(progress)
    if progress.get("accuracy"):
        from granframe.run.monitors import describe as describe_accuracy

        lines.extend(describe_accuracy(progress["accuracy"], progress["time"]))
    return "\n".join(lines + _origin_lines(meta))


def _contents_lines(store: RunStore) -> list[str]:
    """The lines of :func:`describe` on where the store is, what wrote it, its status,
    its snapshots and its moment records (the first and the last)."""
    meta, progress, group = store.metadata, store.progress, store.group
    lines = [f"store       {os.fspath(store.path)}",
             f"granframe   {meta['version']} (schema {meta['schema']}), created {meta['created']}",
             f"status      {progress.get('status')}"
             + (f": {progress['message']}" if progress.get("message") else "")]
    if progress.get("snapshots"):
        times = group["time"][:int(progress["snapshots"])]
        lines.append(f"snapshots   {len(times)} of f {tuple(group['f'].shape[1:])}, "
                     f"t = {times[0]:g} .. {times[-1]:g}")
    if progress.get("records"):
        n = int(progress["records"])
        lines.append(f"moments     {n} records (every step), t = "
                     f"{float(group['step_time'][0]):g} .. {float(group['step_time'][n - 1]):g}, "
                     f"{int(group['step'][n - 1])} steps")
        if "space" in meta:
            lines.extend(_describe_space(meta, group, n))
        else:
            for name in ("mass", "temperature", "kurtosis", "min_f"):
                values = group[name][[0, n - 1]]
                lines.append(f"  {name:<12s}{values[0]:.10g} -> {values[1]:.10g}")
    return lines


def _resolution_lines(progress: dict) -> list[str]:
    """The lines of :func:`describe` on the resolution at the last commit (none when the
    run recorded none)."""
    resolution = progress.get("resolution")
    if not resolution:
        return []
    lines = [f"resolution  at t = {progress['time']:g} (the last commit): spectral tail "
             f"{resolution['spectral_tail']:.3g} (estimated error "
             f"{resolution['tail_error']:.3g}), negative mass share "
             f"{resolution['negative_mass_fraction']:.3g}, share of pairs beyond 2S "
             f"{resolution['pairs_beyond_support']:.3g}"]
    if "cells" in resolution:           # a space run: the worst cell of each indicator
        def at(name):
            if "position" in resolution:
                x, y = resolution["position"][name]
                return f"(x, y) = ({x:.4g}, {y:.4g})"
            return f"x = {resolution['x'][name]:.4g}"

        lines.append("  worst cells " + ", ".join(
            f"{name} {resolution[name]:.3g} in cell {cell} ({at(name)})"
            for name, cell in resolution["cells"].items()))
    lines.extend(f"  warning: {warning}" for warning in resolution["warnings"])
    return lines


def _origin_lines(meta: dict) -> list[str]:
    """The lines of :func:`describe` on where the run came from: the projection of f0, the
    provenance and the description."""
    lines = []
    if meta.get("f0_projection"):
        lines.append("f0 projection (moments before -> after; the run starts after)")
        for name, m in meta["f0_projection"].items():
            lines.append(f"  {name:<12s}{m['before']:.10g} -> {m['after']:.10g}")
    provenance = meta.get("provenance", {})
    if provenance:
        lines.append("provenance")
        width = max(len(key) for key in provenance) + 2
        for key, value in provenance.items():
            lines.append(f"  {key:<{width}s}{value}")
    lines.append("description (TOML)")
    lines.extend("  " + line for line in meta["description_toml"].strip().splitlines())
    return lines
