"""Cheap lower bounds (pure geometry, no coal query) on the gap between a hand's collision
geometries and an object's bounding ball: where a bound cannot decide, a guarded motion asks
coal (:meth:`eos_svc.world.world.GraspWorld.hand_clear`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

import coal
import numpy as np

#: kinds of lower bound of a hand geometry (see shape_bound)
SPHERE, BOX, SEGMENT = 0, 1, 2
#: subtracted from every lower bound (m): covers the round-off of the bound and of coal's
#: distance, so a bound never exceeds the exact gap coal would return
BOUND_MARGIN = 1e-7


def shape_bound(geometry: Any) -> tuple[int, Any, Any, float]:
    """How to bound the gap between a hand geometry and a ball (the object's bounding ball)
    from below, from the ball centre's position in the geometry's frame: the distance to the
    geometry's primitive less the ball's radius — ``(BOX, half sides, None, r)`` for a box,
    ``(SEGMENT, radius, half length, r)`` for a cylinder or capsule along local z (the
    cylinder lies inside that capsule), for a sphere ``(SPHERE, radius, None, r)`` and for
    any other shape ``(SPHERE, r, AABB centre or None, r)``, with ``r`` the radius of the
    primitive's local AABB ball (about its centre, the frame's origin for the primitives). The
    box and segment bounds hold while the two are apart; where they may overlap the AABB
    ball's bound holds (for the penetration depth too) and is used instead."""
    geometry.computeLocalAABB()
    ball = float(geometry.aabb_radius)
    if isinstance(geometry, coal.Box):
        return BOX, tuple(float(x) for x in geometry.halfSide), None, ball
    if isinstance(geometry, (coal.Cylinder, coal.Capsule)):
        return SEGMENT, float(geometry.radius), float(geometry.halfLength), ball
    if isinstance(geometry, coal.Sphere):
        return SPHERE, float(geometry.radius), None, ball
    c = tuple(float(x) for x in geometry.aabb_center)
    return SPHERE, ball, (None if c == (0.0, 0.0, 0.0) else c), ball


def hand_bound_table(hand: Any) -> list[tuple[int, Any, Any, float]]:
    """:func:`shape_bound` of every collision geometry of ``hand`` (a
    :class:`~eos_svc.kinematics.HandModel`), in geometry-id order."""
    return [shape_bound(go.geometry) for go in hand.collision_model.geometryObjects]


def ball_gap_lower_bounds(
    table: Sequence[tuple[int, Any, Any, float]],
    views: Sequence[tuple[np.ndarray, np.ndarray]],
    geometry_ids: Iterable[int],
    centre: Sequence[float],
    radius: float,
) -> list[tuple[float, int]]:
    """``(lower bound of the gap, id)`` (m) of every geometry in ``geometry_ids`` to the ball of
    ``radius`` about ``centre`` (world, m): ``table[id]`` is the geometry's :func:`shape_bound`,
    ``views[id]`` its world (translation, rotation). Each bound is at most coal's exact gap
    (tested), so a geometry whose bound reaches a threshold needs no exact query."""
    obj_radius = radius + BOUND_MARGIN
    c = np.asarray(centre, dtype=float)
    bounds = []
    for gid in geometry_ids:
        kind, a, b, ball = table[gid]
        t, R = views[gid]
        p = c - t  # the object's centre from the geometry's origin (world axes)
        px, py, pz = p.tolist()
        if kind == SPHERE:  # a ball of radius a about the local point b (usually none)
            if b is not None:
                px, py, pz = (p - R.dot(b)).tolist()
            lower = math.hypot(px, py, pz) - a
        else:
            lx, ly, lz = p.dot(R).tolist()  # Rᵀ p: in the geometry's frame
            if kind == BOX:  # half sides a
                ax, ay, az = a
                lower = math.hypot(max(abs(lx) - ax, 0.0), max(abs(ly) - ay, 0.0), max(abs(lz) - az, 0.0))
            else:  # SEGMENT: radius a about the local z segment of half length b
                lower = math.hypot(lx, ly, max(abs(lz) - b, 0.0)) - a
            if lower <= obj_radius:
                # they may overlap, where this bound does not hold (the centre may lie inside the
                # primitive): the bound of the primitive's local AABB ball (radius ``ball``) does
                lower = math.hypot(px, py, pz) - ball
        bounds.append((lower - obj_radius, gid))
    return bounds
