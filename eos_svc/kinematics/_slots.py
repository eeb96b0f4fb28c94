"""Hot-path construction of frozen, slotted dataclasses without their ``__init__``."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def slot_setters(cls: type, *fields: str) -> tuple[Callable[[Any, Any], None], ...]:
    """The slot setters of ``fields`` of ``cls`` (a ``@dataclass(frozen=True, slots=True)``).

    ``obj = object.__new__(cls)`` followed by one setter call per field builds an instance
    ≈ 2 µs cheaper than the frozen dataclass ``__init__``; the instance stays frozen for its
    users. Raises KeyError for a name that is not a slot of ``cls``.
    """
    return tuple(cls.__dict__[f].__set__ for f in fields)
