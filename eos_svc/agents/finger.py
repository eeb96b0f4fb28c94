"""finger1, finger2, finger3: search moves, then close their finger in the grasping stage.

One agent per finger of the hand, named after it (hand3x3: finger1, finger2, finger3; the
Allegro: index, middle, ring, thumb).

Grasping (paper §2.1, §5): a finger agent closes its finger by a small amount
(every joint by ``WorldParameters.finger_step``), stopping at first touch. Its
opportunistic sub-rating is d/h (estimated object diameter over hand height)
while its fingertip is free and closing from where it is will *land on its
chosen contact*: the finger's closing sweep, from its current angle and the
hand's current pose, first touches the postulated object (grasp_points' target)
within ``WorldParameters.landing_tolerance`` of the contact grasp_points chose
for it (a finger that closed past that contact's angle without touching — the
object is not quite where it was postulated — keeps closing until it touches or
reaches its limit). Otherwise the agent does not know what to do: closing would land
elsewhere — in front of the object's centre while the hand is still on its way,
or not on the object at all — so if it is chosen it reports ``CANNOT_ACT``
(paper §5: at the start of grasping with the opportunistic weight alone,
finger1 is chosen and does not know where to begin).
"""

from __future__ import annotations

from bisect import bisect_left
from operator import itemgetter

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import GRASP, SEARCH, GraspAgent
from eos_svc.agents.search import search_move, search_rating
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.grasp.landing import SweepLandings, rotated_sweep_gaps
from eos_svc.grasp.postulate import make_object
from eos_svc.objects import SurfaceObject
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec

#: finger states that end a finger's part in the grasp
DONE_STATES = frozenset({"touching", "missed", "link"})


