"""What can be trusted in a store: every committed chunk is on disk and passes its checksum.

Every chunk ends in a CRC-32C, so a damaged chunk raises when it is decoded, and every
chunk is written, so a missing chunk file is damage. :func:`chunk_problems` lists the
missing and damaged chunks of one array up to its committed extent and
:func:`absent_arrays` the arrays missing whole, each problem a dict (:func:`problem`);
:meth:`~granframe.run.storage.RunStore.verify` gathers them for a store and
:func:`summarise` puts the first few in words.
"""

from __future__ import annotations

import itertools
import math
import pathlib


def chunk_grid(array, extent: int):
    """Chunk indices of ``array`` covering its first ``extent`` entries along axis 0."""
    counts = [math.ceil(extent / array.chunks[0])] + [
        math.ceil(s / c) for s, c in zip(array.shape[1:], array.chunks[1:])]
    return itertools.product(*(range(n) for n in counts))


def chunk_file(root: pathlib.Path, name: str, index) -> pathlib.Path:
    """The file of the chunk ``index`` of the array ``name`` of the store at ``root``."""
    return root / name / "c" / pathlib.Path(*map(str, index))


def problem(name, array, index, kind, detail="") -> dict:
    """A problem with the chunk ``index`` of the array ``name``: array, chunk, first (its
    first entry along the first axis), kind ('missing' or 'damaged') and detail."""
    return {"array": name, "chunk": list(index), "first": index[0] * array.chunks[0],
            "kind": kind, "detail": detail}


def absent_arrays(expected, present) -> list[dict]:
    """The problems (kind 'missing array') of the arrays of ``expected`` not in ``present``."""
    return [{"array": name, "chunk": [], "first": 0, "kind": "missing array", "detail": ""}
            for name in sorted(set(expected) - set(present))]


def chunk_problems(name: str, array, root: pathlib.Path, extent: int, read: bool = True,
                   entries=None) -> list[dict]:
    """The missing and damaged chunks of the array ``name`` of the store at ``root``.

    Parameters
    ----------
    name : str
        The array's name.
    array : zarr.Array
        The array.
    root : pathlib.Path
        The store's path, where its chunk files are.
    extent : int
        Its committed entries along the first axis: the chunks holding them are checked.
    read : bool
        Decode every chunk (its checksum included); False only checks that the chunk files
        are on disk.
    entries : collection of int, optional
        Only the chunks whose first index is among these (the snapshots of f).
    """
    problems = []
    for index in chunk_grid(array, extent):
        if entries is not None and index[0] not in entries:
            continue
        if not chunk_file(root, name, index).is_file():
            problems.append(problem(name, array, index, "missing"))
            continue
        if not read:
            continue
        try:
            array.get_block_selection(index)
        except Exception as exc:   # any decoding failure is damage
            problems.append(problem(name, array, index, "damaged", str(exc)))
    return problems


def summarise(problems) -> str:
    """The first few problems of :meth:`~granframe.run.storage.RunStore.verify`, in words."""
    shown = [f"{p['kind']} chunk {p['array']}/c/{'/'.join(map(str, p['chunk']))}"
             if p["chunk"] else f"{p['kind']} {p['array']}" for p in problems[:3]]
    return ", ".join(shown) + (f" and {len(problems) - 3} more" if len(problems) > 3 else "")
