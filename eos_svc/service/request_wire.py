"""The fast path of plan-request decoding: one typed msgspec decode (C) straight into the fields.

:func:`decode_fast` parses a plan request in the form the clients send it — every field present
(``encode_request`` writes them all), values of the right JSON types within their bounds — with
msgspec's typed decoder, whose types and :class:`msgspec.Meta` bounds are those
:class:`~eos_svc.agents.request.PlanRequest` and :class:`~eos_svc.agents.request.ObjectSpec` check
(built from the same constants), then builds the request without checking it a second time
(``from_checked``). It returns ``None`` for anything else, and the caller
(:func:`eos_svc.service.protocol.decode_envelope`) takes the full path, which names the field
and the reason of any error: so every refusal keeps its exact message, and what this path accepts
the full path accepts as the same request (the tests compare both on valid and invalid payloads).

What msgspec alone would let through, and how it is kept out:

- a repeated key (msgspec keeps its last value silently; the wire refuses it): the decode is kept
  only when the payload has exactly as many colons (one after every key, others only inside
  strings: never fewer than the keys) as the decoded request has fields;
- an integer beyond ±2**64 (the full path refuses it, naming it): every field but ``rpy`` is
  bounded far below (msgspec refuses it there); an ``rpy`` angle of magnitude ≥ 1e19 (what a
  20-digit integer is) goes the full way;
- a goal id or cancel token of the wrong form: checked against the protocol's own patterns
  (:mod:`eos_svc.service.ids`).

Strict UTF-8, no NaN/Infinity, no trailing data: msgspec refuses those itself.
"""

from __future__ import annotations

import struct
from typing import Annotated, Literal

import msgspec

from eos_svc.errors import ValidationError
from eos_svc.ratings import Weights
from eos_svc.schema.request import (
    MAX_CYCLES_LIMIT,
    MAX_DEADLINE_S,
    MAX_FRICTION,
    MAX_OBJECT_SIZE,
    MAX_POSITION,
    MAX_TACTILE_NOISE,
    ObjectSpec,
    PlanRequest,
)
from eos_svc.service.ids import is_id, is_token

#: an object size (m): > 0 and ≤ MAX_OBJECT_SIZE (ObjectSpec's ``_positive``)
_Size = Annotated[float, msgspec.Meta(gt=0.0, le=MAX_OBJECT_SIZE)]
#: a position coordinate (m): within ±MAX_POSITION
_Coord = Annotated[float, msgspec.Meta(ge=-MAX_POSITION, le=MAX_POSITION)]
_Vec3 = tuple[float, float, float]
_Pos3 = tuple[_Coord, _Coord, _Coord]
_Size3 = tuple[_Size, _Size, _Size]


class _Shape(msgspec.Struct, forbid_unknown_fields=True, tag_field="shape"):
    position: _Pos3
    rpy: _Vec3


class _Sphere(_Shape, tag="sphere"):
    radius: _Size


class _Ellipsoid(_Shape, tag="ellipsoid"):
    radii: _Size3


class _RadiusLength(_Shape):
    """The size fields a cylinder and a capsule share (not itself a member of the union)."""

    radius: _Size
    length: _Size


class _Cylinder(_RadiusLength, tag="cylinder"):
    pass


class _Box(_Shape, tag="box"):
    size: _Size3


class _Capsule(_RadiusLength, tag="capsule"):
    pass


class _Weights(msgspec.Struct, forbid_unknown_fields=True):
    default: float
    opportunistic: float
    learned: float


