"""The errors of run stores: one base, :class:`StoreError`, and the cases a caller tells apart.

Every module of :mod:`granframe.run.storage` raises these; a store that cannot be used as
asked is a :class:`StoreError` (a :class:`ValueError`), a live second writer a
:class:`StoreLockedError`, an existing store a :class:`StoreExistsError` and missing or
corrupt committed data a :class:`StoreDamagedError` listing the problems.
"""

from __future__ import annotations


class StoreError(ValueError):
    """A store that cannot be used as asked (exists, other description, not a run store)."""


class StoreLockedError(StoreError):
    """The store is being written by another live process (named in the message)."""


class StoreExistsError(StoreError):
    """A granframe store is at the path (a run given ``resume`` continues it instead)."""


class StoreDamagedError(StoreError):
    """Committed data of the store is missing or fails its checksum.

    ``problems`` lists what is wrong, as :meth:`RunStore.verify` gives it.
    """

    def __init__(self, message, problems=()):
        super().__init__(message)
        self.problems = list(problems)
