"""A small bounded, thread-safe memo: what jaxnet keeps per process between solves (per sparsity structure,
per scene shape, per thread).

Why one class. Solves run in several threads at once (the host callbacks of a program sharded over several
devices run in XLA's threads; a user may solve in a thread pool), so every such table is read and written
under a lock; and it is bounded, so that a long study over many scene shapes does not grow the process
without end. When full, the oldest entry goes (first in, first out: the tables hold few entries, each
costly to make and cheap to make again, and the newest is the one a Newton loop asks for next).
"""

from __future__ import annotations

import threading
from typing import Callable, Hashable


class Memo:
    """A mapping of at most ``maxsize`` entries (None: unbounded) under a lock.

    ``get(key)`` returns the value or None; ``put(key, value)`` stores it (the oldest entry dropped when
    full); ``get_or_make(key, make)`` returns the value, else ``make()`` stored under ``key``. ``make``
    runs outside the lock (tracing a program may take tens of milliseconds, and other threads go on): two
    threads asking for the same new key at once may both make it, and the first one stored is kept.
    """

    def __init__(self, maxsize: int | None = 64):
        self.maxsize = maxsize
        self._items: dict = {}
        self._lock = threading.Lock()

    def get(self, key: Hashable):
        with self._lock:
            return self._items.get(key)

    def put(self, key: Hashable, value):
        with self._lock:
            self._put(key, value)
        return value

    def _put(self, key, value):
        if key not in self._items and self.maxsize is not None and len(self._items) >= self.maxsize:
            self._items.pop(next(iter(self._items)))
        self._items[key] = value

    def get_or_make(self, key: Hashable, make: Callable[[], object]):
        value = self.get(key)
        if value is None:
            value = make()
            with self._lock:
                known = self._items.get(key)
                if known is not None:
                    return known
                self._put(key, value)
        return value

    def values(self):
        """A list of the values now held (a copy)."""
        with self._lock:
            return list(self._items.values())

    def clear(self):
        with self._lock:
            self._items.clear()

    def __len__(self):
        with self._lock:
            return len(self._items)
