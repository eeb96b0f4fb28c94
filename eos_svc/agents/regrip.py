"""Regrip: a grip on an approximate postulate that the fingertips feel is not in force closure
is let go and planned again, with what the grip felt.

The convex hull of the touches (:mod:`eos_svc.shape.hull`) is a guess between the touches:
a fingertip may land elsewhere on the real object than predicted, with another normal, or a
link may touch first. The hand feels it: each touching fingertip's tactile reading is a
contact point and an outward normal. When those contacts are not in force closure under the
board's μ (:func:`~eos_svc.grasp.quality.grasp_quality`: force closure does not depend on the
torque reference, so the postulate's uncertain centre of mass does not enter) — or a finger
found no contact — the end agent, before judging, asks :class:`Regrip` to try again (at most
:data:`MAX_REGRIPS` times): the felt contacts join EP2's touches (they are measurements of the
surface like any probe's), the hull is made again from all the touches, grasp synthesis runs on
it with the touches' support (:mod:`eos_svc.grasp.support`), leaving out the grasps already
tried, and the hand — fingers opened where they are, then placed open at the new grasp's
pre-grasp, as grasp_points places it — gets the new target. A postulated primitive is never
regripped: its plans stay as they were.

SI units throughout: metres, radians.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agents.ep2 import touch_entry
from eos_svc.agents.grasp_points import GraspPointsAgent
from eos_svc.agents.post_shape import touches_from
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.grasp.candidate import GraspCandidate
from eos_svc.grasp.frames import rotation_from_rpy
from eos_svc.grasp.postulate import Postulate
from eos_svc.grasp.quality import DEFAULT_EDGES, grasp_quality
from eos_svc.schema import keys
from eos_svc.schema.request import DEFAULT_FRICTION, ObjectSpec
from eos_svc.shape.hull import hull_postulate

#: how many times one plan lets go and grips again
MAX_REGRIPS = 2
#: a palm turned within this angle (deg) of a tried grasp's grips across the same axis: left out
SAME_TURN_DEG = 20.0
#: what the regrip reads and writes on the board (the end agent declares them)
READS = frozenset(
    {keys.SHAPE, keys.TARGET, keys.FINGER_STATE, keys.EP1_CONTACT, keys.EP2_TOUCHES, keys.EP2_FREE}
)
WRITES = frozenset({keys.TARGET, keys.FINGER_STATE, keys.AT_TARGET, keys.WRIST_LEFT, keys.EP2_TOUCHES})


class Regrip:
    """Lets go of a grip the fingertips feel is not in force closure and places the hand for
    another (see the module doc). One per plan: it counts its attempts and the grasps tried."""

    def __init__(self, world: HandDriver) -> None:
        self.world = world
        self.placer = GraspPointsAgent(0.0, world)  # grasp synthesis and placement, as grasp_points does them
        self.attempts = 0
        self.tried: list[np.ndarray] = []  # the palm rotations of the grasps gripped

    def felt_closure(self, board: Board) -> tuple[bool, list[dict]]:
        """(whether every fingertip touches and their sensed contacts are in force closure, the
        sensed contacts as EP2 touches)."""
        world, hand = self.world, self.world.hand
        states = board.get(keys.FINGER_STATE, {})
        felt = []
        for finger in hand.finger_names:
            reading = world.tactile(finger)
            if states.get(finger) == "touching" and reading.in_contact:
                felt.append(
                    (finger, np.asarray(reading.point, dtype=float), np.asarray(reading.normal, dtype=float))
                )
        mu = float(board.get(keys.FRICTION, DEFAULT_FRICTION))
        closure = False
        if len(felt) == len(hand.finger_names):
            points = np.array([p for _, p, _ in felt])
            normals = np.array([n for _, _, n in felt])
            quality = grasp_quality(
                points, normals, None, mu, DEFAULT_EDGES, None, world.params.contact_patch_radius
            )
            closure = quality.force_closure
        touches = [
            touch_entry(hand, "grip", finger, p + hand.tip_radius(finger) * n, n) for finger, p, n in felt
        ]
        return closure, touches

    def attempt(self, board: Board) -> str | None:
        """Regrip if the grip is on an approximate postulate, felt not in force closure, and
        attempts are left: what was done, in words; None to judge the grip as it is."""
        shape, target = board.get(keys.SHAPE), board.get(keys.TARGET)
        if self.attempts >= MAX_REGRIPS or target is None or not (shape or {}).get("approximate"):
            return None
        closure, felt = self.felt_closure(board)
        if closure:
            return None
        self.attempts += 1
        self.tried.append(rotation_from_rpy(*target["wrist_rpy"]))
        board.set(keys.EP2_TOUCHES, [*board.get(keys.EP2_TOUCHES, []), *felt])
        world = self.world
        hull = hull_postulate(touches_from(board, world), world.table_height)
        if hull is None:
            return None
        postulate = Postulate(ObjectSpec.from_dict(hull.object), True, False)
        grip = world.joint_positions()  # back to it when no other grasp can be placed
        self._open_fingers()
        synthesis = self.placer.synthesis(board, postulate, shape)
        fresh = [c for c in synthesis.candidates() if not self._was_tried(c)]
        placed = self.placer.place_first(board, fresh, synthesis, postulate)
        if placed is None:
            world.move_joints(grip)  # the grip as it was, for the end agent to judge
            return None
        cand, _ = placed
        return (
            f"regrip {self.attempts}: the fingertips felt {len(felt)} of {len(world.hand.finger_names)} "
            "contacts, not in force closure; "
            f"they join the touches, the hull is made again and the hand placed open for grasp "
            f"{cand.label} (ε = {cand.epsilon:.3f}, {cand.angle_deg:.0f}° across the centre)"
        )

    def _open_fingers(self) -> None:
        """Every finger back to the start of its closing sweep, the wrist where it is."""
        world, hand = self.world, self.world.hand
        q = world.joint_positions()
        for finger in hand.finger_names:
            q[hand.finger_q_index(finger)] = world.sweeps[finger].angles[0]
        world.move_joints(q)

    def _was_tried(self, cand: GraspCandidate) -> bool:
        """``cand`` grips as a grasp already tried did (the palm turned alike: the same grasp
        axis and approach, wherever the remade hull puts its centre)."""
        cos_same = 2.0 * np.cos(np.radians(SAME_TURN_DEG)) + 1.0  # trace(R1ᵀ R2) at that angle
        return any(float(np.trace(cand.rotation.T @ R)) > cos_same for R in self.tried)
