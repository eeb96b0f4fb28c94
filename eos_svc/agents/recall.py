"""recall: tries the grasp remembered for objects like this one (the learned sub-rating, paper §7).

Its learned sub-rating is the smoothed success rate of the remembered grasp of the postulated
class and size band (default and opportunistic 0). Its one action pre-shapes the hand: the
wrist where it stood relative to the centre, each finger two closing steps short of its
remembered angle.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import GRASP, GraspAgent
from eos_svc.agents.memory import GraspMemory, RememberedGrasp
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys


class RecallAgent(GraspAgent):
    """Pre-shapes the hand to a remembered grasp."""

    reads = frozenset({keys.SHAPE, keys.D_OVER_H, keys.RECALLED})
    writes = frozenset({keys.RECALLED, keys.AT_TARGET, keys.FINGER_STATE})

    def __init__(self, world: HandDriver, memory: GraspMemory) -> None:
        super().__init__("recall", (GRASP,), 0.0, world)
        self.memory = memory
        self._cache: tuple[object, RememberedGrasp | None] = (None, None)

    def remembered(self, board: Board) -> RememberedGrasp | None:
        """The memory's grasp for the postulated class and d/h band (looked up once per postulate)."""
        shape = board.get(keys.SHAPE)
        dh = board.get(keys.D_OVER_H)
        if shape is None or dh is None:
            return None
        key = (shape["class"], dh)
        if self._cache[0] != key:
            self._cache = (key, self.memory.recall(shape["class"], float(dh)))
        return self._cache[1]

    def learned_rating(self, board: Board, ctx: CycleContext) -> float:
        if keys.RECALLED in board:
            return 0.0
        entry = self.remembered(board)
        return 0.0 if entry is None else entry.reliability

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        entry = self.remembered(board)
        if entry is None:
            return ActionResult(Outcome.CANNOT_ACT, "nothing remembered for objects like this one")
        world = self.world
        hand = world.hand
        shape = board[keys.SHAPE]
        q = world.joint_positions()
        q[hand.wrist_q_index[:3]] = np.asarray(shape["centre"]) + np.asarray(entry.offset)
        # the wrist keeps the orientation grasp_points turned it to (the remembered offset is
        # the wrist's position relative to the centre at that orientation)
        margin = 2.0 * world.params.finger_step
        for attempt in range(4):
            for finger in hand.finger_names:
                idx = hand.finger_q_index(finger)
                q[idx] = np.maximum(hand.lower[idx], entry.angles.get(finger, 0.0) - margin * (attempt + 1))
            q = np.clip(q, hand.lower, hand.upper)
            world.move_joints(q)
            if world.hand_clear(0.5 * world.params.contact_tolerance):
                break
        else:
            return ActionResult(Outcome.CANNOT_ACT, f"the grasp remembered for {entry.key} collides here")
        board.set(keys.RECALLED, entry.key)
        board.set(keys.AT_TARGET, True)
        board.set(keys.FINGER_STATE, dict.fromkeys(hand.finger_names, "closing"))
        return ActionResult(
            Outcome.PROGRESS,
            f"pre-shaped the hand to the grasp remembered for {entry.key} "
            f"({entry.successes} of {entry.tries} worked)",
            ratings=dict.fromkeys(hand.finger_names, 1.0),
        )
