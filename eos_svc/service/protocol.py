"""Wire protocol of the EOS planning service (keys and messages: ``docs/service.md``): key
expressions under ``eos/@v1[/<namespace>]``, error codes, the request and cancel messages, read
strictly (:mod:`eos_svc.service.wire_json`). Pure (no Zenoh import): the decoder can be fuzzed alone.
"""

from __future__ import annotations

import hmac
import re
import secrets
from collections.abc import Mapping
from dataclasses import dataclass
from json.encoder import encode_basestring_ascii as _json_str
from typing import Any

import msgspec

from eos_svc.errors import ValidationError
from eos_svc.schema.request import PlanRequest
from eos_svc.service.wire_json import (
    DuplicateKeyError,
    HugeIntegerError,
    check_integers,
    dumps,
    loads_strict,
    parse,
)

#: version of the message schemas (the ``"schema"`` field of every message)
SCHEMA_VERSION = 1
#: root of every key expression; ``@v1`` versions the key space
ROOT = "eos/@v1"
#: largest plan request accepted (bytes of JSON)
MAX_REQUEST_BYTES = 64 * 1024
#: largest cancel request accepted (bytes of JSON)
MAX_CANCEL_BYTES = 1024

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

#: plan states published on ``P/goal/<goal_id>/status``
STATE_RUNNING = "running"
STATE_DONE = "done"

#: goal ids and namespaces: one plain key-expression chunk (no wildcards, no ``@``, no ``/``)
ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}")
#: a cancel token: the goal owner's secret (16-128 URL-safe characters), sent with the request and
#: with a cancel, never published
TOKEN_PATTERN = re.compile(r"[A-Za-z0-9_\-]{16,128}")

#: largest JSON size of the field name an error reply echoes (bytes, escaped)
MAX_FIELD_JSON = 256
#: largest JSON size of the reason an error reply carries (bytes, escaped)
MAX_REASON_JSON = 1536


def is_id(value: str) -> bool:
    """Whether ``value`` is a goal id, instance id or namespace (:data:`ID_PATTERN`)."""
    return ID_PATTERN.fullmatch(value) is not None


def is_token(value: str) -> bool:
    """Whether ``value`` has the form of a cancel token (:data:`TOKEN_PATTERN`)."""
    return TOKEN_PATTERN.fullmatch(value) is not None


def clip(text: str, max_json: int) -> str:
    """``text`` cut (with a trailing ``…``) so that its JSON string form is at most ``max_json`` bytes."""
    if len(_json_str(text)) <= max_json:
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


# ---------------------------------------------------------------------- cancel
def new_cancel_token() -> str:
    """A fresh random cancel token: 128 bits from the OS's CSPRNG, URL-safe base64 (22 characters)."""
    return secrets.token_urlsafe(16)


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


# ---------------------------------------------------------------------- plan requests
def encode_request(
    goal_id: str,
    request: PlanRequest | Mapping[str, Any],
    cancel_token: str | None = None,
    watch: bool | None = None,
) -> bytes:
    """A plan request on the wire: ``{"schema": 1, "goal_id", ["cancel_token",] ["watch",] <fields>}``
    (no ``cancel_token``: nobody can cancel it; ``watch``: see :class:`Envelope`). A
    :class:`PlanRequest` is written by msgspec; a mapping is sent as given, through the strict
    encoder (its fields win over the envelope's; NaN or Infinity raise ``ValueError``)."""
    envelope: dict[str, Any] = {"schema": SCHEMA_VERSION, "goal_id": goal_id}
    if cancel_token is not None:
        envelope["cancel_token"] = cancel_token
    if watch is not None:
        envelope["watch"] = bool(watch)
    if isinstance(request, PlanRequest):
        return msgspec.json.encode({**envelope, **request.to_dict()})
    return dumps({**envelope, **dict(request)})


@dataclass(frozen=True)
class Envelope:
    """A decoded plan request: its goal id, the request, the owner's cancel token (or ``None``)
    and the requester's ``watch`` hint (``True``: it subscribed to the goal before sending;
    ``False``: it did not; ``None``: not said, the service asks Zenoh's routing tables)."""

    goal_id: str
    request: PlanRequest
    cancel_token: str | None = None
    watch: bool | None = None


#: the envelope's keys around a plan request's own fields
_ENVELOPE_KEYS = frozenset(("schema", "goal_id", "cancel_token", "watch"))


def decode_request(
    payload: bytes | bytearray | memoryview, max_bytes: int = MAX_REQUEST_BYTES
) -> tuple[str, PlanRequest]:
    """Decode and validate a plan request: ``(goal_id, request)`` (see :func:`decode_envelope`)."""
    env = decode_envelope(payload, max_bytes)
    return env.goal_id, env.request


def decode_envelope(payload: bytes | bytearray | memoryview, max_bytes: int = MAX_REQUEST_BYTES) -> Envelope:
    """Decode and validate a plan request with its envelope (goal id, cancel token, watch hint):
    the strict parser, then every field checked in turn.

    Raises:
        RequestError: and nothing else, whatever the bytes — with the code, the field and the reason.
    """
    if len(payload) > max_bytes:
        raise RequestError(E_TOO_LARGE, "request", f"{len(payload)} bytes > limit {max_bytes}")
    raw = payload if isinstance(payload, bytes) else bytes(payload)
    try:
        data = parse(raw)
    except DuplicateKeyError as exc:
        raise RequestError(E_NOT_JSON, exc.key, "duplicate key in an object") from None
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
    try:
        check_integers(data, raw)
    except HugeIntegerError as exc:
        raise RequestError(E_INVALID, exc.field, exc.reason, goal_id) from None
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
