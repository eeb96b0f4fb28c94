"""The search stage's behaviour (paper §4): a seeded search of a bounded workspace.

Each move sweeps the next column of a coverage lattice in a seeded space-filling order
(:mod:`eos_svc.world.coverage`, which states what the search is sure to find) until the object
is *located* (within ``WorldParameters.envelope_radius`` of the grasp centre). Any motion agent
(the fingers, the wrist) can make a search move. On a table the first move rolls the hand a
quarter turn about its approach (:func:`roll_for_table`) so its grasp centre sweeps low enough.
"""

from __future__ import annotations

import math

from eos_svc.agent import ActionResult, Outcome
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys
from eos_svc.world.coverage import column_counts


def search_rating(board: Board) -> float:
    """Opportunistic sub-rating of a search move: 1 until the object is located."""
    return 0.0 if board.get(keys.LOCATED) else 1.0


def roll_for_table(world: HandDriver) -> bool:
    """Roll the hand a quarter turn about its approach (wrist roll π/2) if it stays clear; whether it did."""
    hand = world.hand
    q = world.joint_positions()
    roll = hand.wrist_q_index[3]
    before = float(q[roll])
    q[roll] = min(max(0.5 * math.pi, float(hand.lower[roll])), float(hand.upper[roll]))
    world.move_joints(q)
    if world.hand_clear(world.params.clearance):
        return True
    q[roll] = before
    world.move_joints(q)
    return False


def search_move(world: HandDriver, board: Board, who: str) -> ActionResult:
    """Make one search move (on a table, :func:`roll_for_table` first); is the object located now?"""
    if world.located():
        board.set(keys.LOCATED, True)
        board.set(keys.GAP, round(world.object_gap_to_grasp_centre(), 6))
        return ActionResult(Outcome.STAGE_COMPLETE, "object already within the hand's envelope")
    moves = int(board.get(keys.SEARCH_MOVES, 0))
    ny, nz = column_counts(world.params)
    if moves >= 2 * ny * nz:  # every column of the coverage lattice swept twice: give up
        return ActionResult(
            Outcome.FINISHED,
            f"object not located after sweeping every column of the search lattice twice "
            f"({moves} sweeps): it is not where the search can find it",
            succeeded=False,
        )
    rolled = moves == 0 and world.table_height is not None and roll_for_table(world)
    label, moved, blocked = world.search_step()
    board.set(keys.SEARCH_MOVES, moves + 1)
    gap = world.object_gap_to_grasp_centre()
    board.set(keys.GAP, round(gap, 6))
    what = (
        ("rolled the hand a quarter turn over the table, " if rolled else "")
        + (f"{who} moved the hand {moved * 1000:.1f} mm sweeping column {label}")
        + (" (stopped short of a contact)" if blocked else "")
    )
    if world.located():
        board.set(keys.LOCATED, True)
        return ActionResult(Outcome.STAGE_COMPLETE, f"{what}: object located, {gap * 1000:.1f} mm away")
    return ActionResult(Outcome.PROGRESS, f"{what}; object surface {gap * 1000:.1f} mm from the grasp centre")
