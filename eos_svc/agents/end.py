"""end: finishes the run when the grasp is complete or can no longer progress.

Success when all fingertips touch (a precision grip). The grasp is *good*
(paper Fig. 2) when the contacts lie about the object's diameter: the opposing
finger's contact and the middle of the other contacts are on opposite sides of
the object's centre — the angle between them, seen from the centre, at least
150° — *and* the contacts are in force closure under Coulomb friction (μ from the board's
``friction`` entry, the request's; see :mod:`eos_svc.agents.quality` for the linearised
cones and the Ferrari–Canny ε, reported with the verdict). Opportunistic sub-rating: 1
when every finger is done (touching, missed, or stopped by a link contact), else 0. When
chosen with a finger still open (nothing else can act), it ends the run as failed, saying
which fingers never reached the object.
"""

from __future__ import annotations

import math

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import GRASP, GraspAgent
from eos_svc.agents.finger import DONE_STATES
from eos_svc.board import Board
from eos_svc.grasp.quality import DEFAULT_EDGES, contacts_quality
from eos_svc.schema import keys
from eos_svc.schema.request import DEFAULT_FRICTION
from eos_svc.world.world import GraspWorld

#: smallest angle (deg) between the opposing contact and the others' midpoint for a good grasp
GOOD_GRASP_ANGLE_DEG = 150.0


def grasp_geometry(world: GraspWorld, friction: float = DEFAULT_FRICTION) -> dict:
    """Contacts per finger and the good-grasp test, from the world as it is (ground truth).

    Returns a dict: ``contacts`` (per finger: touching, distance, point, outward normal),
    ``all_touching``, ``diameter_angle_deg``, ``about_diameter`` (the paper's Fig. 2 test),
    ``quality`` (:class:`~eos_svc.agents.quality.GraspQuality` as a dict: force closure, ε,
    μ, …, over the touching contacts, torques about the object's centre scaled by its half
    diameter), ``good`` (all touching, about the diameter and in force closure) and
    ``q_final`` (the hand configuration judged).
    """
    hand = world.hand
    contacts = {}
    for finger in hand.finger_names:
        c = world.scene.contact(world.state, finger)
        contacts[finger] = {
            "touching": bool(c.distance <= world.params.contact_tolerance),
            "distance": float(c.distance),
            "point": c.point_object.round(6).tolist(),  # np.round's own method, without its wrapper
            "normal": c.normal.round(6).tolist(),
        }
    all_touch = all(c["touching"] for c in contacts.values())
    angle = None
    about = False
    if all_touch:
        centre = world.obj.placement.translation
        opposing = hand.description.opposing_finger
        u = np.asarray(contacts[opposing]["point"]) - centre
        others = [np.asarray(c["point"]) for f, c in contacts.items() if f != opposing]
        v = np.mean(others, axis=0) - centre
        cos = float(u @ v / max(np.linalg.norm(u) * np.linalg.norm(v), 1e-12))
        angle = math.degrees(math.acos(max(-1.0, min(1.0, cos))))
        about = angle >= GOOD_GRASP_ANGLE_DEG
    quality = contacts_quality(
        contacts,
        world.obj.placement.translation,
        0.5 * world.obj.diameter,
        friction,
        DEFAULT_EDGES,
        world.params.contact_patch_radius,
    )
    return {
        "contacts": contacts,
        "all_touching": all_touch,
        "good": bool(about and quality.force_closure),
        "about_diameter": about,
        "diameter_angle_deg": angle,
        "quality": quality.to_dict(),
        "q_final": world.state.q.tolist(),
    }


class EndAgent(GraspAgent):
    """Judges the grasp and ends the run."""

    reads = frozenset({keys.FINGER_STATE, keys.FRICTION})
    writes = frozenset({keys.OUTCOME})

    def __init__(self, default: float, world: GraspWorld) -> None:
        super().__init__("end", (GRASP,), default, world)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        states = board.get(keys.FINGER_STATE)
        if states and DONE_STATES.issuperset(states.values()):  # every finger is done
            return 1.0
        return 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        verdict = grasp_geometry(self.world, float(board.get(keys.FRICTION, DEFAULT_FRICTION)))
        board.set(keys.OUTCOME, verdict)
        states = board.get(keys.FINGER_STATE, {})
        if verdict["all_touching"]:
            q = verdict["quality"]
            if verdict["good"]:
                judgement = "good"
            elif verdict["about_diameter"]:
                judgement = "not good (no force closure)"
            else:
                judgement = "not good (not about the diameter)"
            angle = verdict["diameter_angle_deg"]
            closure = "force closure" if q["force_closure"] else "no force closure"
            return ActionResult(
                Outcome.FINISHED,
                f"precision grip: all fingertips touch; grasp {judgement} ({angle:.0f}° across the "
                f"centre, {closure} at μ={q['friction']:g}, ε={q['epsilon']:.3f})",
                succeeded=True,
            )
        missing = [f for f, c in verdict["contacts"].items() if not c["touching"]]
        why = ", ".join(f"{f} {states.get(f, 'open')}" for f in missing)
        return ActionResult(
            Outcome.FINISHED, f"grasp failed: no fingertip contact for {why}", succeeded=False
        )
