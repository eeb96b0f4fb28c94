"""The remote-agent protocol: key expressions and the JSON messages (schema 1).

Query payloads (``rate`` and ``act``)::

    {"schema": 1, "ctx": {"seq": 12, "stage": "information", "stage_cycle": 4,
     "events": ["shape"], "last_agent": "post_shape", "acted": {"ep1": 2}},
     "board": {"<entry it reads>": <value>, ...}}

Replies: ``describe`` -> ``{"schema": 1, "name", "stages", "default", "reads", "writes"}``;
``rate`` -> ``{"rating": <number in [0, 1] or null>}``; ``act`` -> ``{"outcome": "progress",
"detail": "...", "ratings": {...}, "succeeded": null, "writes": {"<entry>": <value>},
"deletes": ["<entry>"]}``. A failure is an error reply ``{"reason": "..."}``. Board values
are JSON (:func:`eos_svc.records.to_jsonable`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

import msgspec

from eos_svc.agent import CycleContext
from eos_svc.board import BoardChange
from eos_svc.errors import ValidationError
from eos_svc.records import to_jsonable

#: the service's versioned root, as in :data:`eos_svc.service.protocol.ROOT`
ROOT = "eos/@v1"
SCHEMA = 1
#: the queryables of one agent
PARTS = ("describe", "rate", "act")
#: liveliness token of a serving agent
ALIVE = "alive"
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")


def check_name(value: object, field: str = "name") -> str:
    """An agent or namespace name: one key-expression chunk, 1–64 chars of ``[A-Za-z0-9_.-]``."""
    if not isinstance(value, str) or not _NAME.fullmatch(value):
        raise ValidationError(
            field, f"must be 1-64 characters of A-Z a-z 0-9 _ . - (no wildcard), got {value!r}"
        )
    return value


def prefix(namespace: str | None = None) -> str:
    """``eos/@v1`` or ``eos/@v1/<namespace>`` (the service's prefix)."""
    return ROOT if not namespace else f"{ROOT}/{check_name(namespace, 'namespace')}"


def agent_key(pfx: str, name: str, part: str) -> str:
    """The key of one of an agent's queryables (or ``alive``, its liveliness token)."""
    return f"{pfx}/agent/{check_name(name)}/{part}"


def dumps(value: Any) -> bytes:
    """Strict JSON bytes of ``value`` (msgspec; what it cannot encode, e.g. a NumPy array, made
    JSON by :func:`eos_svc.records.to_jsonable`; non-finite floats become ``null``)."""
    return _encode(value)


def loads(raw: bytes) -> Any:
    """The JSON value of ``raw`` (raises ``ValueError`` when it is not JSON)."""
    try:
        return _decode(raw)
    except msgspec.DecodeError as exc:
        raise ValueError(str(exc)) from None


_encode = msgspec.json.Encoder(enc_hook=to_jsonable).encode
_decode = msgspec.json.Decoder().decode


def ctx_to_json(ctx: CycleContext) -> dict[str, Any]:
    """The cycle context's JSON form (events as the keys they changed)."""
    return {
        "seq": ctx.seq,
        "stage": ctx.stage,
        "stage_cycle": ctx.stage_cycle,
        "events": [change.key for change in ctx.events],
        "last_agent": ctx.last_agent,
        "acted": dict(ctx.acted),
    }


def ctx_from_json(data: Mapping[str, Any]) -> CycleContext:
    """A :class:`CycleContext` back from its JSON form (events carry their keys only)."""
    events = tuple(BoardChange(str(key), None, None) for key in data.get("events", ()))
    return CycleContext(
        int(data["seq"]),
        str(data["stage"]),
        int(data["stage_cycle"]),
        events,
        data.get("last_agent"),
        dict(data.get("acted", {})),
    )


def query_payload(ctx: CycleContext, entries: Mapping[str, Any]) -> bytes:
    """The payload of a ``rate`` or ``act`` query."""
    return dumps({"schema": SCHEMA, "ctx": ctx_to_json(ctx), "board": entries})
