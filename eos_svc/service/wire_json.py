"""Strict JSON of the service's wire (UTF-8, RFC 8259; pure, no Zenoh import): what anyone may
send is read by :func:`loads_strict` (no NaN, duplicate keys or integers beyond ±2**64), what the
service sends by :func:`loads_message`; written by :func:`dumps` or :func:`encode_result` (msgspec).
"""

from __future__ import annotations

import json
import re
from typing import Any

import msgspec

from eos_svc.errors import ContractError, ValidationError
from eos_svc.records import to_jsonable

#: largest |integer| on the wire (no field needs more; bigger ones do not fit a float)
MAX_WIRE_INT = 2**64
#: 20 digits in a row: the only way to write an integer with |x| > 2**64 (= 18446744073709551616)
_LONG_DIGITS = re.compile(rb"[0-9]{20}")
_BOM = b"\xef\xbb\xbf"


class DuplicateKeyError(ValidationError):
    """An object of the message has the same key twice (RFC 8259: names SHOULD be unique)."""

    def __init__(self, field: str, reason: str = "duplicate key in an object") -> None:
        super().__init__(field, reason)
        self.key = field  #: the repeated key


class HugeIntegerError(ValidationError):
    """An integer beyond ±2**64 (``field``: where it is, dotted)."""


class _HugeInt:
    """An integer literal too long to be any field's value (kept as text, named later)."""

    __slots__ = ("digits",)

    def __init__(self, digits: str) -> None:
        self.digits = digits


def _parse_int(literal: str) -> Any:
    """``int`` for literals up to 21 characters (all ≤ 2**64 need); longer ones (never converted:
    Python refuses > 4,300 digits, and big ones cost quadratic time) a :class:`_HugeInt`."""
    return int(literal) if len(literal) <= 21 else _HugeInt(literal)


def _reject_constant(name: str) -> Any:
    raise ValidationError("payload", f"{name} is not valid JSON")


def _unique_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object, refusing a key given twice."""
    obj = dict(pairs)
    if len(obj) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise DuplicateKeyError(key)
            seen.add(key)
    return obj


def _text(data: bytes | bytearray | str) -> str:
    """JSON text from UTF-8 bytes (strict: invalid bytes, encoded surrogates, UTF-16/32 refused;
    a leading UTF-8 byte-order mark ignored, as RFC 8259 §8.1 allows)."""
    if isinstance(data, str):
        return data[1:] if data.startswith("\ufeff") else data
    if not isinstance(data, (bytes, bytearray)):
        raise ContractError(
            "payload", f"the JSON object must be str, bytes or bytearray, not {type(data).__name__}"
        )
    if data.startswith(_BOM):
        data = data[3:]
    elif b"\x00" in data[:4] or data[:2] in (b"\xff\xfe", b"\xfe\xff"):  # what json.detect_encoding reads
        raise ValidationError("payload", "not UTF-8: UTF-16 or UTF-32 text (the wire is UTF-8)")
    return data.decode("utf-8")  # strict: a UnicodeDecodeError (a ValueError) names the byte


def check_integers(value: Any, raw: bytes | bytearray | str) -> None:
    """Raise :class:`HugeIntegerError` for an integer too large for any field in ``value`` (parsed
    from ``raw`` by :func:`parse`), naming where it is."""
    if not _LONG_DIGITS.search(raw.encode() if isinstance(raw, str) else raw):
        return  # an integer beyond 2**64 has ≥ 20 digits: only then look for it
    stack: list[tuple[Any, str]] = [(value, "")]
    while stack:
        v, where = stack.pop()
        if isinstance(v, dict):
            stack.extend((item, f"{where}.{k}" if where else str(k)) for k, item in v.items())
        elif isinstance(v, list):
            stack.extend((item, f"{where}[{i}]") for i, item in enumerate(v))
        elif isinstance(v, _HugeInt) or (
            isinstance(v, int) and not isinstance(v, bool) and abs(v) > MAX_WIRE_INT
        ):
            digits = len(v.digits.lstrip("-")) if isinstance(v, _HugeInt) else len(str(abs(v)))
            raise HugeIntegerError(where or "request", f"integer too large ({digits} digits; |x| ≤ 2**64)")


def parse(data: bytes | bytearray | str) -> Any:
    """Parse strict JSON, huge integers left unchecked (see :func:`check_integers`).

    Raises:
        DuplicateKeyError: naming the key (a ValidationError).
        ValidationError: NaN/Infinity, UTF-16/32 text.
        ValueError: not JSON, invalid UTF-8 (``UnicodeDecodeError``). RecursionError: too deep.
    """
    return json.loads(
        _text(data), parse_constant=_reject_constant, parse_int=_parse_int, object_pairs_hook=_unique_object
    )


def loads_strict(data: bytes | bytearray | str) -> Any:
    """Parse strict JSON (see the module doc): :func:`parse`, then :func:`check_integers`."""
    value = parse(data)
    check_integers(value, data)
    return value


def loads_message(data: bytes) -> Any:
    """Parse a message the service wrote (msgspec: strict UTF-8, no NaN/Infinity; ValueError)."""
    return msgspec.json.decode(data)


def dumps(obj: Any) -> bytes:
    """Compact strict JSON bytes (NaN or Infinity raise ``ValueError``)."""
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).encode()


def encode_result(obj: Any) -> bytes:
    """A plan result or cycle record as compact JSON (msgspec; non-finite floats ``null``; what
    msgspec cannot encode, e.g. NumPy values, through :func:`~eos_svc.records.to_jsonable` first)."""
    try:
        return msgspec.json.encode(obj)
    except (TypeError, ValueError, OverflowError, msgspec.EncodeError):
        return msgspec.json.encode(to_jsonable(obj))
