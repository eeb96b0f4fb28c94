"""Cheap lower bounds on the gap between a hand's collision geometries and an object's
bounding ball (pure geometry, no coal query): the distance from the ball's centre to each
geometry's primitive (box, segment of a cylinder or capsule, sphere) less the ball's radius.
A guarded motion asks coal for an exact gap only where a bound cannot decide (see
:meth:`eos_svc.world.world.GraspWorld.hand_clear`)."""

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
    :class:`~eos_svc.kinematics.HandModel`), in geometry-id order (≈ 30 µs for hand3x3; a
    plan's world takes it from its hand's context)."""
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
    ``views[id]`` its world (translation, rotation). Each bound is at most the exact gap coal
    would return (tested against coal), so a geometry whose bound reaches a threshold needs no
    exact query."""
    ox, oy, oz = centre
    obj_radius = radius + BOUND_MARGIN
    bounds = []
    for gid in geometry_ids:
        kind, a, b, ball = table[gid]
        t, R = views[gid]
        tx, ty, tz = t.tolist()
        px, py, pz = ox - tx, oy - ty, oz - tz  # object centre relative to the geometry
        if kind == SPHERE:  # a ball of radius a about the local point b (usually 0)
            if b is not None:
                (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
                bx, by, bz = b
                px -= r00 * bx + r01 * by + r02 * bz
                py -= r10 * bx + r11 * by + r12 * bz
                pz -= r20 * bx + r21 * by + r22 * bz
            lower = math.sqrt(px * px + py * py + pz * pz) - a
        else:
            (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
            # the object centre in the geometry's frame
            lx = r00 * px + r10 * py + r20 * pz
            ly = r01 * px + r11 * py + r21 * pz
            lz = r02 * px + r12 * py + r22 * pz
            if kind == BOX:  # half sides a
                hx, hy, hz = a
                dx = abs(lx) - hx
                dy = abs(ly) - hy
                dz = abs(lz) - hz
                dx = dx if dx > 0.0 else 0.0
                dy = dy if dy > 0.0 else 0.0
                dz = dz if dz > 0.0 else 0.0
                lower = math.sqrt(dx * dx + dy * dy + dz * dz)
            else:  # SEGMENT: radius a about the local z segment of half length b
                dz = abs(lz) - b
                dz = dz if dz > 0.0 else 0.0
                lower = math.sqrt(lx * lx + ly * ly + dz * dz) - a
            if lower <= obj_radius:
                # they may overlap, and this bound does not hold for a penetration
                # depth (the object's centre may lie inside the primitive): the balls'
                # bound (the primitive's local AABB ball, radius ``ball``) does
                lower = math.sqrt(px * px + py * py + pz * pz) - ball
        bounds.append((lower - obj_radius, gid))
    return bounds
