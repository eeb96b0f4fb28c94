"""What a validation needs from a plan result, checked at the edge.

A plan result (a :class:`~eos_svc.agents.PlanResult` or its JSON form, as ``eos plan --json``
prints it) gives the final hand configuration ``q_final``, the real object
(``ground_truth``: shape, size fields, position, rpy) and the friction μ. Every problem is a
:class:`~eos_svc.errors.ValidationError` naming the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from eos_svc.errors import ValidationError
from eos_svc.schema.request import MAX_FRICTION, MESH_FIELDS, SHAPE_SIZE_FIELDS, ObjectSpec, Table
from eos_svc.validation.report import DIRECTIONS


@dataclass(frozen=True)
class GraspSetup:
    """The grasp to simulate.

    Attributes:
        q_final: every joint of the hand in the planner's order (hand3x3: wrist x, y, z (m),
            roll, pitch, yaw (rad), then each finger's joints from the palm out (rad)).
        obj: the real object, shape, size and pose.
        friction: Coulomb μ of the hand–object contacts.
        table_height: the table the object rests on (world z of its top, m), or None.
    """

    q_final: tuple[float, ...]
    obj: ObjectSpec
    friction: float
    table_height: float | None = None


def _field(result: Any, name: str) -> Any:
    found = name in result if isinstance(result, Mapping) else hasattr(result, name)
    if not found:
        raise ValidationError(name, "is missing from the plan result")
    return result[name] if isinstance(result, Mapping) else getattr(result, name)


def _q_final(value: Any, joints: int) -> tuple[float, ...]:
    if value is None:
        raise ValidationError(
            "q_final", "is null: the plan has no final hand configuration (the end agent never judged it)"
        )
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence):
        raise ValidationError("q_final", f"must be a list of {joints} numbers, got {type(value).__name__}")
    if len(value) != joints:
        raise ValidationError(
            "q_final",
            f"must have {joints} joint values (wrist then fingers), got {len(value)}: is this another "
            "hand's plan (e.g. --hand allegro)? Validate it with its hand (validate_grasp(..., hand=...), "
            "eos validate --hand NAME)",
        )
    out = []
    for i, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
            raise ValidationError(f"q_final[{i}]", f"must be a finite number, got {v!r}")
        out.append(float(v))
    return tuple(out)


def _object(value: Any) -> ObjectSpec:
    if not isinstance(value, Mapping):
        raise ValidationError("ground_truth", f"must be an object, got {type(value).__name__}")
    sizes = {k for fields in SHAPE_SIZE_FIELDS.values() for k in fields} | set(MESH_FIELDS)
    # ground_truth also carries derived fields (diameter, d_over_h): keep what a request has
    spec = {k: v for k, v in value.items() if k in sizes | {"shape", "position", "rpy"}}
    if "position" not in spec:
        raise ValidationError("ground_truth.position", "is required")
    try:
        return ObjectSpec.from_dict(spec, prefix="ground_truth")
    except ValidationError as exc:  # size checks name the request's "object.*" fields
        where = "ground_truth" + exc.field[len("object") :] if exc.field.startswith("object") else exc.field
        raise ValidationError(where, exc.reason) from None


def _friction(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValidationError("friction", f"must be a number, got {type(value).__name__}")
    mu = float(value)
    if not (math.isfinite(mu) and 0.0 <= mu <= MAX_FRICTION):
        raise ValidationError("friction", f"must be in [0, {MAX_FRICTION}], got {value!r}")
    return mu


def grasp_setup(result: Any, joints: int) -> GraspSetup:
    """The grasp of a plan result (object or JSON dict) with ``joints`` hand joints.

    Raises:
        ValidationError: naming the missing or malformed field (``q_final``,
            ``ground_truth.radius``, ``friction``, …).
    """
    if not isinstance(result, Mapping) and not hasattr(result, "q_final"):
        raise ValidationError(
            "result", f"must be a plan result or its JSON object, got {type(result).__name__}"
        )
    q = _q_final(_field(result, "q_final"), joints)
    obj = _object(_field(result, "ground_truth"))
    friction = _friction(_field(result, "friction"))
    return GraspSetup(q, obj, friction, _table_height(result))


def _table_height(result: Any) -> float | None:
    """The table of the plan's request (``request.table.height``), or None (none, or a result
    without its request)."""
    request = result.get("request") if isinstance(result, Mapping) else getattr(result, "request", None)
    table = request.get("table") if isinstance(request, Mapping) else None
    if table is None:
        return None
    try:
        return Table.from_dict(table).height
    except ValidationError as exc:
        raise ValidationError(f"request.{exc.field}", exc.reason) from None


def load_directions(directions: int | Sequence[str]) -> tuple[str, ...]:
    """The load directions: the first ``n`` of :data:`DIRECTIONS` or named ones (``"+x"``, …).

    Raises:
        ValidationError: ``directions`` names an unknown or repeated direction, or is out of 1…6.
    """
    if isinstance(directions, int) and not isinstance(directions, bool):
        if not 1 <= directions <= len(DIRECTIONS):
            raise ValidationError("directions", f"must be in [1, {len(DIRECTIONS)}], got {directions}")
        return DIRECTIONS[:directions]
    if isinstance(directions, (str, bool)) or not isinstance(directions, Sequence) or not directions:
        raise ValidationError(
            "directions", "must be a count 1…6 or a non-empty list of +x, -x, +y, -y, +z, -z"
        )
    for i, d in enumerate(directions):
        if d not in DIRECTIONS or d in directions[:i]:
            why = "given twice" if d in DIRECTIONS else f"unknown (choose from {', '.join(DIRECTIONS)})"
            raise ValidationError("directions", f"direction {d!r}: {why}")
    return tuple(directions)
