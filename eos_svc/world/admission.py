"""Admission: refuse, before any planning, the objects the grasp planner cannot plan for.

:func:`check_plannable` runs first in :func:`eos_svc.agents.plan`, ``eos plan`` and the
service, so a request the planner would refuse is refused at the edge with a
:class:`~eos_svc.errors.ValidationError` naming the field. Real geometric queries on the hand's
model: **reach** (the search's swept grasp-centre box comes within ``envelope_radius`` of the
object), **overlap** (the object clears the start pose by ``clearance``), **size** (it fits
between the fingertips along some grip: :func:`~eos_svc.world.fingertip_fit.fit_refusal`) and,
with a table, **on the table** (:func:`check_on_table`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import coal
import numpy as np

from eos_svc.errors import ValidationError
from eos_svc.grasp.postulate import make_object
from eos_svc.kinematics import HandModel
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.world.coverage import findable
from eos_svc.world.fingertip_fit import fit_refusal
from eos_svc.world.hand_context import HandContext, context_for, default_context, hand_span
from eos_svc.world.parameters import WorldParameters

__all__ = [
    "check_default",
    "check_plannable",
    "default_check",
    "hand_span",
    "plannable_verdict",
]


def _distance(
    a: coal.ShapeBase, ta: coal.Transform3s, b: coal.ShapeBase, tb: coal.Transform3s
) -> coal.DistanceResult:
    """coal's signed distance between two placed shapes (a fresh result: callers run in parallel)."""
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    res = coal.DistanceResult()
    coal.distance(a, ta, b, tb, req, res)
    return res


def check_plannable(
    request: PlanRequest,
    hand: HandModel | None = None,
    params: WorldParameters | None = None,
    *,
    context: HandContext | None = None,
) -> None:
    """Raise :class:`ValidationError` (naming ``object.position``, the size field or the table's)
    if the planner cannot plan ``request`` with ``context`` (default: ``context_for(hand)``; give
    it when planning many requests with another hand), ``params`` overriding its own."""
    context = context_for(hand) if context is None else context
    verdict = plannable_verdict(request.obj, context if params is None else context.with_params(params))
    if verdict:
        field, reason = verdict
        raise ValidationError(field, reason)
    if request.table is not None:
        check_on_table(request.obj, request.table.height)


#: how far an object may reach into the table (m): resting on it, within rounding
TABLE_TOLERANCE = 1e-3


def check_on_table(spec: ObjectSpec, height: float) -> None:
    """Refuse an object whose lowest point is below the table's top ``height`` (world z, m) by more
    than :data:`TABLE_TOLERANCE`."""
    obj = make_object(spec)
    lowest = float(obj.centre[2] - obj.depth_below_centre())
    if lowest < height - TABLE_TOLERANCE:
        raise ValidationError(
            "object.position[2]",
            f"the object reaches {1000 * (height - lowest):.1f} mm into the table (its lowest point "
            f"z = {lowest:.4f} m, the table's top z = {height:.4f} m): place it on the table",
        )


def check_default(request: PlanRequest) -> None:
    """:func:`check_plannable` on the default hand (hand3x3) and its parameters."""
    check_plannable(request, context=default_context())


def default_check() -> Callable[[PlanRequest], None]:
    """The admission check of the default hand: :func:`check_default` (one function, so a caller
    can tell it from another check by identity)."""
    return check_default


def plannable_verdict(spec: ObjectSpec, context: HandContext) -> tuple[str, ...]:
    """``()`` when the planner can plan ``spec``, else the refusal's ``(field, reason)``."""
    try:
        _check_object(spec, context)
    except ValidationError as exc:
        return exc.field, exc.reason
    return ()


def _check_object(spec: ObjectSpec, context: HandContext) -> None:
    """The three tests of the module doc; raises the refusal."""
    params, reach_ahead = context.params, context.forward_reach

    too_large = fit_refusal(spec, context.opening, params.clearance)
    if too_large is not None:
        raise ValidationError(*too_large)

    # Reach. The centre lies in the object, so the object's gap to the swept box is at most the
    # centre's distance to it and at least that minus the bounding radius: coal only in between.
    obj = make_object(spec)
    centre = spec.position
    radius = 0.5 * obj.diameter
    # the box the grasp centre sweeps during the search (world, m)
    lo = [a + b for a, b in zip(params.search_box_lo, params.grasp_centre, strict=True)]
    hi = [a + b for a, b in zip(params.search_box_hi, params.grasp_centre, strict=True)]
    outside = [max(lo[i] - centre[i], 0.0, centre[i] - hi[i]) for i in range(3)]
    centre_gap = math.sqrt(sum(d * d for d in outside))
    shape = obj.geometry
    tf_obj = coal.Transform3s(np.array(obj.placement.rotation), np.array(obj.placement.translation))
    if centre_gap > params.envelope_radius:
        gap, axis = centre_gap - radius, max(range(3), key=outside.__getitem__)
        if gap <= params.envelope_radius:  # undecided by the bounds: the exact distance
            res = _distance(
                shape,
                tf_obj,
                coal.Box(*(np.subtract(hi, lo))),
                coal.Transform3s(np.eye(3), 0.5 * np.add(lo, hi)),
            )
            gap = float(res.min_distance)
            separation = np.abs(np.asarray(res.getNearestPoint1()) - np.asarray(res.getNearestPoint2()))
            axis = int(np.argmax(separation))
        if gap > params.envelope_radius:
            pos = ", ".join(f"{v:.3f}" for v in centre)
            raise ValidationError(
                f"object.position[{axis}]",  # the axis it is farthest out along
                f"out of reach: the object at [{pos}] m stays ≥ {gap:.3f} m from every grasp-centre "
                f"position the search can reach ([{lo[0]:.3f}, {hi[0]:.3f}] x [{lo[1]:.3f}, {hi[1]:.3f}] "
                f"x [{lo[2]:.3f}, {hi[2]:.3f}] m), more than the envelope radius {params.envelope_radius} m",
            )

    # Overlap: only the hand geometries whose bounding spheres come within clearance of the object's.
    cx, cy, cz = centre
    reach = radius + params.clearance
    for g in context.neutral_geometries:
        gx, gy, gz = g.centre
        if math.sqrt((gx - cx) ** 2 + (gy - cy) ** 2 + (gz - cz) ** 2) - g.radius > reach:
            continue  # the bounding spheres are apart (plain floats: 13 of them cost less than numpy)
        d = float(_distance(shape, tf_obj, g.shape, g.transform).min_distance)
        if d < params.clearance:
            raise ValidationError(
                "object.position",
                f"the object overlaps the hand at its start configuration ({g.name}: "
                f"distance {d * 1000:.1f} mm < clearance {params.clearance * 1000:.1f} mm); "
                "place it in front of the open hand",
            )

    # Findable: the search sweeps a lattice of columns and guarantees to locate only objects that
    # come near a sweep line and lie ahead of the fingers' reach from the rear of the box.
    rear_limit = params.search_box_lo[0] + reach_ahead + params.clearance
    if not findable(obj, params, reach_ahead):
        pos = ", ".join(f"{v:.3f}" for v in centre)
        raise ValidationError(
            "object.position",
            f"the search cannot be sure to find the object at [{pos}] m: it must come within "
            f"{params.envelope_radius} m of a sweep line and lie wholly ahead of x = "
            f"{rear_limit:.3f} m "
            "(what the fingers reach from the rear of the search box)",
        )
