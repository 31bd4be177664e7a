"""What a store path holds, and how a store is put in place or replaced there safely.

:func:`store_kind` tells a run or sweep store (by its metadata), an empty directory or
anything else; :func:`check_replaceable` refuses to replace anything but a granframe
store or an empty directory. A store is built beside its path as
``.NAME.granframe-new-TOKEN`` and an existing one moved aside as
``.NAME.granframe-old-TOKEN`` (:func:`sibling`, roles :data:`STAGING` and :data:`TRASH`);
:func:`recover` finishes or cleans what a writer killed during a swap left.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil

from granframe.run.storage.errors import StoreError, StoreExistsError
from granframe.run.storage.locks import WriterLock
from granframe.run.storage.schema import RECORD_ARRAYS, SNAPSHOT_ARRAYS, SWEEP_SCHEMA_KEY

#: the roles of a store's siblings: one being built (staged), one being replaced (trash)
STAGING, TRASH = "granframe-new", "granframe-old"


def _root_attributes(path: pathlib.Path) -> dict | None:
    """The root attributes of the zarr v3 group at ``path``; None when there is none."""
    try:
        document = json.loads((path / "zarr.json").read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(document, dict) or document.get("node_type") != "group":
        return None
    attributes = document.get("attributes")
    return attributes if isinstance(attributes, dict) else {}


def store_kind(path) -> str:
    """What ``path`` holds: 'missing', 'file', 'empty', 'run', 'sweep' or 'other'.

    'run' and 'sweep' are recognised by granframe's metadata in the root ``zarr.json``.
    """
    path = pathlib.Path(path)
    if not os.path.lexists(path):
        return "missing"
    if not path.is_dir() or path.is_symlink():
        return "file"
    if not any(path.iterdir()):
        return "empty"
    attributes = _root_attributes(path)
    if attributes is None:
        return "other"
    meta = attributes.get("granframe")
    if isinstance(meta, dict) and str(meta.get("schema", "")).startswith("granframe.run/"):
        return "run"
    if isinstance(attributes.get(SWEEP_SCHEMA_KEY), dict):
        return "sweep"
    return "other"


def _foreign_entries(path: pathlib.Path, kind: str) -> list[str]:
    """Entries at the top of a granframe store that granframe did not write."""
    if kind == "run":
        meta = (_root_attributes(path) or {}).get("granframe", {})
        own = set(SNAPSHOT_ARRAYS) | set(meta.get("record_arrays", RECORD_ARRAYS)) | {"zarr.json"}
        own |= set(meta.get("coordinate_arrays", ()))
        own |= {p.name for p in path.iterdir() if p.name[:1] == "v" and p.name[1:].isdigit()}
    else:
        own = {"zarr.json", "runs", "table"}
    return sorted(p.name for p in path.iterdir()
                  if p.name not in own and not p.name.endswith(".partial"))


def _inside(inner: pathlib.Path, outer: pathlib.Path) -> bool:
    return inner == outer or outer in inner.parents


def check_replaceable(path, protect=()) -> None:
    """Refuse, by name, to replace anything but a granframe store or an empty directory.

    ``path`` may be replaced when it is missing, an empty directory, or a granframe run
    or sweep store (recognised by its metadata) holding nothing granframe did not write.
    Refused: a file, any other directory, the current directory, a directory holding the
    current directory, a directory holding any path of ``protect`` (the source of the
    run), and a sweep store with a run still written by a live process.
    """
    path = pathlib.Path(path)
    kind = store_kind(path)
    if kind == "missing":
        return
    where = path.resolve()
    if _inside(pathlib.Path.cwd().resolve(), where):
        raise StoreError(f"--overwrite refused: '{path}' is the current directory or holds "
                         "it; choose a store path such as runs/NAME.zarr")
    for source in protect:
        if _inside(pathlib.Path(source).resolve(), where):
            raise StoreError(f"--overwrite refused: '{path}' holds the source '{source}'; "
                             "choose a store path beside it")
    if kind == "file":
        raise StoreError(f"--overwrite refused: '{path}' is a file, not a granframe store; "
                         "only a granframe run or sweep store, or an empty directory, is "
                         "replaced")
    if kind == "other":
        entries = sorted(p.name for p in path.iterdir())
        shown = ", ".join(entries[:5]) + (", ..." if len(entries) > 5 else "")
        raise StoreError(f"--overwrite refused: '{path}' is not a granframe store (it holds "
                         f"{shown}); only a granframe run or sweep store, or an empty "
                         "directory, is replaced")
    if kind == "sweep" and (path / "runs").is_dir():
        for run in sorted((path / "runs").iterdir()):   # workers may outlive their driver
            WriterLock.check_free(run)
    if kind in ("run", "sweep"):
        foreign = _foreign_entries(path, kind)
        if foreign:
            raise StoreError(f"--overwrite refused: the granframe store '{path}' also holds "
                             f"files granframe did not write ({', '.join(foreign[:5])}); "
                             "move them out first")


def check_creatable(path: pathlib.Path, overwrite: bool, protect) -> None:
    """Refuse to create a store at ``path`` where a granframe store is
    (:class:`StoreExistsError`) or a file or non-empty directory of another kind is
    (:class:`StoreError`), unless ``overwrite``; even then, what
    :func:`check_replaceable` refuses."""
    kind = store_kind(path)
    if kind in ("run", "sweep") and not overwrite:
        raise StoreExistsError(f"store '{path}' exists; pass --resume to continue the run it "
                               "holds, or --overwrite to replace it")
    if kind in ("file", "other") and not overwrite:
        raise StoreError(f"'{path}' exists and is not a granframe store; choose another --out")
    check_replaceable(path, protect)


def sibling(path: pathlib.Path, role: str, token: str) -> pathlib.Path:
    """``.NAME.ROLE-TOKEN`` beside ``path``: a staged (role 'granframe-new') or a replaced
    ('granframe-old') store."""
    return path.parent / f".{path.name}.{role}-{token}"


def siblings(path: pathlib.Path, role: str) -> list[pathlib.Path]:
    """The staged or replaced stores of ``path`` (names compared as text: a store's name
    may hold any character, glob patterns included)."""
    prefix = f".{path.name}.{role}-"
    try:
        entries = os.scandir(path.parent)
    except FileNotFoundError:
        return []
    with entries:
        return sorted(path.parent / e.name for e in entries
                      if e.name.startswith(prefix) and e.name[len(prefix):].isalnum())


def recover(path) -> None:
    """Finish or clean what a writer of ``path`` left when it was killed.

    Call with the store's :class:`WriterLock` held (no other writer is at work), so
    every staging or replaced sibling belongs to a writer that has died:

    - ``path`` missing and a replaced store beside it: the kill fell between the two
      renames of a swap; the new store (complete up to its first commit) is put in
      place, or the old one when the new is not there;
    - a replaced store beside ``path``: deleted (the swap was done);
    - a staging store: a creation cut short, deleted.
    """
    path = pathlib.Path(path)
    for old in siblings(path, TRASH):
        new = sibling(path, STAGING, old.name.rsplit("-", 1)[-1])
        if not os.path.lexists(path):
            os.rename(new if store_kind(new) == "run" and _published(new) else old, path)
        if old.exists():
            shutil.rmtree(old)
    for new in siblings(path, STAGING):
        shutil.rmtree(new)


def _published(path: pathlib.Path) -> bool:
    """True when the staged store at ``path`` holds its first commit (ready to swap in)."""
    meta = (_root_attributes(path) or {}).get("granframe", {})
    return int(meta.get("progress", {}).get("snapshots", 0)) >= 1
