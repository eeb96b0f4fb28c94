"""The support surface under the object: the hand's gap to it and the motions it forbids.

The table is the half-space z ≤ ``height`` (world, m), a coal ``Halfspace``; the hand's gap to
it is the least coal distance of any hand collision geometry to it (exact, negative when a
geometry dips into it). A wrist *translation* moves every hand geometry alike, so along a
straight wrist move the gap changes by exactly the move's vertical component: the guarded
moves clamp their targets with that, without sampling the path.
"""

from __future__ import annotations

import coal
import numpy as np

from eos_svc.kinematics import HandState

_UP = np.array([0.0, 0.0, 1.0])


def table_shape(height: float) -> coal.Halfspace:
    """The table as coal's half-space z ≤ ``height``."""
    return coal.Halfspace(_UP, float(height))


def hand_table_gap(state: HandState, table: coal.Halfspace, geometry_ids: list[int] | None = None) -> float:
    """The least distance (m) between the hand's collision geometries (``geometry_ids``, default
    all) at ``state`` and the table (negative: a geometry is in it)."""
    model = state.hand.collision_model
    placements = state.geometry_data.oMg
    req, res = coal.DistanceRequest(), coal.DistanceResult()
    req.enable_signed_distance = True
    identity = coal.Transform3s()
    best = np.inf
    for gid in range(model.ngeoms) if geometry_ids is None else geometry_ids:
        res.clear()
        coal.distance(model.geometryObjects[gid].geometry, placements[gid], table, identity, req, res)
        best = min(best, float(res.min_distance))
    return best


def clamp_above(
    start: np.ndarray, target: np.ndarray, gap: float, clearance: float
) -> tuple[np.ndarray, bool]:
    """``target`` for a straight wrist translation from ``start`` (world, m), shortened along the
    line so the hand's table gap (``gap`` now) stays ≥ ``clearance``; whether it was shortened."""
    start, target = np.asarray(start, dtype=float), np.asarray(target, dtype=float)
    drop = float(start[2] - target[2])
    room = gap - clearance
    if drop <= max(room, 0.0):
        return target, False
    fraction = max(room, 0.0) / drop
    return start + fraction * (target - start), True
