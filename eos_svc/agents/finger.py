"""The finger agents (hand3x3: finger1, finger2, finger3): search moves, then closing steps.

One agent per finger of the hand, named after it. Grasping (paper §2.1, §5): an action closes
the finger's joints by ``WorldParameters.finger_step``, stopping at first touch. Opportunistic
sub-rating: d/h while the tip is free and closing from where it is lands on the contact
grasp_points chose for it (within ``WorldParameters.landing_tolerance``; a finger that closed
past its contact keeps closing); otherwise 0, and ``CANNOT_ACT`` if chosen (paper §5).
"""

from __future__ import annotations

import math
from bisect import bisect_left
from operator import itemgetter

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import GRASP, SEARCH, GraspAgent
from eos_svc.agents.search import search_move, search_rating
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.grasp.landing import SweepLandings, sweep_landings
from eos_svc.grasp.postulate import make_object
from eos_svc.objects import SurfaceObject
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec

#: finger states that end a finger's part in the grasp
DONE_STATES = frozenset({"touching", "missed", "link"})


class TargetLandings:
    """The sweep landings of the fingers the grasp target names, on its postulated object, at the
    current wrist pose: one plan's finger agents share them, computed once per wrist pose and
    target in one signed-distance query (the postulated object built once per target)."""

    def __init__(self, world: HandDriver) -> None:
        self.world = world
        # the wrist's joint values, as a tuple, from the configuration list
        self._wrist_pose = itemgetter(*(int(i) for i in world.hand.wrist_q_index))
        # (wrist pose, target entry, its postulated object, the landings there)
        self._memo: tuple[object, object, SurfaceObject | None, dict] = (None, None, None, {})

    def at_wrist(self, target: dict) -> dict[str, SweepLandings]:
        """Per finger of ``target``'s contacts, its sweep's landings from where the wrist is now
        (none when the target has no object)."""
        world = self.world
        pose = self._wrist_pose(world.q_list())
        memo_pose, memo_target, obj, landings = self._memo
        if memo_target is not target:
            spec = target.get("object")
            obj = None if spec is None else make_object(ObjectSpec.from_dict(spec))
        elif memo_pose == pose:
            return landings
        landings = {}
        if obj is not None:
            radii = {f: world.hand.tip_radius(f) for f in target.get("contacts", {})}
            translation, rotation = world.palm_views()
            landings = sweep_landings(obj, world.sweeps, radii, rotation, translation)
        self._memo = (pose, target, obj, landings)
        return landings


class FingerAgent(GraspAgent):
    """Closes one finger; makes search moves in the search stage."""

    reads = frozenset(
        {keys.LOCATED, keys.SEARCH_MOVES, keys.TARGET, keys.FINGER_STATE, keys.FINGER_ANGLE, keys.D_OVER_H}
    )
    writes = frozenset({keys.LOCATED, keys.GAP, keys.SEARCH_MOVES, keys.FINGER_STATE, keys.FINGER_ANGLE})

    def __init__(
        self, finger: str, default: float, world: HandDriver, landings: TargetLandings | None = None
    ) -> None:
        super().__init__(finger, (SEARCH, GRASP), default, world)
        self.finger = finger
        self._sweep_angles = world.sweeps[finger].angles.tolist()
        #: the landings shared with the plan's other finger agents (their own when not given)
        self.landings = landings if landings is not None else TargetLandings(world)

    def finger_state(self, board: Board) -> str:
        """This finger's state on the board ("open" before grasping starts)."""
        return str(board.get(keys.FINGER_STATE, {}).get(self.finger, "open"))

    def landing_miss(self, board: Board) -> float | None:
        """How far (m) from its chosen contact this finger's tip lands on the postulated object
        if it closes from where it is now; None when it would not land on it at all
        (:class:`TargetLandings`)."""
        target = board.get(keys.TARGET)
        if target is None or self.finger not in target.get("contacts", {}):
            return None
        world = self.world
        landings = self.landings.at_wrist(target).get(self.finger)
        if landings is None:
            return None
        hit = landings.landing(bisect_left(self._sweep_angles, world.finger_angle(self.finger) - 1e-12))
        if hit is None:
            return None
        return math.dist(hit.point.tolist(), target["contacts"][self.finger]["point"])

    def in_reach(self, board: Board) -> bool:
        """Whether closing from the current angle would land on this finger's chosen contact —
        or the finger has closed past it without touching (the object is not quite where it
        was postulated): then it keeps closing until it touches or reaches its limit — or
        another fingertip already touches (the wrist holds the hand where it is) and closing
        lands on the postulated object at all: the hand stopped short of its grasp position when
        a finger in reach there touched, and landing near the chosen contact beats stalling."""
        miss = self.landing_miss(board)
        if miss is not None and miss <= self.world.params.landing_tolerance:
            return True
        states = board.get(keys.FINGER_STATE, {})
        if miss is not None and any(s == "touching" for f, s in states.items() if f != self.finger):
            return True
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