class _Request(msgspec.Struct, forbid_unknown_fields=True):
    schema: Literal[1]
    goal_id: str
    object: _Sphere | _Ellipsoid | _Cylinder | _Box | _Capsule
    weights: _Weights
    seed: Annotated[int, msgspec.Meta(ge=0, le=2**63 - 1)]
    tactile_noise: Annotated[float, msgspec.Meta(ge=0.0, le=MAX_TACTILE_NOISE)]
    max_cycles: Annotated[int, msgspec.Meta(ge=1, le=MAX_CYCLES_LIMIT)]
    deadline_s: Annotated[float, msgspec.Meta(gt=0.0, le=MAX_DEADLINE_S)] | None
    friction: Annotated[float, msgspec.Meta(ge=0.0, le=MAX_FRICTION)]
    cancel_token: str | msgspec.UnsetType | None = msgspec.UNSET
    watch: bool | msgspec.UnsetType | None = msgspec.UNSET


_decode = msgspec.json.Decoder(_Request).decode
#: per shape struct: the shape's name and its size fields, in ObjectSpec's order
_SHAPES: dict[type, tuple[str, tuple[str, ...]]] = {
    struct_type: (struct_type.__struct_config__.tag, sizes)  # type: ignore[misc]
    for struct_type, sizes in (
        (_Sphere, ("radius",)),
        (_Ellipsoid, ("radii",)),
        (_Cylinder, ("radius", "length")),
        (_Box, ("size",)),
        (_Capsule, ("radius", "length")),
    )
}
#: keys of a request besides the object's size fields, the cancel token and the watch hint: 9 at the top level
#: (schema, goal_id, object, weights, seed, tactile_noise, max_cycles, deadline_s, friction),
#: the object's shape, position, rpy and the 3 weights
_FIXED_KEYS = 15
#: Weights already built, by their three values' bytes (-0.0 and 0.0 apart): a Weights is
#: immutable, and most requests carry one of a few (the default's); at most _WEIGHTS_KEPT kept
_WEIGHTS: dict[bytes, Weights] = {}
_WEIGHTS_KEPT = 64
_pack3 = struct.Struct("3d").pack
#: an ``rpy`` angle this large may be an integer literal of 20 digits or more (see the module doc)
_HUGE = 1e19


def decode_fast(raw: bytes) -> tuple[str, PlanRequest, str | None, bool | None] | None:
    """``(goal_id, request, cancel_token, watch)`` of a plan request in the clients' form (an
    absent token or watch hint as ``None``), or ``None``: take the full path (see the module doc)."""
    try:
        msg = _decode(raw)
    except (msgspec.DecodeError, RecursionError, ValueError, TypeError):  # ValidationError: a DecodeError
        return None  # whatever msgspec refuses, the full path names
    obj = msg.object
    shape, sizes = _SHAPES[type(obj)]
    token = msg.cancel_token
    watch = msg.watch
    keys = _FIXED_KEYS + len(sizes) + (token is not msgspec.UNSET) + (watch is not msgspec.UNSET)
    if raw.count(b":") != keys:  # a key given twice (or a colon in a string: either way)
        return None
    roll, pitch, yaw = obj.rpy
    if not (abs(roll) < _HUGE and abs(pitch) < _HUGE and abs(yaw) < _HUGE):
        return None
    if not is_id(msg.goal_id):
        return None
    if token is msgspec.UNSET:
        token = None
    elif token is not None and not is_token(token):
        return None
    w = msg.weights
    key = _pack3(w.default, w.opportunistic, w.learned)
    weights = _WEIGHTS.get(key)
    if weights is None:
        try:
            weights = Weights(w.default, w.opportunistic, w.learned)  # checks itself: ranges, sum
        except ValidationError:
            return None
        if len(_WEIGHTS) < _WEIGHTS_KEPT:
            _WEIGHTS[key] = weights
    size = {sizes[0]: getattr(obj, sizes[0])}
    if len(sizes) == 2:
        size[sizes[1]] = getattr(obj, sizes[1])
    spec = ObjectSpec.from_checked(shape, size, obj.position, obj.rpy)
    request = PlanRequest.from_checked(
        spec, weights, msg.seed, msg.tactile_noise, msg.max_cycles, msg.deadline_s, msg.friction
    )
    return msg.goal_id, request, token, (None if watch is msgspec.UNSET else watch)  # null: None too
