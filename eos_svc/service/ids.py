"""Goal ids, namespaces and cancel tokens on the wire: their forms, and fast checks of them.

The forms are the two patterns. :func:`is_id` and :func:`is_token` answer exactly as their
``fullmatch`` does (the tests compare them on generated strings) with a few string methods
instead of the regular-expression engine: they run on every plan request's path, where the
engine's first call after the process idled costs ≈ 25 µs more (its code is out of the caches).
"""

from __future__ import annotations

import re

#: goal ids and namespaces: one plain key-expression chunk (no wildcards, no ``@``, no ``/``)
ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}")
#: a cancel token: the goal owner's secret (16-128 URL-safe characters), sent with the request and
#: with a cancel, never published
TOKEN_PATTERN = re.compile(r"[A-Za-z0-9_\-]{16,128}")


def is_id(value: str) -> bool:
    """``ID_PATTERN.fullmatch(value)`` as a bool: 1-64 ASCII letters, digits, ``_ . -``,
    the first a letter or digit (``str.isalnum`` on ASCII is exactly ``[A-Za-z0-9]``)."""
    return (
        0 < len(value) <= 64
        and value.isascii()
        and value[0].isalnum()
        and value.replace("-", "").replace("_", "").replace(".", "").isalnum()
    )


def is_token(value: str) -> bool:
    """``TOKEN_PATTERN.fullmatch(value)`` as a bool: 16-128 ASCII letters, digits, ``_ -``."""
    if not (16 <= len(value) <= 128 and value.isascii()):
        return False
    rest = value.replace("-", "").replace("_", "")
    return not rest or rest.isalnum()
