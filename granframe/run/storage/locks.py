"""One writer per store: the exclusive lock a writer holds on ``.NAME.granframe.lock``.

A writer takes :class:`WriterLock` (``flock``) on the lock file beside the store
(:func:`lock_path`), which names the holder (pid, host, since, command) and is removed
when the writer ends; the kernel drops the lock when the holder dies, however it dies,
and a second writer is refused with the holder's name (:class:`StoreLockedError`).
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import pathlib
import platform
import sys

from granframe.run.storage.errors import StoreError, StoreLockedError
from granframe.run.storage.schema import now


def lock_path(path) -> pathlib.Path:
    """The lock file of the store ``path``: ``.NAME.granframe.lock`` beside it."""
    path = pathlib.Path(path)
    return path.parent / f".{path.name}.granframe.lock"


class WriterLock:
    """An exclusive lock on a store path, held by one writer at a time.

    ``flock`` on the file ``.NAME.granframe.lock`` beside the store, which records the
    holder (pid, host, since, command) for the message a second writer gets. The
    holder removes the file when it releases the lock, so a store leaves nothing beside
    it; the kernel drops the lock when its holder's process ends, however it ends (a
    kill, a crash), so a dead holder never blocks, and its file is taken over. A lock
    taken on a file that its holder removed meanwhile is dropped and taken again on
    the file now at the path (the inode is compared), so two writers never both hold it.
    """

    def __init__(self, path):
        self.path = pathlib.Path(path)
        self.file = lock_path(path)
        self._handle = None

    def acquire(self) -> "WriterLock":
        """Take the lock, or raise :class:`StoreLockedError` naming its live holder."""
        self.file.parent.mkdir(parents=True, exist_ok=True)
        while True:
            handle = open(self.file, "a+")
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                handle.close()
                if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise StoreError(f"cannot lock '{self.file}' for writing: {exc}") from None
                raise StoreLockedError(
                    f"store '{self.path}' is being written by {self.holder()}; a second "
                    "writer is refused (wait for it to end, or stop it)") from None
            try:
                current = os.stat(self.file).st_ino == os.fstat(handle.fileno()).st_ino
            except FileNotFoundError:
                current = False
            if current:
                break
            handle.close()      # its holder removed this file meanwhile: take the new one
        handle.seek(0)
        handle.truncate()
        handle.write(json.dumps({"pid": os.getpid(), "host": platform.node(), "since": now(),
                                 "command": " ".join(sys.argv)[:300]}) + "\n")
        handle.flush()
        self._handle = handle
        return self

    def holder(self) -> str:
        """Who holds (or last held) the lock, in words."""
        try:
            info = json.loads(self.file.read_text())
            return (f"pid {info['pid']} on host {info['host']} since {info['since']} "
                    f"({info.get('command', '')})")
        except (OSError, ValueError, KeyError, TypeError):
            return "another process (its record is being written)"

    @property
    def held(self) -> bool:
        return self._handle is not None

    @classmethod
    def check_free(cls, path) -> None:
        """Raise :class:`StoreLockedError` when a live process holds the lock of ``path``
        (a lock file left by a dead holder is free); takes nothing."""
        lock = cls(path)
        try:
            handle = open(lock.file)
        except FileNotFoundError:
            return
        with handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except OSError:
                raise StoreLockedError(f"store '{lock.path}' is being written by "
                                       f"{lock.holder()}") from None

    def release(self) -> None:
        """Remove the lock file, then drop the lock (in this order: see the class notes)."""
        if self._handle is not None:
            self.file.unlink(missing_ok=True)
            fcntl.flock(self._handle, fcntl.LOCK_UN)
            self._handle.close()
            self._handle = None

    def __enter__(self):
        return self if self.held else self.acquire()

    def __exit__(self, *exc):
        self.release()
