"""grasp_points: chooses the grasp on the postulated object and places the hand before it.

Grasp synthesis (:mod:`eos_svc.grasp.synthesis`; Miller, Knoop, Christensen, Allen, ICRA 2003)
on post_shape's postulate (:mod:`eos_svc.grasp.postulate`) scores candidate grasps by
Ferrari–Canny ε. The action turns the wrist to the best one, moves the hand to its pre-grasp
(``approach_distance`` before it, fingers open), writes the target and completes the
information stage. An object larger than the hand height across every grip (d/h ≥ 1, paper
§2.1), or no collision-free candidate, ends the run as failed.

Opportunistic sub-rating: post_shape's confidence once ≥ 60 % and no target yet (60 % for an
approximate postulate once EP2 has no rounds left); 0 otherwise.
"""

from __future__ import annotations

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.post_shape import touches_from
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.errors import ValidationError
from eos_svc.grasp.postulate import Postulate, make_object, read_postulate
from eos_svc.grasp.support import TouchSupport
from eos_svc.grasp.synthesis import GraspCandidate, GraspSynthesis
from eos_svc.schema import keys
from eos_svc.schema.request import MESH, ObjectSpec

#: the reason synthesis gives for a grip wider than the hand height
TOO_LARGE = "larger than the hand height across the grip"


def size_words(spec: ObjectSpec) -> str:
    """The postulated size in the request's field names, mm (e.g. ``size [70, 35, 45] mm``)."""
    if spec.shape == MESH:  # a mesh: its extents
        obj = make_object(spec)
        return f"extents [{', '.join(f'{2000 * v:.0f}' for v in obj.half_extents())}] mm"
    parts = []
    for key, value in spec.size.items():
        if isinstance(value, tuple):
            parts.append(f"{key} [{', '.join(f'{v * 1000:.0f}' for v in value)}] mm")
        else:
            parts.append(f"{key} {value * 1000:.0f} mm")
    return ", ".join(parts)


