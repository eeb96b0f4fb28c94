"""Wire protocol of the EOS planning service: key expressions and message schemas.

Everything on the wire is UTF-8 JSON (RFC 8259) carrying ``"schema": 1``, read
strictly: UTF-8 only (a leading UTF-8 byte-order mark is ignored; UTF-16/32 and
invalid bytes such as encoded surrogates are refused), no NaN/Infinity, no
duplicate keys in an object, no integer beyond ±2**64 (refused naming its
field). Every error reply is bounded: the field and reason it echoes are
clipped (:data:`MAX_FIELD_JSON`, :data:`MAX_REASON_JSON`), so a reply stays
under 4 KiB whatever the request. Key expressions live under a versioned prefix
``eos/@v1`` (``@v1`` is a verbatim chunk: wildcards never cross it), with an
optional namespace: ``eos/@v1/<namespace>``. With ``P`` the prefix:

=================================  =========================  ==========================================
key expression                     Zenoh entity               message
=================================  =========================  ==========================================
``P/instance/<iid>``               liveliness token           (none) — one per service instance
``P/plan/<iid>``                   queryable (one/instance)   request: :func:`encode_request`; reply: the
                                                              plan result, or an error reply
                                                              (:class:`RequestError`)
``P/cancel/<goal_id>``             queryable ``P/cancel/*``   request: :func:`encode_cancel` (the goal's
                                                              ``cancel_token``); reply: ``{"goal_id",
                                                              "instance", "found"}`` or ``forbidden``
``P/goal/<goal_id>/cycle``         publication (BLOCK)        ``{"schema", "goal_id", "instance", "seq",
                                                              "record"}`` — one per cycle, seq 1, 2, ...
``P/goal/<goal_id>/status``        publication (BLOCK)        ``{"schema", "goal_id", "instance", "state",
                                                              ...}`` — ``running`` with the ``request``,
                                                              then ``done`` with ``status``, ``cycles``
                                                              and ``result``
=================================  =========================  ==========================================

This module is pure (no Zenoh import) so the decoder can be fuzzed alone.
"""

from __future__ import annotations

import base64
import hmac
import json
import math
import os
import re
from collections.abc import Mapping
from json.encoder import encode_basestring_ascii as _json_str
from typing import Any, NamedTuple

import msgspec

from eos_svc.errors import ContractError, ValidationError
from eos_svc.records import CycleRecord, to_jsonable
from eos_svc.schema.request import PlanRequest
from eos_svc.service.ids import ID_PATTERN as ID_PATTERN  # the protocol's names, defined there
from eos_svc.service.ids import TOKEN_PATTERN as TOKEN_PATTERN
from eos_svc.service.ids import is_id, is_token
from eos_svc.service.request_wire import decode_fast

#: version of the message schemas (the ``"schema"`` field of every message)
SCHEMA_VERSION = 1
#: root of every key expression; ``@v1`` versions the key space
ROOT = "eos/@v1"
#: largest plan request accepted (bytes of JSON)
MAX_REQUEST_BYTES = 64 * 1024

# Error codes carried by error replies.
E_TOO_LARGE = "payload_too_large"
E_NOT_JSON = "not_json"
E_SCHEMA = "unsupported_schema"
E_INVALID = "invalid_request"
E_BUSY = "busy"
E_DUPLICATE = "duplicate_goal"
E_UNAVAILABLE = "unavailable"
E_INTERNAL = "internal_error"
E_FORBIDDEN = "forbidden"
ERROR_CODES = frozenset(
    {
        E_TOO_LARGE,
        E_NOT_JSON,
        E_SCHEMA,
        E_INVALID,
        E_BUSY,
        E_DUPLICATE,
        E_UNAVAILABLE,
        E_INTERNAL,
        E_FORBIDDEN,
    }
)
#: largest cancel request accepted (bytes of JSON)
MAX_CANCEL_BYTES = 1024

#: plan states published on ``P/goal/<goal_id>/status``
STATE_RUNNING = "running"
STATE_DONE = "done"


#: largest JSON size of the field name an error reply echoes (bytes, escaped)
MAX_FIELD_JSON = 256
#: largest JSON size of the reason an error reply carries (bytes, escaped)
MAX_REASON_JSON = 1536


