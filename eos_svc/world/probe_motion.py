"""EP2's guarded probe: a fingertip moved in a straight line until it touches the object (world, m)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from eos_svc.world.probing import ProbeOutcome, densify

if TYPE_CHECKING:
    from eos_svc.world.world import GraspWorld


def guarded_probe(
    world: GraspWorld,
    finger: str,
    start: np.ndarray,
    direction: np.ndarray,
    travel: float,
    angle: float,
    yaw: float = 0.0,
) -> ProbeOutcome:
    """Move ``finger``'s tip in a straight line from ``start`` along ``direction`` (world,
    m) for at most ``travel`` m, stopping at first touch (EP2's guarded move).

    The hand is placed with its wrist turned by ``yaw`` rad about the vertical, ``finger`` at
    ``angle`` rad and the other fingers open, the tip's centre at ``start`` (backed off along
    ``−direction`` by up to 6 cm when the hand would not be clear there); with a table, a start
    at or under it is blocked and a downward travel stops above it. Conservative advancement:
    each sub-step is at most the tip's and the other geometries' gaps beyond half the contact
    tolerance, so only the tip can touch and it never pushes the object.
    The outcome: touched, missed, or blocked (another part of the hand first, the wrist's limits).
    Counted in ``world.probes``.
    """
    world.probes += 1
    p = world.params
    hand = world.hand
    d = np.asarray(direction, dtype=float)
    d = d / math.sqrt(d.dot(d))  # = d / np.linalg.norm(d) (sqrt of the dot product)
    pose = world.context.probe_pose(finger, angle, yaw)  # wrist rotation (0, 0, yaw), the fingers set
    q = world.state.q
    pose.apply(q)
    world.set_q(q)
    state = world.state
    offset = state.tip_position(finger) - world.wrist_position()
    xyz = world.wrist_xyz_q
    lo, hi = pose.wrist_lo, pose.wrist_hi
    start = np.asarray(start, dtype=float)
    tip_gid = hand.tip_geometry_id(finger)
    others = pose.others
    for back in (0.0, 0.02, 0.04, 0.06):
        wrist = start - back * d - offset
        wx, wy, wz = wrist.tolist()  # np.any(wrist < lo) or np.any(wrist > hi), in floats
        if wx < lo[0] or wy < lo[1] or wz < lo[2] or wx > hi[0] or wy > hi[1] or wz > hi[2]:
            return ProbeOutcome("blocked", finger, why="outside the wrist's workspace")
        q[xyz] = wrist
        world.set_q(q)
        # the hand's exact clearance: the other geometries' minimum (the first sub-step's
        # ``other``) and the tip's gap
        others_gap = world.min_gap(others, math.inf)
        clearance = others_gap if tip_gid is None else min(world.scene.gap(state, tip_gid), others_gap)
        if clearance >= p.clearance:
            travel += back
            break
    else:
        return ProbeOutcome("blocked", finger, why="no clear start")
    if world.table is not None:  # the table: no start under or at it, no travel into it
        table_room = world.table_gap() - p.clearance
        if table_room < 0.0:
            return ProbeOutcome("blocked", finger, why="the hand would be under or at the table")
        if d[2] < 0.0:
            travel = min(travel, table_room / -d[2])
    tol = p.contact_tolerance
    half_tol = 0.5 * tol
    # the wrist's start and the direction as floats: each sub-step's wrist0 + d · travelled
    w0, w1, w2 = q[xyz].tolist()
    d0, d1, d2 = d.tolist()
    i0, i1, i2 = pose.wrist_xyz
    travelled = 0.0
    tip = state.tip_centre_view(finger)  # live view of the tip centre (world)
    free = [tip.copy()]
    other = others_gap - half_tol  # the other geometries' gap at the start pose
    for _ in range(300):
        contact = world.scene.contact(state, finger)
        tip_gap = float(contact.distance)
        if tip_gap <= tol:
            reading = world.sensor.read(state, contact)
            M = world.encoders.tip_frame(state, finger)  # as the joint encoders report it
            normal = -(M.rotation @ reading.normal_tip)
            return ProbeOutcome(
                "touched", finger, centre=M.translation.copy(), normal=normal, travelled=travelled
            )
        if other < 1e-5:
            return ProbeOutcome(
                "blocked",
                finger,
                free=densify(_reported(world, finger, np.array(free))),
                travelled=travelled,
                why="another part of the hand would touch first",
            )
        travelled += min(travel - travelled, tip_gap - half_tol, other)
        q[i0], q[i1], q[i2] = w0 + d0 * travelled, w1 + d1 * travelled, w2 + d2 * travelled
        world.set_q(q)
        free.append(tip.copy())
        if travelled >= travel - 1e-12:
            break
        other = world.min_gap(others, math.inf) - half_tol
    return ProbeOutcome(
        "missed", finger, free=densify(_reported(world, finger, np.array(free))), travelled=travelled
    )


def _reported(world: GraspWorld, finger: str, path: np.ndarray) -> np.ndarray:
    """A probe's true tip-centre path (N, 3) as the hand reports it: shifted by the report's
    error at the probe's end (the finger's joints hold still during a probe, the wrist is known;
    :class:`~eos_svc.world.joint_sensing.JointSensing`). The path itself when exact."""
    if world.encoders.exact:
        return path
    state = world.state
    offset = (
        world.encoders.tip_frame(state, finger).translation
        - state.data.oMf[world.hand.tip_frame_id(finger)].translation
    )
    return path + offset