class GraspPointsAgent(GraspAgent):
    """Chooses the grasp and places the hand at the pre-grasp. ``oracle``: plan on this object
    instead of the postulate (measurement only); ``name``: a subclass's own (another sampler,
    :meth:`choose_candidates`)."""

    reads = frozenset(
        {keys.SHAPE, keys.TARGET, keys.FRICTION, keys.EP1_CONTACT, keys.EP2_TOUCHES, keys.EP2_FREE}
    )
    writes = frozenset({keys.TARGET, keys.FINGER_STATE, keys.AT_TARGET, keys.WRIST_LEFT})

    def __init__(
        self, default: float, world: HandDriver, oracle: ObjectSpec | None = None, name: str = "grasp_points"
    ) -> None:
        super().__init__(name, (INFO,), default, world)
        self.oracle = oracle

    def confident_shape(self, board: Board) -> dict | None:
        """post_shape's postulate if it is :func:`confident`."""
        shape = board.get(keys.SHAPE)
        return shape if confident(shape, self.world.params.confidence_threshold) else None

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        shape = self.confident_shape(board)
        if shape is None or keys.TARGET in board:
            return 0.0
        return max(float(shape["confidence"]), self.world.params.confidence_threshold)

    def postulate(self, shape: dict) -> Postulate | None:
        """The object to plan on (the oracle's when given)."""
        if self.oracle is not None:
            return Postulate(self.oracle, True, False, source="oracle")
        return read_postulate(shape)

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        shape = self.confident_shape(board)
        if shape is None:
            why = unsure(board.get(keys.SHAPE), self.world.params.confidence_threshold)
            return ActionResult(Outcome.CANNOT_ACT, f"no shape postulated with enough confidence yet{why}")
        try:
            postulate = self.postulate(shape)
        except ValidationError as exc:
            why = f"the postulated object is not valid: {exc.field}: {exc.reason}"
            return ActionResult(Outcome.FINISHED, why, succeeded=False)
        if postulate is None:
            return ActionResult(
                Outcome.FINISHED,
                f"cannot choose grasp points on a {shape['class']} of unknown size from EP1 alone",
                succeeded=False,
            )
        spec = postulate.spec
        synthesis = self.synthesis(board, postulate, shape)
        note = postulate.words()
        note = f" ({note})" if note else ""
        candidates = self.choose_candidates(synthesis, spec)
        if not candidates:
            return self._no_grasp(spec, synthesis, note)
        placed = self.place_first(board, candidates, synthesis, postulate)
        if placed is None:
            return ActionResult(Outcome.FINISHED, f"no collision-free pre-grasp found{note}", succeeded=False)
        cand, stand_off = placed
        roll, pitch, yaw = np.degrees(cand.wrist_rpy) + 0.0  # + 0.0: never "-0°"
        if not cand.about_centre:
            angle = f"{cand.angle_deg:.1f}°"
            note += f" — no grasp about the centre is reachable, the closest lands {angle} across it"
        return ActionResult(
            Outcome.STAGE_COMPLETE,
            f"grasp {cand.label} of the postulated {spec.shape}{note}: best of {len(candidates)} "
            f"candidates, ε = {cand.epsilon:.3f}, contacts {cand.angle_deg:.0f}° across the centre; "
            f"wrist turned to roll {roll:.0f}°, pitch {pitch:.0f}°, yaw {yaw:.0f}°, hand placed "
            f"{stand_off * 1000:.0f} mm before the grasp, open",
        )

    def synthesis(self, board: Board, postulate: Postulate, shape: dict | None = None) -> GraspSynthesis:
        """Grasp synthesis of this world's hand on the postulated object, at the board's μ; on
        an approximate postulate (post_shape's ``shape`` says so) its candidates are ranked by
        the touches' support first (:mod:`eos_svc.grasp.support`)."""
        world = self.world
        support = None
        if shape is not None and shape.get("approximate") and postulate.source == "post_shape":
            touches = touches_from(board, world)
            support = TouchSupport(touches.surface_points, touches.normals)
        return GraspSynthesis(
            world.hand,
            world.sweeps,
            world.params,
            make_object(postulate.spec),
            float(board.get(keys.FRICTION, 0.5)),
            vertical_only=postulate.vertical_only,
            table_height=world.table_height,
            support=support,
        )

    def choose_candidates(self, synthesis: GraspSynthesis, spec: ObjectSpec) -> list[GraspCandidate]:
        """The candidate grasps on ``spec``, best first (a grasp agent with another sampler overrides
        this: ``eos_svc.agents.plugins.sampled_grasp_points``)."""
        return synthesis.candidates()

    def _no_grasp(self, spec: ObjectSpec, synthesis: GraspSynthesis, note: str) -> ActionResult:
        """End the run: why no candidate was kept."""
        why = synthesis.rejections
        if why and set(why) == {TOO_LARGE} | ({"wrist rotation out of its limits"} & set(why)):
            h = self.world.hand.hand_height
            return ActionResult(
                Outcome.FINISHED,
                f"object too large to grasp in every direction: postulated {spec.shape} "
                f"{size_words(spec)} is at least the hand height {h * 1000:.0f} mm across every "
                f"grip (d/h ≥ 1){note}",
                succeeded=False,
            )
        reasons = ", ".join(f"{k} ({n})" for k, n in sorted(why.items()))
        return ActionResult(
            Outcome.FINISHED,
            f"no grasp of the postulated {spec.shape} {size_words(spec)} is reachable{note}: {reasons}",
            succeeded=False,
        )

    def place_first(
        self, board: Board, candidates: list[GraspCandidate], synthesis: GraspSynthesis, postulate: Postulate
    ) -> tuple[GraspCandidate, float] | None:
        """Place the hand, open, at the pre-grasp of the first of ``candidates`` that is clear of
        the object there and write its target (fingers open, not yet at it, the stand-off left);
        (that candidate, its stand-off in m), or None when none is clear."""
        for cand in candidates:
            placed = self._place(cand, synthesis)
            if placed is not None:
                pre, stand_off = placed
                board.set(keys.TARGET, self._target(cand, pre, postulate.spec, postulate))
                board.set(keys.FINGER_STATE, dict.fromkeys(self.world.hand.finger_names, "open"))
                board.set(keys.AT_TARGET, False)
                board.set(keys.WRIST_LEFT, round(stand_off, 6))
                return cand, stand_off
        return None

    def _place(self, cand: GraspCandidate, synthesis: GraspSynthesis) -> tuple[np.ndarray, float] | None:
        """Move the hand to ``cand``'s pre-grasp, fingers open, if it is clear of the object there;
        (pre-grasp wrist position, stand-off)."""
        world = self.world
        hand = world.hand
        pre = synthesis.pregrasp(cand)
        if pre is None:
            return None
        q = world.joint_positions()
        widx = hand.wrist_q_index
        q[widx[:3]] = pre[0]
        q[widx[3:6]] = cand.wrist_rpy
        for finger in hand.finger_names:
            # open: every joint at the start of the finger's closing sweep (all joints equal,
            # so that closing follows the sweep the grasp was planned on)
            q[hand.finger_q_index(finger)] = world.sweeps[finger].angles[0]
        world.move_joints(q)
        if not world.hand_clear(world.params.clearance):
            return None
        return pre

    @staticmethod
    def _target(cand: GraspCandidate, pre: np.ndarray, spec: ObjectSpec, postulate: Postulate) -> dict:
        return {
            "wrist": np.round(cand.wrist, 6).tolist(),
            "wrist_rpy": [round(float(a), 6) for a in cand.wrist_rpy],
            "pregrasp": np.round(pre, 6).tolist(),
            "centre": np.round(np.asarray(spec.position), 6).tolist(),
            "approach": np.round(cand.approach, 6).tolist(),
            "closing": np.round(cand.closing, 6).tolist(),
            "grasp": cand.label,
            "epsilon": round(cand.epsilon, 6),
            "angle_deg": round(cand.angle_deg, 3),
            "contacts": {f: hit.to_dict() for f, hit in cand.landings.items()},
            "object": spec.to_dict(),
            "pose_assumed_upright": not postulate.pose_known,
            "postulate": postulate.source,
        }


