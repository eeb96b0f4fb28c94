"""The postulated object grasp synthesis plans on, from post_shape's postulate (board ``shape``):
its ``object`` in the request's JSON form, or for an older postulate an upright ball (curved
classes) or cube (plane, box) of its vertical half-extent ``grasp_radius``, grasped across the
vertical.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from eos_svc import objects
from eos_svc.objects import ObjectSizeError, SurfaceObject
from eos_svc.schema.request import ObjectSpec


def make_object(spec: ObjectSpec) -> SurfaceObject:
    """The kinematics object for a validated :class:`ObjectSpec`; :class:`ObjectSizeError`
    naming ``object.<field>`` when it cannot be built (an unreadable or flat mesh)."""
    try:
        return objects.make(spec.shape, spec.size, spec.position, spec.rpy)
    except ObjectSizeError as exc:
        raise ObjectSizeError(f"object.{exc.field}", exc.reason) from None


@dataclass(frozen=True)
class Postulate:
    """The object grasp synthesis plans on (request form), whether its orientation was sensed
    (else upright), whether its size is known along the vertical only (grasp across it), and its
    source: ``"post_shape"`` or ``"oracle"`` (the true object, for measurements only)."""

    spec: ObjectSpec
    pose_known: bool
    vertical_only: bool
    source: str = "post_shape"

    def words(self) -> str:
        """How the postulate was read, for the cycle record ("" when nothing was assumed)."""
        if self.source == "oracle":
            return "oracle postulate (the true object; measurement only)"
        if self.vertical_only:
            return "pose assumed upright, size known along the vertical only"
        return "" if self.pose_known else "pose assumed upright"


def read_postulate(shape: Mapping[str, Any]) -> Postulate | None:
    """The postulate's object (``object`` when present, else the upright one), or None when
    neither is known; a :class:`ValidationError` naming the field of an invalid ``object``."""
    obj = shape.get("object")
    if obj is not None:
        spec = ObjectSpec.from_dict(obj, prefix="shape.object")
        return Postulate(spec, bool(shape.get("pose_known", True)), False)
    g, centre = shape.get("grasp_radius"), shape.get("centre")
    if g is None or centre is None:
        return None
    g = float(g)  # an older postulate: an upright cube or ball of its vertical half-extent
    if str(shape.get("class")) in ("plane", "box"):
        return Postulate(ObjectSpec("box", {"size": (2.0 * g, 2.0 * g, 2.0 * g)}, tuple(centre)), False, True)
    return Postulate(ObjectSpec("sphere", {"radius": g}, tuple(centre)), False, True)