class FingerAgent(GraspAgent):
    """Closes one finger; makes search moves in the search stage."""

    reads = frozenset(
        {keys.LOCATED, keys.SEARCH_MOVES, keys.TARGET, keys.FINGER_STATE, keys.FINGER_ANGLE, keys.D_OVER_H}
    )
    writes = frozenset({keys.LOCATED, keys.GAP, keys.SEARCH_MOVES, keys.FINGER_STATE, keys.FINGER_ANGLE})

    def __init__(self, finger: str, default: float, world: HandDriver) -> None:
        super().__init__(finger, (SEARCH, GRASP), default, world)
        self.finger = finger
        self._tip_radius = world.hand.tip_radius(finger)
        self._sweep = world.sweeps[finger]
        self._sweep_angles = self._sweep.angles.tolist()
        # (target entry, its postulated object); (wrist pose, target, the sweep's landings
        # there); per first touching sample, the landing's distance to the chosen contact
        self._object_memo: tuple[object, SurfaceObject | None] = (None, None)
        self._landings_memo: tuple[object, object, SweepLandings | None] = (None, None, None)
        self._miss_memo: dict[int, float] = {}
        self._far_samples: set[tuple[int, float]] = set()  # (first touching sample, tolerance) past the bound
        self._rotated: tuple[bytes, np.ndarray] = (b"", self._sweep.points)
        # the wrist's joint values, as a tuple, from the configuration list
        self._wrist_pose = itemgetter(*(int(i) for i in world.hand.wrist_q_index))

    def finger_state(self, board: Board) -> str:
        """This finger's state on the board ("open" before grasping starts)."""
        return str(board.get(keys.FINGER_STATE, {}).get(self.finger, "open"))

    def _postulated(self, target: dict) -> SurfaceObject | None:
        """The postulated object of ``target`` (built once per target)."""
        if self._object_memo[0] is not target:
            spec = target.get("object")
            obj = None if spec is None else make_object(ObjectSpec.from_dict(spec))
            self._object_memo = (target, obj)
        return self._object_memo[1]

    def landing_miss(self, board: Board) -> float | None:
        """How far (m) from its chosen contact this finger's tip lands on the postulated object
        if it closes from where it is now; None when it would not land on it at all.

        Memoised: per target and wrist pose, the gaps of the whole sweep to the object (they
        change only when the wrist moves, :class:`~eos_svc.grasp.landing.SweepLandings`),
        then per first touching sample the landing's distance to the chosen contact."""
        found = self._landings(board)
        if found is None:
            return None
        landings, start, target = found
        k = landings.first_touch(start)
        if k is None:
            return None
        miss = self._miss_memo.get(k)
        if miss is None:
            hit = landings.landing(start)
            assert hit is not None  # k is its first touching sample
            chosen = np.asarray(target["contacts"][self.finger]["point"], dtype=float)
            miss = self._miss_memo[k] = float(np.linalg.norm(hit.point - chosen))
        return miss

    def _landings(self, board: Board) -> tuple[SweepLandings, int, dict] | None:
        """(the sweep's landings on the postulated object at the current wrist pose, the
        finger's start sample, the target), or None without a chosen contact or an object."""
        target = board.get(keys.TARGET)
        if target is None or self.finger not in target.get("contacts", {}):
            return None
        world = self.world
        start = bisect_left(self._sweep_angles, world.finger_angle(self.finger) - 1e-12)
        pose = self._wrist_pose(world.q_list())
        memo_pose, memo_target, landings = self._landings_memo
        if memo_pose != pose or memo_target is not target:
            obj = self._postulated(target)
            landings = None
            if obj is not None:
                translation, rotation = world.palm_views()
                rotated = self._rotated_sweep(rotation)
                pts, gaps = rotated_sweep_gaps(obj, rotated, self._tip_radius, translation)
                landings = SweepLandings(obj, self._sweep, pts, gaps)
            self._landings_memo = (pose, target, landings)
            self._miss_memo = {}
            self._far_samples = set()
        if landings is None:
            return None
        return landings, start, target

    def lands_within(self, board: Board, tolerance: float) -> bool:
        """``landing_miss(board)`` is not None and ≤ ``tolerance`` (m), without the landing's
        closest point when :meth:`SweepLandings.miss_lower_bound` already exceeds it (per
        first touching sample, memoised like the miss)."""
        found = self._landings(board)
        if found is None:
            return False
        landings, start, target = found
        k = landings.first_touch(start)
        if k is None or (k, tolerance) in self._far_samples:
            return False
        miss = self._miss_memo.get(k)
        if miss is None:
            chosen = np.asarray(target["contacts"][self.finger]["point"], dtype=float)
            if landings.miss_lower_bound(start, self._tip_radius, chosen) > tolerance:
                self._far_samples.add((k, tolerance))
                return False
            miss = self.landing_miss(board)
            assert miss is not None  # k is its first touching sample
        return miss <= tolerance

    def _rotated_sweep(self, rotation: np.ndarray) -> np.ndarray:
        """The sweep's points turned by the palm's ``rotation`` (``points @ rotation.T``), kept
        while the palm keeps its rotation (the wrist approaches its grasp without turning)."""
        key = rotation.tobytes()
        if self._rotated[0] != key:
            self._rotated = (key, self._sweep.points @ rotation.T)
        return self._rotated[1]

    def in_reach(self, board: Board) -> bool:
        """Whether closing from the current angle would land on this finger's chosen contact —
        or the finger has closed past it without touching (the object is not quite where it
        was postulated): then it keeps closing until it touches or reaches its limit — or
        another fingertip already touches, so the hand will not move again, and closing lands
        on the postulated object at all (short of its grasp position, the hand stopped when a
        finger in reach there touched: landing near the chosen contact is then better than
        none)."""
        if self.lands_within(board, self.world.params.landing_tolerance):
            return True
        if self.passed_its_contact(board):
            return True
        return self.hand_held(board) and self.landing_miss(board) is not None

    def hand_held(self, board: Board) -> bool:
        """Another fingertip touches the object: the wrist holds the hand where it is."""
        states = board.get(keys.FINGER_STATE, {})
        return any(state == "touching" for finger, state in states.items() if finger != self.finger)

    def passed_its_contact(self, board: Board) -> bool:
        """The finger is closing, free, and already beyond its chosen contact's angle."""
        if self.finger_state(board) != "closing":
            return False
        chosen = board.get(keys.TARGET, {}).get("contacts", {}).get(self.finger)
        return chosen is not None and self.world.finger_angle(self.finger) >= float(chosen["angle"]) - 1e-9

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
            miss = self.landing_miss(board)
            where = (
                "would miss the object"
                if miss is None
                else f"would land {miss * 1000:.1f} mm from its chosen contact"
            )
            return ActionResult(
                Outcome.CANNOT_ACT,
                f"closing {self.finger} from here {where} (the hand must reach its grasp position first)",
            )
        step = self.world.close_finger_step(self.finger, self.world.params.finger_step)
        event, angle = step.event, step.angle
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
