"""wrist: search moves, then brings the hand closer to its grasp position.

Grasping (paper §2.1, §5): each action moves the hand ``WorldParameters.wrist_step`` along the
grasp's approach, stopping short of contact; stopped short, it re-predicts on the postulated
object where each fingertip lands from here and makes those the chosen contacts.
Opportunistic sub-rating: 1 − d/h while the hand is not there and no tip touches, never below
:data:`WRIST_FLOOR` (for d/h ≥ 1 the wrist alone can still bring the hand to its grasp).
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import GRASP, SEARCH, GraspAgent
from eos_svc.agents.search import search_move, search_rating
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.grasp.landing import sweep_landings
from eos_svc.grasp.postulate import make_object
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec

#: the wrist's least opportunistic sub-rating while the hand is short of its grasp position
WRIST_FLOOR = 0.05


class WristAgent(GraspAgent):
    """Moves the whole hand."""

    reads = frozenset(
        {keys.LOCATED, keys.SEARCH_MOVES, keys.TARGET, keys.AT_TARGET, keys.FINGER_STATE, keys.D_OVER_H}
    )
    writes = frozenset(
        {keys.LOCATED, keys.GAP, keys.SEARCH_MOVES, keys.TARGET, keys.AT_TARGET, keys.WRIST_LEFT}
    )

    def __init__(self, default: float, world: HandDriver) -> None:
        super().__init__("wrist", (SEARCH, GRASP), default, world)

    @staticmethod
    def any_touching(board: Board) -> bool:
        """Whether some fingertip already touches (the hand must not move on)."""
        return any(s == "touching" for s in board.get(keys.FINGER_STATE, {}).values())

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        if ctx.stage == SEARCH:
            return search_rating(board)
        if keys.TARGET not in board or board.get(keys.AT_TARGET) or self.any_touching(board):
            return 0.0
        return max(WRIST_FLOOR, 1.0 - self.d_over_h(board))

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        if ctx.stage == SEARCH:
            return search_move(self.world, board, self.name)
        target = board.get(keys.TARGET)
        if target is None:
            return ActionResult(Outcome.CANNOT_ACT, "no grasp target on the board: nowhere to go")
        if board.get(keys.AT_TARGET):
            # chosen on its default alone (it has not acted in this stage yet): nothing to move
            return ActionResult(Outcome.PROGRESS, "the hand is already at its grasp position: it holds")
        if self.any_touching(board):
            return ActionResult(Outcome.CANNOT_ACT, "a fingertip touches the object: the hand must stay")
        move = self.world.step_wrist_toward(np.asarray(target["wrist"]), self.world.params.wrist_step)
        left, blocked = move.left, move.blocked
        board.set(keys.WRIST_LEFT, round(left, 6))
        if left < 1e-6 or blocked:
            board.set(keys.AT_TARGET, True)
        why = ""
        if blocked:
            why = " (stopped short of a contact; " + self.repredict(board, target) + ")"
        return ActionResult(
            Outcome.PROGRESS, f"hand moved closer; {left * 1000:.1f} mm to the grasp position{why}"
        )

    def repredict(self, board: Board, target: dict) -> str:
        """Make the fingers' chosen contacts those they land on from the hand's pose now (on
        the postulated object); returns what was done, in words."""
        world = self.world
        hand = world.hand
        spec = target.get("object")
        if spec is None:
            return "no postulated object to re-predict the contacts on"
        obj = make_object(ObjectSpec.from_dict(spec))
        palm_translation, palm_rotation = world.palm_views()
        radii = {f: hand.tip_radius(f) for f in hand.finger_names}
        found = sweep_landings(obj, world.sweeps, radii, palm_rotation, palm_translation)
        contacts = dict(target.get("contacts", {}))
        for finger, landings in found.items():
            hit = landings.landing(world.sweeps[finger].index_at(world.finger_angle(finger)))
            if hit is not None:
                contacts[finger] = hit.to_dict()
        board.set(keys.TARGET, {**target, "contacts": contacts, "repredicted": True})
        return "contacts re-predicted from here"
