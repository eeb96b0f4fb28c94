"""finger1, finger2, finger3: search moves, then close their finger in the grasping stage.

One agent per finger of the hand, named after it (hand3x3: finger1, finger2, finger3; the
Allegro: index, middle, ring, thumb).

Grasping (paper §2.1, §5): a finger agent closes its finger by a small amount
(every joint by ``WorldParameters.finger_step``), stopping at first touch. Its
opportunistic sub-rating is d/h (estimated object diameter over hand height)
while its fingertip is free and the object is *within reach* — the finger's
closing sweep, from its current angle, passes within the estimated object
radius plus the fingertip radius of the estimated centre. Out of reach, the
agent does not know what to do: closing would miss the object, so if it is
chosen it reports ``CANNOT_ACT`` (paper §5: at the start of grasping with the
opportunistic weight alone, finger1 is chosen and does not know where to begin).
"""

from __future__ import annotations

from bisect import bisect_left

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents import keys
from eos_svc.agents.base import GRASP, SEARCH, GraspAgent
from eos_svc.agents.search import search_move, search_rating
from eos_svc.agents.world import GraspWorld
from eos_svc.board import Board

#: finger states that end a finger's part in the grasp
DONE_STATES = frozenset({"touching", "missed", "link"})


class FingerAgent(GraspAgent):
    """Closes one finger; makes search moves in the search stage."""

    def __init__(self, finger: str, default: float, world: GraspWorld) -> None:
        super().__init__(finger, (SEARCH, GRASP), default, world)
        self.finger = finger
        self._reach_radius_extra = world.hand.tip_radius(finger)
        sweep = world.sweeps[finger]
        self._sweep = sweep
        self._sweep_angles = sweep.angles.tolist()
        # (wrist position, shape entry) -> last sweep sample within reach (see FingerSweep.last_within)
        self._reach_memo: tuple[object, object, int] = (None, None, -1)

    def finger_state(self, board: Board) -> str:
        """This finger's state on the board ("open" before grasping starts)."""
        return str(board.get(keys.FINGER_STATE, {}).get(self.finger, "open"))

    def in_reach(self, board: Board) -> bool:
        """Whether closing from the current angle would reach the estimated object."""
        shape = board.get(keys.SHAPE)
        if not shape or keys.TARGET not in board:
            return False
        world = self.world
        wrist = world.wrist_xyz()
        memo_wrist, memo_shape, last = self._reach_memo
        if memo_shape is not shape or memo_wrist != wrist:
            centre_palm = np.asarray(shape["centre"]) - world.wrist_position()
            radius = float(shape["grasp_radius"]) + self._reach_radius_extra
            last = self._sweep.last_within(centre_palm, radius)
            self._reach_memo = (wrist, shape, last)
        if last < 0:
            return False
        # FingerSweep.index_at (np.searchsorted, side left) on the angles as a list
        return bisect_left(self._sweep_angles, world.finger_angle(self.finger) - 1e-12) <= last

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        if ctx.stage == SEARCH:
            return search_rating(board)
        if self.finger_state(board) in DONE_STATES or not self.in_reach(board):
            return 0.0
        return min(1.0, self.d_over_h(board))

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        if ctx.stage == SEARCH:
            return search_move(self.world, board, self.name)
        state = self.finger_state(board)
        if keys.TARGET not in board:
            return ActionResult(Outcome.CANNOT_ACT, "no grasp target on the board: nothing to close on")
        if state in DONE_STATES:
            return ActionResult(Outcome.CANNOT_ACT, f"{self.finger} is already done ({state})")
        if not self.in_reach(board):
            return ActionResult(
                Outcome.CANNOT_ACT,
                f"the object is out of reach of {self.finger}'s sweep: closing would miss it "
                "(the hand must come closer first)",
            )
        event, angle = self.world.close_finger_step(self.finger, self.world.params.finger_step)
        new_state = {"moved": "closing", "touched": "touching", "limit": "missed", "link": "link"}[event]
        states = dict(board.get(keys.FINGER_STATE, {}))
        states[self.finger] = new_state
        board.set(keys.FINGER_STATE, states)
        angles = dict(board.get(keys.FINGER_ANGLE, {}))
        angles[self.finger] = round(angle, 6)
        board.set(keys.FINGER_ANGLE, angles)
        words = {
            "moved": "closed",
            "touched": "closed and touched the object",
            "limit": "closed to its joint limit without touching: missed",
            "link": "closed until a link (not the fingertip) touched the object",
        }[event]
        return ActionResult(Outcome.PROGRESS, f"{self.finger} {words} (joints at {angle:.3f} rad)")
