"""The information board (paper Fig. 1, "IF"): named entries agents read and write, each write
attributed to the acting agent; the entries each cycle changed go to its record and, as
*events*, to the next cycle's precondition tests.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from eos_svc.errors import ContractError

_MISSING: Any = object()


@dataclass(frozen=True, slots=True)
class BoardChange:
    """One entry written during a cycle: its ``old`` value (``None`` when ``created``) and its
    ``new`` one (``None`` when ``removed``)."""

    key: str
    old: Any
    new: Any
    created: bool = False
    removed: bool = False


class Board(Mapping[str, Any]):
    """A mapping of named entries with a per-cycle change log.

    Reads are plain mapping access (``board["shape"]``, ``board.get("shape")``).
    Writes go through :meth:`set` / :meth:`delete` so they are recorded. Outside
    a cycle (set-up by the caller) writes are not recorded as changes.
    """

    __slots__ = ("_changes", "_entries", "_first_old")

    def __init__(self, entries: Mapping[str, Any] | None = None) -> None:
        self._entries: dict[str, Any] = dict(entries or {})
        self._changes: dict[str, BoardChange] | None = None
        self._first_old: dict[str, Any] = {}

    # --- Mapping -------------------------------------------------------------
    def __getitem__(self, key: str) -> Any:
        return self._entries[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def get(self, key: str, default: Any = None) -> Any:
        """The entry ``key``, or ``default`` when it does not exist."""
        return self._entries.get(key, default)

    # --- writes --------------------------------------------------------------
    def set(self, key: str, value: Any) -> None:
        """Write entry ``key``; recorded as a change when inside a cycle."""
        if not isinstance(key, str) or not key:
            raise ContractError("key", f"a board key must be a non-empty str, got {key!r}")
        old = self._entries.get(key, _MISSING)
        self._entries[key] = value
        if self._changes is not None:
            self._record(key, old, value)

    def update(self, values: Mapping[str, Any]) -> None:
        """Write several entries at once."""
        for key, value in values.items():
            self.set(key, value)

    def delete(self, key: str) -> None:
        """Remove entry ``key`` (no error if it is absent)."""
        old = self._entries.pop(key, _MISSING)
        if old is not _MISSING and self._changes is not None:
            self._record(key, old, _MISSING)

    def snapshot(self) -> dict[str, Any]:
        """A shallow copy of every entry."""
        return dict(self._entries)

    # --- cycle bookkeeping (called by the controller) --------------------------
    def begin_cycle(self) -> None:
        """Start recording changes."""
        self._changes = {}
        self._first_old = {}

    def end_cycle(self) -> tuple[BoardChange, ...]:
        """Stop recording; return what changed since :meth:`begin_cycle`."""
        changes = self._changes or {}
        self._changes = None
        return tuple(changes.values())

    def _record(self, key: str, old: Any, new: Any) -> None:
        changes = self._changes
        assert changes is not None
        first_old = self._first_old.setdefault(key, old)
        created = first_old is _MISSING
        removed = new is _MISSING
        if not created and not removed and _same(first_old, new):
            changes.pop(key, None)  # written back to what it was
            return
        changes[key] = BoardChange(
            key=key,
            old=None if created else first_old,
            new=None if removed else new,
            created=created,
            removed=removed,
        )


def _same(a: Any, b: Any) -> bool:
    """Equality that tolerates array-like values (whose == is element-wise)."""
    if a is b:
        return True
    try:
        result = a == b
        return bool(result) if isinstance(result, bool) else bool(getattr(result, "all", lambda: False)())
    except Exception:  # incomparable values count as different
        return False
