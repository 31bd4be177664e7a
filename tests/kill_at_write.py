"""Run ``granframe`` killed (SIGKILL) just before its K-th write to the file system.

Usage: ``python kill_at_write.py K LOG granframe-arguments...``. A write is any call of
``os.mkdir``, ``os.rename``, ``os.replace``, ``os.link``, ``os.unlink``, ``os.rmdir``
(what zarr, ``shutil.rmtree`` and granframe's own renames go through) or of zarr's
``LocalStore.set`` (a chunk or metadata document about to be written). Each write is
logged to LOG as ``index operation path``; K = 0 counts every write and kills nothing.
"""

import os
import signal
import sys
import threading

import zarr.storage

OPERATIONS = ("mkdir", "rename", "replace", "link", "unlink", "rmdir")


def install(kill_at: int, log) -> None:
    count, guard = [0], threading.Lock()

    def before(operation, path):
        with guard:
            count[0] += 1
            if count[0] == kill_at:
                os.kill(os.getpid(), signal.SIGKILL)
            log.write(f"{count[0]} {operation} {path}\n")

    def wrap(operation, function):
        def counted(*args, **kwargs):
            before(operation, args[0] if args else "")
            return function(*args, **kwargs)
        return counted

    for operation in OPERATIONS:
        setattr(os, operation, wrap(operation, getattr(os, operation)))
    store_set = zarr.storage.LocalStore.set

    async def counted_set(self, key, value):
        before("set", f"{self.root}/{key}")
        return await store_set(self, key, value)

    zarr.storage.LocalStore.set = counted_set


if __name__ == "__main__":
    kill_at, log_path, arguments = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
    install(kill_at, open(log_path, "w", buffering=1))
    from granframe.tools.cli import main

    sys.exit(main(arguments))
