"""Whether a candidate grasp can be reached without collision on the postulated object: coal
distances at the pre-grasp, along the straight approach (fingers open) and while the fingers
close (only the tips may touch). SI units.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from eos_svc.grasp.candidate import GraspCandidate
from eos_svc.grasp.sweeps import FingerSweep
from eos_svc.kinematics import HandModel, Scene
from eos_svc.kinematics.gap_bounds import ball_gap_lower_bounds, hand_bound_table
from eos_svc.objects import SurfaceObject
from eos_svc.world.table import hand_table_gap, table_shape

if TYPE_CHECKING:
    from eos_svc.world.parameters import WorldParameters

#: approach-path samples checked for collisions between pre-grasp and grasp
APPROACH_SAMPLES = 4
#: stand-offs tried for the pre-grasp: ``approach_distance``, then 1 cm more each time
PREGRASP_TRIES = 4


class HandClearance:
    """Collision checks of one hand (its closing sweeps: the open hand at their first samples)
    against one postulated object, with the world constants' stand-off, clearance and contact
    tolerance; ``table_height`` (world z, m): no hand geometry may come nearer the table than
    each check's threshold."""

    def __init__(
        self,
        hand: HandModel,
        sweeps: dict[str, FingerSweep],
        params: WorldParameters,
        obj: SurfaceObject,
        table_height: float | None = None,
    ) -> None:
        self.hand, self.sweeps, self.params, self.obj = hand, sweeps, params, obj
        self.table = None if table_height is None else table_shape(table_height)
        self.scene = Scene(hand, obj)
        self.state = hand.state(hand.neutral())
        tips = {hand.tip_geometry_id(f) for f in hand.finger_names}
        self.geometries = list(range(hand.collision_model.ngeoms))
        self.body_geometries = [g for g in self.geometries if g not in tips]
        # per collision geometry, how to bound its gap to the object's bounding ball from below
        self._bound_table = hand_bound_table(hand)
        widx = hand.wrist_q_index
        self._xyz_lo, self._xyz_hi = hand.lower[widx[:3]], hand.upper[widx[:3]]

    def configuration(
        self, rpy: tuple[float, float, float], wrist: np.ndarray, angles: dict[str, float] | None = None
    ) -> np.ndarray:
        """The hand with its palm at ``wrist`` (m) turned by ``rpy`` (rad), each finger at
        ``angles`` (rad; open when None), within the joint limits."""
        hand = self.hand
        widx = hand.wrist_q_index
        q = hand.neutral()
        q[widx[:3]] = wrist
        q[widx[3:6]] = rpy
        for finger in hand.finger_names:
            q[hand.finger_q_index(finger)] = (
                self.sweeps[finger].angles[0] if angles is None else angles[finger]
            )
        out: np.ndarray = np.clip(q, hand.lower, hand.upper)
        return out

    def clear(self, q: np.ndarray, threshold: float, skip_tips: bool) -> bool:
        """Whether every collision geometry of the hand at ``q`` (the fingertips skipped when
        asked) is at least ``threshold`` m from the object (coal where a lower bound cannot tell)."""
        state = self.state
        state.update(q)
        state.geometry_data  # noqa: B018 -- brings the geometry placements up to date
        bounds = ball_gap_lower_bounds(
            self._bound_table,
            state.geometry_views(),
            self.body_geometries if skip_tips else self.geometries,
            self.obj.placement.translation.tolist(),
            0.5 * float(self.obj.diameter),
        )
        if self.table is not None and hand_table_gap(state, self.table) < max(threshold, 0.0):
            return False  # the table: no part of the hand, fingertips included, may touch it
        return all(lower >= threshold or self.scene.gap(state, gid) >= threshold for lower, gid in bounds)

    def pregrasp(self, c: GraspCandidate) -> tuple[np.ndarray, float] | None:
        """The collision-free pre-grasp wrist position (world, m) before ``c`` along its
        approach, and its stand-off (m): ``approach_distance``, lengthened by 1 cm up to
        ``PREGRASP_TRIES`` times if needed; None when none is clear."""
        for k in range(PREGRASP_TRIES):
            stand_off = self.params.approach_distance + 0.01 * k
            pre = c.wrist - stand_off * c.approach
            inside = np.all(pre >= self._xyz_lo) and np.all(pre <= self._xyz_hi)
            if inside and self.clear(self.configuration(c.wrist_rpy, pre), self.params.clearance, False):
                return pre, stand_off
        return None

    def collision(self, c: GraspCandidate) -> str | None:
        """Why reaching ``c`` collides, in words (None: it does not): no clear pre-grasp, the
        open hand's approach from it, or the closing fingers (half-way and at their landings)
        touching with more than their tips."""
        pre = self.pregrasp(c)
        if pre is None:
            return "no collision-free pre-grasp"
        start = pre[0]
        for s in np.linspace(0.0, 1.0, APPROACH_SAMPLES + 1)[1:]:
            q = self.configuration(c.wrist_rpy, start + s * (c.wrist - start))
            if not self.clear(q, 0.5 * self.params.contact_tolerance, False):
                return "the approach collides"
        for fraction in (0.5, 1.0):
            angles = {}
            for finger, hit in c.landings.items():
                lo = float(self.sweeps[finger].angles[0])
                angles[finger] = lo + fraction * (hit.angle - lo)
            if not self.clear(self.configuration(c.wrist_rpy, c.wrist, angles), 0.0, True):
                return "a link or the palm touches before the fingertips"
        return None
