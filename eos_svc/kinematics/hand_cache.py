"""Values derived once from a hand (and whatever else they depend on), shared read-only by
every plan in every thread: a hand's geometry bound table, its probe poses, what a world
derives from it, its span and reach.

Entries are keyed by the owners' ids and keep the owners themselves, so an id that Python
recycles for a new object never returns another object's values. Building runs under a
lock: at most one build per key, and builds that write into the hand's shared objects (coal's
``computeLocalAABB``) never run in two threads at once. A few entries are kept, the oldest
dropped first.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import Any, Generic, TypeVar

V = TypeVar("V")


class PerHandCache(Generic[V]):
    """A bounded, thread-safe cache of values built from owner objects (a hand, its sweeps, …)."""

    def __init__(self, keep: int) -> None:
        if keep < 1:
            raise ValueError(f"keep must be ≥ 1, got {keep}")
        self._keep = keep
        self._entries: dict[tuple[Hashable, ...], tuple[tuple[object, ...], V]] = {}
        self._lock = threading.Lock()

    def get(self, owners: tuple[object, ...], build: Callable[[], V], *key: Hashable) -> V:
        """The value for ``owners`` (compared by identity) and ``key``, built by ``build()`` the
        first time (under the cache's lock) and the same object afterwards."""
        k = (*(id(o) for o in owners), *key)
        entry = self._entries.get(k)
        if entry is not None and _same(entry[0], owners):
            return entry[1]
        with self._lock:
            entry = self._entries.get(k)
            if entry is None or not _same(entry[0], owners):
                entry = self._entries[k] = (owners, build())
                while len(self._entries) > self._keep:
                    self._entries.pop(next(iter(self._entries)))
        return entry[1]

    def __len__(self) -> int:
        return len(self._entries)


def _same(kept: tuple[Any, ...], owners: tuple[Any, ...]) -> bool:
    return len(kept) == len(owners) and all(a is b for a, b in zip(kept, owners, strict=True))
