"""relocate: before the grasp, checks by touch that the object is where the postulate says.

A hand that explores a free object by touch may push it (the Drake world's object rests on its
table; a real one too). The postulate fits touches made while the object was somewhere else,
and a grasp planned on it aims where the object was. This agent joins the team only in a world
whose object can move (:attr:`HandDriver.object_fixed` false; the kinematic world's object is
fixed, so its plans do not change). It never reads the true object: it touches it.

Once post_shape's postulate is confident (grasp_points would plan on it) and before there is a
grasp target, it makes **check touches**: guarded probes onto the surface points the postulate
predicts — the front along +x, a side along ±y and the top along −z (one per axis: a ball
moved 12 mm across the front probe's line moves its touch by 1.8 mm only), each from
:data:`~eos_svc.agents.ep2.STANDOFF` outside the postulated bounds. A touch farther than
:data:`~eos_svc.drivers.protocol.RELOCATE_AFTER` (2 mm) from the predicted surface, or a miss,
means the object moved: it then **re-locates** it — probes of both sides along ±y and of the
front off its centre, then the postulated object's pose refitted to the fresh touches, its
shape kept (:func:`~eos_svc.shape.pose_refit.refit_pose`) — and writes the re-located postulate
(``object``, ``centre``, ``bounds``) for grasp_points to plan on. The next check verifies the
refit; after :data:`MAX_ROUNDS` checks the plan goes on with the last pose, saying so. The
postulate's ``located`` entry records what was found.

Opportunistic sub-rating: 1 while a confident postulate has no ``located`` verdict and no grasp
target exists (ahead of grasp_points: default 0.65 against its 0.6); 0 otherwise.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.ep2 import STANDOFF
from eos_svc.agents.grasp_points import confident
from eos_svc.agents.probe_plan import Probe, front_probe, side_probe, top_probe
from eos_svc.board import Board
from eos_svc.drivers.protocol import RELOCATE_AFTER, HandDriver
from eos_svc.grasp.postulate import make_object, read_postulate
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec
from eos_svc.shape.pose_refit import refit_pose, touch_misses

#: most checks of one plan (each after the refit the one before triggered)
MAX_ROUNDS = 3
#: the front's off-centre relocation probes, as fractions of the half height
FRONT_OFFSETS = (0.5, -0.5)
#: where along x a side probe touches, as a fraction of the half length from the middle (toward
#: the hand: the finger's links trail the tip, clear of the object)
SIDE_DX = -0.25


class RelocateAgent(GraspAgent):
    """Checks the postulated pose by touch and re-locates a moved object (module docstring)."""

    reads = frozenset({keys.SHAPE, keys.TARGET})
    writes = frozenset({keys.SHAPE})

    def __init__(self, default: float, world: HandDriver) -> None:
        super().__init__("relocate", (INFO,), default, world)
        self.rounds = 0

    def _pending(self, board: Board) -> dict | None:
        """The confident postulate awaiting a check (None when there is none)."""
        shape = board.get(keys.SHAPE)
        if keys.TARGET in board or not confident(shape, self.world.params.confidence_threshold):
            return None
        if shape.get("located") is not None or shape.get("object") is None:
            return None
        return dict(shape)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 1.0 if self._pending(board) is not None else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        shape = self._pending(board)
        if shape is None:
            return ActionResult(Outcome.CANNOT_ACT, "no confident postulate awaiting a check")
        postulate = read_postulate(shape)
        assert postulate is not None  # it has an object
        spec = postulate.spec
        self.rounds += 1
        checks = self._probe(self.check_probes(spec))
        misses = self._misses(spec, checks)
        worst = max((abs(m) for m in misses if m is not None), default=0.0)
        lost = any(m is None for m in misses)
        if not lost and worst <= RELOCATE_AFTER:
            shape["located"] = {"moved": False, "checks": self.rounds, "miss_mm": round(1000 * worst, 3)}
            board.set(keys.SHAPE, shape)
            return ActionResult(
                Outcome.PROGRESS,
                f"check touches on the postulated {spec.shape}: {len(checks)} within "
                f"{1000 * worst:.1f} mm of the predicted surface: it is where it was postulated",
            )
        what = (
            "a check probe missed it" if lost else f"a check touch {1000 * worst:.1f} mm off the prediction"
        )
        if self.rounds >= MAX_ROUNDS:
            return self._unverified(
                board,
                shape,
                f"{what} after {self.rounds} checks: the object keeps moving; planning on the last pose",
            )
        more = self._probe(self.relocation_probes(spec))
        touches = [t for t in checks if t is not None] + [t for t in more if t is not None]
        if len(touches) < 3:
            return self._unverified(
                board, shape, f"{what}; only {len(touches)} fresh touches: cannot re-locate it"
            )
        centres, normals, radii = (np.array([t[i] for t in touches]) for i in range(3))
        fit = refit_pose(spec, centres, normals, radii, self.world.support_height, self.world.tactile_noise)
        board.set(keys.SHAPE, relocated_shape(shape, fit.spec, self.rounds))
        return ActionResult(
            Outcome.PROGRESS,
            f"{what}: the object moved; re-located from {len(touches)} fresh touches, its "
            f"{spec.shape} kept: moved {1000 * float(np.linalg.norm(fit.shift)):.1f} mm, turned "
            f"{np.degrees(fit.turn):.0f}°, touches within {1000 * fit.rms:.1f} mm rms",
        )

    def _unverified(self, board: Board, shape: dict, words: str) -> ActionResult:
        """The postulate marked moved and not verified (the plan goes on with its last pose)."""
        shape["located"] = {"moved": True, "checks": self.rounds, "verified": False}
        board.set(keys.SHAPE, shape)
        return ActionResult(Outcome.PROGRESS, words)

    # --- the probes ---------------------------------------------------------------------------
    def _estimate(self, spec: ObjectSpec) -> tuple[np.ndarray, np.ndarray]:
        obj = make_object(spec)
        return obj.centre, np.maximum(obj.half_extents(), 0.005)

    def check_probes(self, spec: ObjectSpec) -> list[Probe]:
        """The check probes: the front's middle along +x, a side's along ±y (the one from −y,
        else, where another part of the hand ends it, the one from +y: alternatives of one
        group) and the top's along −z — one per axis, so a move in any direction shows (a round
        object moved across a probe's line barely changes where that probe touches it)."""
        world = self.world
        centre, half = self._estimate(spec)
        return [
            front_probe(world, centre, half, 0.0, 0.0, STANDOFF),
            *(
                side_probe(world, centre, half, sign, SIDE_DX * half[0], STANDOFF, group=0)
                for sign in (1, -1)
            ),
            top_probe(world, centre, half, 0.0, 0.0, STANDOFF),
        ]

    def relocation_probes(self, spec: ObjectSpec) -> list[Probe]:
        """The probes added to re-locate: both sides along ±y, the front off its middle."""
        world = self.world
        centre, half = self._estimate(spec)
        sides = [side_probe(world, centre, half, sign, SIDE_DX * half[0], STANDOFF) for sign in (1, -1)]
        fronts = [front_probe(world, centre, half, 0.0, f * half[2], STANDOFF) for f in FRONT_OFFSETS]
        return sides + fronts

    def _probe(self, probes: list[Probe]) -> list[tuple[np.ndarray, np.ndarray, float] | None]:
        """Each probe's touch (tip centre, sensed normal, tip radius), None where it missed; the
        probes of one group (``group`` ≥ 0, consecutive) are alternatives: one entry, the first
        that touches (the rest not made), None when one missed and none touched. A probe blocked
        (another part of the hand first, or no clear start) says nothing of the object: no entry."""
        out: list[tuple[np.ndarray, np.ndarray, float] | None] = []
        touched_groups: set[int] = set()
        missed_groups: set[int] = set()
        for k, p in enumerate(probes):
            if p.group >= 0 and p.group in touched_groups:
                continue
            outcome = self.world.guarded_probe(p.finger, p.start, p.direction, p.travel, p.angle, p.yaw)
            if outcome.event == "touched" and outcome.centre is not None and outcome.normal is not None:
                radius = self.world.hand.tip_radius(p.finger)
                out.append((np.asarray(outcome.centre), np.asarray(outcome.normal), radius))
                touched_groups.add(p.group)
                continue
            if outcome.event == "missed":
                missed_groups.add(p.group)
            last = p.group < 0 or all(q.group != p.group for q in probes[k + 1 :])
            if last and (outcome.event == "missed" or (p.group >= 0 and p.group in missed_groups)):
                out.append(None)  # a miss, or the group's alternatives blocked or missed, one missed
        return out

    @staticmethod
    def _misses(spec: ObjectSpec, touches: list) -> list[float | None]:
        """Each touch's distance from the predicted surface (m), None for a miss."""
        obj = make_object(spec)
        return [
            None if t is None else float(touch_misses(obj, t[0][None], np.array([t[2]]))[0]) for t in touches
        ]


def relocated_shape(shape: dict, spec: ObjectSpec, rounds: int) -> dict:
    """The postulate ``shape`` with its object at the re-located pose ``spec`` (centre and
    bounds with it), awaiting the next check."""
    obj = make_object(spec)
    centre, half = obj.centre, obj.half_extents()
    out = dict(shape)
    out["object"] = spec.to_dict()
    out["centre"] = np.round(centre, 6).tolist()
    out["bounds"] = [np.round(centre - half, 6).tolist(), np.round(centre + half, 6).tolist()]
    out["pose_known"] = True
    out["relocations"] = rounds
    out.pop("located", None)
    return out