def confident(shape: dict | None, threshold: float) -> bool:
    """Whether post_shape's postulate ``shape`` asks for nothing more and is confident (at least
    ``threshold``) or approximate: a postulate to plan a grasp on."""
    if shape is None or shape.get("needs") is not None:
        return False
    return shape["confidence"] >= threshold or bool(shape.get("approximate"))


def unsure(shape: dict | None, threshold: float) -> str:
    """Why post_shape's postulate is not trusted, in words (empty before there is one): its
    confidence against the rule, and what keeps it low — faces no touch bounds, classes that
    explain the touches alike, or touches no class fits."""
    if shape is None:
        return ""
    evidence = shape.get("evidence") or {}
    out = (
        f": the {shape['class']} postulated from {evidence.get('contacts', '?')} contacts is "
        f"{shape['confidence']:.0%} sure (the grasp needs {threshold:.0%})"
    )
    faces = shape.get("open_faces") or []
    classes = list((evidence.get("classes") or {}).items())
    if faces:
        normals = "; ".join("[" + ", ".join(f"{v:+.2f}" for v in f["normal"]) + "]" for f in faces)
        return out + f"; no touch bounds its face{'s' if len(faces) > 1 else ''} toward {normals}"
    if len(classes) > 1 and classes[1][1] > 0.2:
        (a, pa), (b, pb) = classes[0], classes[1]
        return out + f"; the touches fit a {a} ({pa:.0%}) and a {b} ({pb:.0%}) alike"
    rms = evidence.get("fit_rms")
    if rms is not None and rms > 2.0:
        return out + f"; no class fits the touches (whitened residual rms {rms:.1f})"
    return out + "; its size or centre is not known to 10 %"