def clip(text: str, max_json: int) -> str:
    """``text`` cut (with a trailing ``…``) so that its JSON string form is at most ``max_json`` bytes."""
    if len(text) * 12 + 2 <= max_json or len(_json_str(text)) <= max_json:  # 12: \udXXX\udXXX
        return text
    cut = text[: max_json - 3]
    while len(_json_str(cut + "…")) > max_json:
        cut = cut[: len(cut) - max(1, len(cut) // 8)]
    return cut + "…"


class RequestError(ValidationError):
    """A request the service refuses; sent back as an error reply.

    Attributes:
        code: machine-readable cause (one of :data:`ERROR_CODES`).
        field: dotted name of the offending field (``"request"`` for the whole message).
        reason: why, in words.
        goal_id: the request's goal id when it could be read, else ``None``.
    """

    def __init__(self, code: str, field: str, reason: str, goal_id: str | None = None) -> None:
        super().__init__(clip(field, MAX_FIELD_JSON), clip(reason, MAX_REASON_JSON))
        self.code = code
        self.goal_id = goal_id

    def to_dict(self) -> dict[str, Any]:  # type: ignore[override,unused-ignore]
        """The error reply's JSON form."""
        return {
            "schema": SCHEMA_VERSION,
            "code": self.code,
            "field": self.field,
            "reason": self.reason,
            "goal_id": self.goal_id,
        }

    def __str__(self) -> str:
        return f"{self.code}: {self.field}: {self.reason}"


def check_id(value: object, field: str) -> str:
    """Validate a goal id or namespace (one key-expression chunk, 1–64 chars of ``[A-Za-z0-9_.-]``)."""
    if not isinstance(value, str):
        raise RequestError(E_INVALID, field, f"must be a string, got {type(value).__name__}")
    if not is_id(value):
        raise RequestError(
            E_INVALID,
            field,
            "must be 1-64 characters of A-Z a-z 0-9 _ . - starting with a letter or digit",
        )
    return value


def prefix(namespace: str | None = None) -> str:
    """The service's key prefix: ``eos/@v1`` or ``eos/@v1/<namespace>``."""
    if namespace is None or namespace == "":
        return ROOT
    return f"{ROOT}/{check_id(namespace, 'namespace')}"


def instance_key(pfx: str, instance: str = "*") -> str:
    """Liveliness token key of an instance (``*``: all)."""
    return f"{pfx}/instance/{instance}"


def plan_key(pfx: str, instance: str = "*") -> str:
    """Plan queryable of an instance (``*``: any)."""
    return f"{pfx}/plan/{instance}"


def cancel_key(pfx: str, goal_id: str = "*") -> str:
    """Cancel query key of a goal (every instance serves ``P/cancel/*``)."""
    return f"{pfx}/cancel/{goal_id}"


def cycle_key(pfx: str, goal_id: str = "*") -> str:
    """Where a goal's cycle records are published (``*``: every goal)."""
    return f"{pfx}/goal/{goal_id}/cycle"


def status_key(pfx: str, goal_id: str = "*") -> str:
    """Where a goal's status messages are published (``*``: every goal)."""
    return f"{pfx}/goal/{goal_id}/status"


def goal_keys(pfx: str, goal_id: str = "*") -> str:
    """Everything published about a goal (cycles and status)."""
    return f"{pfx}/goal/{goal_id}/*"


def _reject_constant(name: str) -> Any:
    raise ValidationError("payload", f"{name} is not valid JSON")


class DuplicateKeyError(ValidationError):
    """An object of the message has the same key twice (RFC 8259: names SHOULD be unique)."""

    def __init__(self, field: str, reason: str = "duplicate key in an object") -> None:
        super().__init__(field, reason)
        self.key = field  #: the repeated key


class _HugeInt:
    """An integer literal too long to be any field's value (kept as text, named later)."""

    __slots__ = ("digits",)

    def __init__(self, digits: str) -> None:
        self.digits = digits


def _parse_int(literal: str) -> Any:
    """``int`` for literals up to 20 digits (all ≤ 2**64 need); longer ones are never converted
    (Python refuses > 4,300 digits, and big ones cost quadratic time): a :class:`_HugeInt`."""
    return int(literal) if len(literal) <= 21 else _HugeInt(literal)


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


#: one strict decoder for every message (``json.loads`` with options builds a new one per call)
_DECODER = json.JSONDecoder(
    parse_constant=_reject_constant, parse_int=_parse_int, object_pairs_hook=_unique_object
)
#: one compact strict encoder (what ``json.dumps(separators=..., allow_nan=False)`` builds per call)
_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)
_BOM = b"\xef\xbb\xbf"
_tuple_new = tuple.__new__
_msgspec_decode = msgspec.json.Decoder().decode
_msgspec_encode = msgspec.json.Encoder().encode


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


def loads_strict(data: bytes | str) -> Any:
    """Parse strict JSON (see the module doc); raises ValueError (an integer beyond ±2**64
    included, named by where it is) or RecursionError."""
    value = _DECODER.decode(_text(data))
    if _LONG_DIGITS.search(data.encode() if isinstance(data, str) else data):
        try:
            _check_integers(value, "", None)
        except RequestError as err:
            raise ValidationError(err.field, err.reason) from None
    return value


def loads_message(data: bytes) -> Any:
    """Parse a message *from the service* (reply, cycle, status) fast, with msgspec: strict
    UTF-8, no NaN/Infinity (a duplicate key keeps its last value: requests, which come from
    anyone, go through :func:`decode_envelope` instead). Raises ValueError or RecursionError."""
    return _msgspec_decode(data)


def encode_result(obj: Any) -> bytes:
    """A plan result (or any message body) as compact JSON bytes, fast (msgspec; non-finite
    floats become ``null``); values msgspec cannot encode (NumPy scalars and arrays, objects
    with ``to_dict``) go through ``to_jsonable`` first, and msgspec writes that: the same bytes
    as converting first whenever the plain values agree."""
    try:
        return _msgspec_encode(obj)
    except (TypeError, ValueError, OverflowError, msgspec.EncodeError):
        return _msgspec_encode(to_jsonable(obj))


def dumps(obj: Any) -> bytes:
    """Compact strict JSON bytes."""
    return _ENCODER.encode(obj).encode()


# ---------------------------------------------------------------------- cycle records on the wire
_float_repr = float.__repr__
#: float -> its JSON text: rating values, weights and many board values repeat from cycle to cycle
_FLOAT_TEXT: dict[float, str] = {}
_FLOAT_TEXT_MAX = 4096


def _float_json(x: float) -> str:
    """JSON text of a float as ``dumps(to_jsonable(x))`` writes it (non-finite: ``null``)."""
    if x == 0.0:  # 0.0 and -0.0 are equal keys: never cached
        return _float_repr(x)
    s = _FLOAT_TEXT.get(x)
    if s is None:
        if not math.isfinite(x):
            return "null"
        s = _float_repr(x)
        if len(_FLOAT_TEXT) < _FLOAT_TEXT_MAX:
            _FLOAT_TEXT[x] = s
    return s


def _value_json(v: Any) -> str:
    """JSON text of any record value, as ``dumps(to_jsonable(v))`` writes it."""
    t = type(v)
    if t is float:
        return _float_json(v)
    if t is str:
        return _json_str(v)
    if v is None:
        return "null"
    if v is True:
        return "true"
    if v is False:
        return "false"
    if t is int:
        return int.__repr__(v)
    if t is tuple and v and all([type(x) is float for x in v]):
        # a flat tuple of floats: the hand's configuration (board entry hand_q), written as the
        # new value of one cycle and the old value of the next — the same tuple, encoded once
        last = _last_vector[0]
        if v is last[0]:
            return last[1]
        text = "[" + ",".join([_float_repr(x) if math.isfinite(x) else "null" for x in v]) + "]"
        _last_vector[0] = (v, text)
        return text
    return _ENCODER.encode(to_jsonable(v))


#: (the last float tuple encoded, its JSON) in one slot, read and replaced whole (thread-safe as
#: _last_weights); tuples are immutable, so the same object always has the same text
_last_vector: list[tuple[Any, str]] = [((), "")]


#: agent name -> ``{"agent":"<name>","default":`` (the fixed start of its rating row)
_RATING_HEAD: dict[str, str] = {}
_ELIGIBLE = {True: ',"eligible":true}', False: ',"eligible":false}'}
#: (the last Weights seen, its JSON) in one slot: read and replaced whole, so workers running
#: plans with different weights never pair one's Weights with the other's JSON
_last_weights: list[tuple[Any, str]] = [(None, "")]


def cycle_record_json(record: CycleRecord) -> str:
    """``CycleRecord.to_dict()`` as compact strict JSON, without building the dict.

    The same text as ``dumps(to_jsonable(record.to_dict()))`` (checked by the tests), written
    straight from the record with the fixed parts and repeated floats cached: a cycle is
    encoded once per cycle in the service's planner thread.
    """
    weights = record.weights
    last = _last_weights[0]
    if weights is last[0]:
        weights_json = last[1]
    else:
        weights_json = _value_json(weights.to_dict())
        _last_weights[0] = (weights, weights_json)
    fj = _float_json
    vj = _value_json
    rows = []
    for r in record.ratings:
        name = r.name
        head = _RATING_HEAD.get(name) if type(name) is str else None
        if head is None:
            head = '{"agent":' + vj(name) + ',"default":'
            if type(name) is str and len(_RATING_HEAD) < 1024:
                _RATING_HEAD[name] = head
        d, o, le, tot, el = r.default, r.opportunistic, r.learned, r.total, r.eligible
        rows.append(
            head
            + (fj(d) if type(d) is float else vj(d))
            + ',"opportunistic":'
            + (fj(o) if type(o) is float else vj(o))
            + ',"learned":'
            + (fj(le) if type(le) is float else vj(le))
            + ',"total":'
            + (fj(tot) if type(tot) is float else vj(tot))
            + (_ELIGIBLE[el] if type(el) is bool else ',"eligible":' + vj(el) + "}")
        )
    outcome = record.outcome
    changes = [
        '{"key":' + vj(c.key) + ',"old":' + vj(c.old) + ',"new":' + vj(c.new) + "}" for c in record.changes
    ]
    return (
        '{"seq":'
        + vj(record.seq)
        + ',"stage":'
        + vj(record.stage)
        + ',"stage_cycle":'
        + vj(record.stage_cycle)
        + ',"weights":'
        + weights_json
        + ',"ratings":['
        + ",".join(rows)
        + '],"chosen":'
        + vj(record.chosen)
        + ',"outcome":'
        + ("null" if outcome is None else vj(outcome.value))
        + ',"detail":'
        + vj(record.detail)
        + ',"changes":['
        + ",".join(changes)
        + '],"elapsed_s":'
        + vj(record.elapsed_s)
        + "}"
    )


#: fresh cancel tokens, made :data:`_TOKEN_BATCH` at a time (one ``os.urandom`` call, as
#: ``secrets.token_urlsafe`` makes each); emptied in a forked child, which must not reuse its
#: parent's secrets
_TOKENS: list[str] = []
_TOKEN_BATCH = 64
os.register_at_fork(after_in_child=_TOKENS.clear)


def new_cancel_token() -> str:
    """A fresh random cancel token: 128 bits from the OS's CSPRNG, URL-safe base64 (22 characters),
    each handed out once (``list.pop`` is atomic: threads may share the batch)."""
    try:
        return _TOKENS.pop()
    except IndexError:
        raw = os.urandom(16 * _TOKEN_BATCH)
        _TOKENS.extend(
            base64.urlsafe_b64encode(raw[i : i + 16]).rstrip(b"=").decode() for i in range(0, len(raw), 16)
        )
        return _TOKENS.pop()


def encode_request(
    goal_id: str,
    request: PlanRequest | Mapping[str, Any],
    cancel_token: str | None = None,
    watch: bool | None = None,
) -> bytes:
    """A plan request on the wire: ``{"schema": 1, "goal_id": ..., ["cancel_token": ...,]
    ["watch": ...,] <PlanRequest fields>}``. Without a ``cancel_token`` nobody can cancel the
    goal. ``watch``: whether the requester subscribes to the goal's messages before sending
    (see :class:`Envelope`); ``None`` leaves it out and the service asks Zenoh instead.

    A :class:`PlanRequest` (validated: every number finite) is written by msgspec (floats in
    their shortest round-trip digits, e.g. ``1e-05`` as ``0.00001``); a mapping is sent as given,
    through the strict encoder (NaN or Infinity in it raise ``ValueError``)."""
    envelope: dict[str, Any] = {"schema": SCHEMA_VERSION, "goal_id": goal_id}
    if cancel_token is not None:
        envelope["cancel_token"] = cancel_token
    if watch is not None:
        envelope["watch"] = bool(watch)
    if isinstance(request, PlanRequest):
        return _msgspec_encode({**envelope, **request.to_dict()})  # no key of the body is the envelope's
    body = dict(request)
    if not body or body.keys() & envelope.keys():  # the body's fields win, as in a merged dict
        return dumps({**envelope, **body})
    # the envelope spliced before the body's own JSON (no merged dict): the same bytes
    return dumps(envelope)[:-1] + b"," + dumps(body)[1:]


def encode_cancel(cancel_token: str | None) -> bytes:
    """A cancel request (the payload of a query on ``P/cancel/<goal_id>``)."""
    return dumps({"schema": SCHEMA_VERSION, "cancel_token": cancel_token})


def decode_cancel(payload: bytes | None) -> str | None:
    """The cancel token of a cancel request (``None`` when absent or unreadable)."""
    if not payload or len(payload) > MAX_CANCEL_BYTES:
        return None
    try:
        data = loads_strict(payload)
    except (ValueError, RecursionError):
        return None
    token = data.get("cancel_token") if isinstance(data, dict) else None
    return token if isinstance(token, str) and is_token(token) else None


def token_matches(expected: str | None, given: str | None) -> bool:
    """Whether a cancel carries the goal's token (constant-time compare; no token: never)."""
    if expected is None or given is None:
        return False
    return hmac.compare_digest(expected.encode(), given.encode())


#: largest |integer| on the wire (no field needs more; bigger ones do not fit a float)
MAX_WIRE_INT = 2**64


#: 20 digits in a row: the only way to write an integer with |x| > 2**64 (= 18446744073709551616)
_LONG_DIGITS = re.compile(rb"[0-9]{20}")


def _check_integers(value: Any, path: str, goal_id: str | None) -> None:
    """Reject integers too large for any field, naming where they are."""
    stack: list[tuple[Any, str]] = [(value, path)]
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
            raise RequestError(
                E_INVALID, where or "request", f"integer too large ({digits} digits; |x| ≤ 2**64)", goal_id
            )


class Envelope(NamedTuple):
    """A decoded plan request: its goal id, the request, the owner's cancel token (or ``None``)
    and the requester's ``watch`` hint: ``True`` when it subscribed to the goal's messages before
    sending (the service publishes them from the start without asking Zenoh), ``False`` when it
    did not (the service publishes them only for the other watchers it knows of), ``None`` when
    the request does not say (the service asks Zenoh's routing tables)."""

    goal_id: str
    request: PlanRequest
    cancel_token: str | None = None
    watch: bool | None = None


# the generated constructor's annotations as objects: namedtuple builds it in a namespace of its
# own, where the module's postponed annotations (strings) cannot be resolved (pdoc reads them)
Envelope.__new__.__annotations__ = {
    "goal_id": str,
    "request": PlanRequest,
    "cancel_token": str | None,
    "watch": bool | None,
}


#: the envelope's keys around a plan request's own fields
_ENVELOPE_KEYS = frozenset(("schema", "goal_id", "cancel_token", "watch"))


def decode_request(
    payload: bytes | bytearray | memoryview, max_bytes: int = MAX_REQUEST_BYTES
) -> tuple[str, PlanRequest]:
    """Decode and validate a plan request: ``(goal_id, request)`` (see :func:`decode_envelope`)."""
    env = decode_envelope(payload, max_bytes)
    return env.goal_id, env.request


def decode_envelope(payload: bytes | bytearray | memoryview, max_bytes: int = MAX_REQUEST_BYTES) -> Envelope:
    """Decode and validate a plan request with its envelope (goal id, cancel token).

    A request in the form the clients send (every field present and valid) takes one typed
    msgspec decode (:func:`~eos_svc.service.request_wire.decode_fast`); anything else, the strict
    stdlib parser and the field-by-field checks, which name the field and the reason.

    Raises:
        RequestError: and nothing else, whatever the bytes — with the code, the field and the reason.
    """
    if len(payload) > max_bytes:
        raise RequestError(E_TOO_LARGE, "request", f"{len(payload)} bytes > limit {max_bytes}")
    raw = payload if isinstance(payload, bytes) else bytes(payload)
    fast = decode_fast(raw)  # the clients' form, in one typed decode
    if fast is not None:
        return _tuple_new(Envelope, fast)  # a NamedTuple made in C
    return decode_checked(raw)


def decode_checked(raw: bytes) -> Envelope:
    """The full path of :func:`decode_envelope` (any size): the strict stdlib parser, then every
    field checked in turn; raises a :class:`RequestError` naming the field and the reason."""
    try:
        data = _DECODER.decode(_text(raw))
    except DuplicateKeyError as exc:
        raise RequestError(E_NOT_JSON, clip(exc.key, MAX_FIELD_JSON), "duplicate key in an object") from None
    except ValidationError as exc:  # not UTF-8 at all (UTF-16/32), NaN/Infinity
        raise RequestError(E_NOT_JSON, "request", exc.reason) from None
    except UnicodeDecodeError as exc:
        raise RequestError(
            E_NOT_JSON,
            "request",
            f"not UTF-8: byte {exc.start} ({raw[exc.start : exc.start + 1]!r}): {exc.reason}",
        ) from None
    except (ValueError, RecursionError) as exc:  # JSONDecodeError is a ValueError
        raise RequestError(E_NOT_JSON, "request", f"not JSON: {str(exc)[:200]}") from None
    if not isinstance(data, dict):
        raise RequestError(E_INVALID, "request", f"must be a JSON object, got {type(data).__name__}")
    goal_raw = data.get("goal_id")
    goal_id = goal_raw if isinstance(goal_raw, str) and is_id(goal_raw) else None
    if _LONG_DIGITS.search(raw):  # an integer beyond 2**64 has ≥ 20 digits: only then look for it
        _check_integers(data, "", goal_id)
    if "schema" not in data:
        raise RequestError(E_SCHEMA, "schema", "is required", goal_id)
    schema = data["schema"]
    if isinstance(schema, bool) or not isinstance(schema, int):
        raise RequestError(E_SCHEMA, "schema", f"must be an integer, got {type(schema).__name__}", goal_id)
    if schema != SCHEMA_VERSION:
        raise RequestError(
            E_SCHEMA, "schema", f"version {schema} not supported (this is {SCHEMA_VERSION})", goal_id
        )
    if "goal_id" not in data:
        raise RequestError(E_INVALID, "goal_id", "is required")
    check_id(goal_raw, "goal_id")
    assert goal_id is not None
    token = data.get("cancel_token")
    if token is not None and not (isinstance(token, str) and is_token(token)):
        raise RequestError(E_INVALID, "cancel_token", "must be 16-128 characters of A-Z a-z 0-9 _ -", goal_id)
    watch = data.get("watch")  # absent or null: no hint
    if watch is not None and type(watch) is not bool:
        raise RequestError(
            E_INVALID, "watch", f"must be true, false or null, got {type(watch).__name__}", goal_id
        )
    body = {k: v for k, v in data.items() if k not in _ENVELOPE_KEYS}
    try:
        request = PlanRequest.from_dict(body)
    except ValidationError as exc:
        raise RequestError(E_INVALID, exc.field or "request", exc.reason, goal_id) from None
    except (ArithmeticError, TypeError, ValueError, RecursionError) as exc:  # e.g. float(10**400)
        raise RequestError(E_INVALID, "request", f"unacceptable value: {str(exc)[:200]}", goal_id) from None
    if "file" in request.obj.size:  # a mesh: the service reads no file of its host's
        raise RequestError(
            E_INVALID,
            "object.file",
            "the service reads no files: send the mesh inline (vertices, faces)",
            goal_id,
        )
    return Envelope(goal_id, request, token, watch)


def error_from_payload(payload: bytes) -> RequestError:
    """Rebuild the :class:`RequestError` of an error reply (robust to foreign payloads)."""
    try:
        data = loads_strict(payload)
        if isinstance(data, dict) and isinstance(data.get("code"), str):
            return RequestError(
                str(data["code"]),
                str(data.get("field", "request")),
                str(data.get("reason", "")),
                data.get("goal_id") if isinstance(data.get("goal_id"), str) else None,
            )
    except (ValueError, RecursionError):
        pass
    return RequestError(E_INTERNAL, "reply", f"unreadable error reply: {bytes(payload[:200])!r}")
