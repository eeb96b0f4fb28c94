"""wrist: search moves, then brings the hand closer to its grasp position.

Grasping (paper §2.1, §5): each action moves the hand a little closer
(``WorldParameters.wrist_step``) from the pre-grasp stand-off toward the grasp
position chosen by grasp_points, stopping short of any contact. Opportunistic
sub-rating: 1 − d/h while the hand is not there yet and no fingertip touches.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents import keys
from eos_svc.agents.base import GRASP, SEARCH, GraspAgent
from eos_svc.agents.search import search_move, search_rating
from eos_svc.agents.world import GraspWorld
from eos_svc.board import Board


class WristAgent(GraspAgent):
    """Moves the whole hand."""

    def __init__(self, default: float, world: GraspWorld) -> None:
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
        return max(0.0, 1.0 - self.d_over_h(board))

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
        left, blocked = self.world.step_wrist_toward(
            np.asarray(target["wrist"]), self.world.params.wrist_step
        )
        board.set(keys.WRIST_LEFT, round(left, 6))
        if left < 1e-6 or blocked:
            board.set(keys.AT_TARGET, True)
        why = " (stopped short of a contact)" if blocked else ""
        return ActionResult(
            Outcome.PROGRESS, f"hand moved closer; {left * 1000:.1f} mm to the grasp position{why}"
        )
