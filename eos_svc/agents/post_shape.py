"""post_shape: postulates the object — class, size, pose and a calibrated confidence.

From **EP1 alone**: the class from the top's principal curvatures (:func:`classify`), the
vertical half extent from the top and bottom contacts, the confidence
:data:`EP1_CLASS_PROBABILITY` × P(size within ±10 %) — below 60 %, so it asks EP1 for the
bottom (``needs: "bottom"``), for more rolling (``"curvature"``), then EP2 (``"surface"``).
From **every contact**: every class fitted and chosen by model evidence (:mod:`eos_svc.shape`),
the confidence P(class right and size within tolerance); below 60 %, or not precise to
:data:`PRECISION` on fewer than :data:`PRECISION_CONTACTS` contacts, it asks EP2 again and
leaves its ``candidates`` and ``open_faces``. When **no class explains the contacts** after
EP2's last round (:data:`OUT_OF_CLASS`, or the best reaches far past them:
:mod:`eos_svc.shape.span`): their convex hull (:mod:`eos_svc.shape.hull`),
``approximate``. A fit still below 60 % after EP2's last round is planned on as it is, flagged
``approximate`` too (nothing will raise its confidence; the plan must not stall on it). The
postulate's fields: :class:`~eos_svc.schema.board_entries.ShapeEntry`; docs/planner.md has the
detail.

Opportunistic sub-rating: 1 right after EP1 or EP2 wrote something new, else 0.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.ep2 import MAX_ROUNDS as EP2_ROUNDS
from eos_svc.board import Board
from eos_svc.drivers.protocol import HandDriver
from eos_svc.schema import keys
from eos_svc.shape import Touches, select_class
from eos_svc.shape.hull import HullPostulate, hull_postulate
from eos_svc.shape.open_faces import open_faces
from eos_svc.shape.probe_information import Candidate, candidates_of
from eos_svc.shape.selection import MIN_CONTACTS, fit_probability, tolerance_probability
from eos_svc.shape.span import within_span

#: relative anisotropy below which the two curvatures count as equal (sphere)
SPHERE_TOLERANCE = 0.15
#: the size tolerance the confidence refers to (relative)
SIZE_TOLERANCE = 0.10
#: most free-space samples given to the fit
MAX_FREE_SAMPLES = 60
#: below this plausibility of the best primitive's fit under the noise model, no class explains
#: the touches: post_shape postulates their convex hull (:mod:`eos_svc.shape.hull`)
OUT_OF_CLASS = 1e-3
#: the approximate postulate's class name
HULL = "hull"
#: the precision rule: on fewer contacts than this, a confident postulate must also have its sizes
#: and centre within ±PRECISION with the confidence threshold's probability (a few contacts fit loosely)
PRECISION_CONTACTS = 12
PRECISION = 0.03
#: probability that EP1's curvature class is right: two readings cannot tell a sphere from an
#: upright capsule or ellipsoid, nor a box from a large cylinder
EP1_CLASS_PROBABILITY = 0.5


def size_confidence(relative_error: float | None) -> float:
    """Probability that the true size is within ±SIZE_TOLERANCE of the estimate (Gaussian σ)."""
    if relative_error is None or not math.isfinite(relative_error) or relative_error <= 0.0:
        return 0.0 if relative_error is None or not math.isfinite(relative_error) else 1.0
    return math.erf(SIZE_TOLERANCE / (math.sqrt(2.0) * relative_error))


def classify(curvature: dict) -> tuple[str, float]:
    """(class, grasp radius in m) from a curvature summary (``CurvatureEstimate.to_dict``)."""
    k1, k2 = curvature["principal_curvatures"]
    flat1, flat2 = curvature["flat"]
    s1, s2 = (s if s is not None else math.inf for s in curvature["sigma_curvatures"])
    if flat1 and flat2:
        return "plane", math.inf
    if flat2 and not flat1:
        return "cylinder", 1.0 / k1
    mean = 0.5 * (k1 + k2)
    if abs(k1 - k2) <= max(2.0 * math.hypot(s1, s2), SPHERE_TOLERANCE * abs(mean)):
        return "sphere", 1.0 / mean
    return "ellipsoid", 1.0 / mean


def sized(centre: np.ndarray, half: np.ndarray) -> dict[str, Any]:
    """A postulate's size fields from its centre and half extents along the world axes (m)."""
    return {
        "grasp_radius": round(float(half[2]), 6),
        "diameter": round(2.0 * float(half[2]), 6),
        "centre": np.round(centre, 6).tolist(),
        "bounds": [np.round(centre - half, 6).tolist(), np.round(centre + half, 6).tolist()],
    }


def touches_from(board: Board, world: HandDriver) -> Touches:
    """EP1's and EP2's contacts and EP2's free samples as fit measurements."""
    centres, normals, radii = [], [], []
    for contact in board.get(keys.EP1_CONTACT, {}).values():
        r = world.hand.tip_radius(contact["finger"])
        n = np.asarray(contact["normal"], dtype=float)
        centres.append(np.asarray(contact["point"], dtype=float) + r * n)
        normals.append(n)
        radii.append(r)
    for t in board.get(keys.EP2_TOUCHES, []):
        centres.append(np.asarray(t["centre"], dtype=float))
        normals.append(np.asarray(t["normal"], dtype=float))
        radii.append(float(t["radius"]))
    free = np.asarray(board.get(keys.EP2_FREE, []), dtype=float).reshape(-1, 4)
    if len(free) > MAX_FREE_SAMPLES:  # an even subset: the fit's cost grows with them
        free = free[np.linspace(0, len(free) - 1, MAX_FREE_SAMPLES).astype(int)]
    return Touches(
        np.array(centres).reshape(-1, 3),
        np.array(normals).reshape(-1, 3),
        np.array(radii),
        free[:, :3],
        free[:, 3],
        tactile_noise=world.tactile_noise,
        contact_tolerance=world.params.contact_tolerance,
        kinematic_sigma=world.kinematic_sigma,
    )


class PostShapeAgent(GraspAgent):
    """Turns what the fingers felt into a postulated object with a confidence."""

    reads = frozenset(
        {
            keys.CURVATURE,
            keys.EP1_CONTACT,
            keys.APPROACH,
            keys.EP2_TOUCHES,
            keys.EP2_FREE,
            keys.EP2_RUNS,
            keys.SHAPE,  # its own previous candidates: warm starts of the next fit
        }
    )
    writes = frozenset({keys.SHAPE, keys.D_OVER_H})

    def __init__(self, default: float, world: HandDriver) -> None:
        super().__init__("post_shape", (INFO,), default, world)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        new = (
            ctx.changed(keys.CURVATURE)
            or ctx.changed(keys.CURVATURE_BOTTOM)
            or ctx.changed(keys.EP2_TOUCHES)
            or ctx.changed(keys.EP2_FREE)  # a probe that touched nothing bounds the object too
            or ctx.changed(keys.EP1_CONTACT)  # on a table, the bottom is the table's plane
        )
        return 1.0 if new else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        curvature = board.get(keys.CURVATURE)
        contacts = board.get(keys.EP1_CONTACT, {})
        if curvature is None or "top" not in contacts:
            return ActionResult(Outcome.CANNOT_ACT, "no curvature estimate of the object's top to ponder yet")
        if keys.EP2_TOUCHES in board:
            touches = touches_from(board, self.world)
            if touches.count >= MIN_CONTACTS:
                return self._from_touches(board, curvature, touches)
        return self._from_ep1(board, curvature, contacts)

    def _write(self, board: Board, curvature: dict, shape: dict[str, Any]) -> None:
        """Write the postulate, with EP1's curvature on top, and d/h once it is sized."""
        radius = classify(curvature)[1]
        shape["principal_curvatures"] = curvature["principal_curvatures"]
        shape["curvature_radius"] = round(radius, 6) if math.isfinite(radius) else None
        board.set(keys.SHAPE, shape)
        if shape["grasp_radius"] is not None:
            board.set(keys.D_OVER_H, round(2.0 * shape["grasp_radius"] / self.world.hand.hand_height, 6))

    def _from_touches(self, board: Board, curvature: dict, touches: Touches) -> ActionResult:
        # the previous postulate's candidate fits, on fewer of these touches, start their classes'
        # fits; its classes' χ² tell which are settled
        previous = board.get(keys.SHAPE) or {}
        warm = {c.kind: (c.theta, c.r0) for c in map(Candidate.from_dict, previous.get("candidates", []))}
        post = select_class(touches, warm=warm, earlier=previous.get("evidence", {}).get("chi2"))
        ep2_done = int(board.get(keys.EP2_RUNS, 0)) >= EP2_ROUNDS  # the surface is all EP2 will feel
        out_of_class = post.best is not None and (
            fit_probability(post.best, 3 * touches.count) < OUT_OF_CLASS
            or not within_span(post.best.geometry, touches)
        )
        if ep2_done and out_of_class:
            hull = hull_postulate(touches, self.world.table_height)
            if hull is not None:
                return self._from_hull(board, curvature, touches, post.kind, hull)
        threshold = self.world.params.confidence_threshold
        fit = post.best
        precise = (
            fit is None
            or touches.count >= PRECISION_CONTACTS
            or ep2_done
            or tolerance_probability(fit, touches, tolerance=PRECISION) >= threshold
        )
        trusted = post.confidence >= threshold and precise
        # after EP2's last round nothing will raise the confidence: the best fit is planned on as
        # it is, approximate (as the convex hull is), rather than the plan stalling on it
        # (not a fit that explains nothing, when the touches make no hull)
        accepted = ep2_done and not trusted and fit is not None and not out_of_class
        shape: dict[str, Any] = {
            "class": post.kind,
            "confidence": round(post.confidence, 6),
            "grasp_radius": None,
            "diameter": None,
            "centre": None,
            "needs": None if trusted or accepted else "surface",
            "object": post.object(),
            "pose_known": fit is not None,
            "evidence": {
                **post.evidence(),
                "source": "fit to EP1 and EP2 contacts",
                "free_samples": len(touches.free),
            },
            "bounds": None,
            "open_faces": [],
        }
        if accepted:
            shape["approximate"] = True
        if fit is not None:
            if not trusted:  # what EP2 should feel next: the faces no touch bounds
                shape["open_faces"] = [face.to_dict() for face in open_faces(fit, touches)]
                # the classes and extents EP2 should tell apart (its next probes)
                shape["candidates"] = [c.to_dict() for c in candidates_of(post, touches)]
            shape.update(sized(fit.geometry.centre, fit.geometry.half_extents()))
        self._write(board, curvature, shape)
        rivals = ", ".join(f"{k} {p:.0%}" for k, p in list(shape["evidence"]["classes"].items())[:3])
        ask = "" if trusted else "; asks EP2 for more of the surface"
        if accepted:
            ask = f"; EP2 has no rounds left: planned on as it is, approximate (below {threshold:.0%})"
        if post.confidence >= threshold and not precise:
            ask += f" (its size not yet known to {PRECISION:.0%})"
        size = "" if fit is None else f", half-height {shape['grasp_radius'] * 1000:.2f} mm"
        return ActionResult(
            Outcome.PROGRESS,
            f"fitted every class to {touches.count} contacts: a {post.kind}{size} ({rivals}), "
            f"confidence {post.confidence:.0%}{ask}",
        )

    def _from_hull(
        self, board: Board, curvature: dict, touches: Touches, best: str, hull: HullPostulate
    ) -> ActionResult:
        """The approximate postulate (:mod:`eos_svc.shape.hull`), once EP2 has felt all it
        will: grasp_points plans on it as it is."""
        shape: dict[str, Any] = {
            "class": HULL,
            "confidence": round(hull.confidence, 6),
            **sized(hull.centre, hull.half_extents),
            "needs": None,
            "object": hull.object,
            "pose_known": True,
            "approximate": True,
            "evidence": {
                "contacts": touches.count,
                "best_primitive": best,
                "on_hull": round(hull.on_hull, 6),
                "source": "convex hull of the EP1 and EP2 contacts: no primitive explains them",
            },
        }
        self._write(board, curvature, shape)
        return ActionResult(
            Outcome.PROGRESS,
            f"no class explains the {touches.count} contacts (best: a {best}): the convex hull of the "
            f"touches, approximate ({hull.on_hull:.0%} of the touches on it), confidence "
            f"{hull.confidence:.0%}",
        )

    def _from_ep1(self, board: Board, curvature: dict, contacts: dict) -> ActionResult:
        kind, radius = classify(curvature)
        top = contacts["top"]
        needs: str | None
        centre: list[float] | None = None
        half: float | None = None
        own = 0.0
        if "bottom" not in contacts:
            needs = "bottom"
            how = "size unknown until the bottom is felt"
        else:
            p_top, p_bottom = np.asarray(top["point"]), np.asarray(contacts["bottom"]["point"])
            half = 0.5 * float(p_top[2] - p_bottom[2])
            if half <= 0.0:
                return ActionResult(Outcome.CANNOT_ACT, "the top and bottom contacts are inverted")
            mid = 0.5 * (p_top + p_bottom)
            approach = board.get(keys.APPROACH)
            if approach is not None:
                # depth: assume the object is about as deep as it is high, measured from the
                # surface point nearest the hand along the approach
                d = np.asarray(approach["direction"], dtype=float)
                n_xy = float(np.hypot(d[0], d[1]))
                if n_xy > 1e-6:
                    mid[:2] = np.asarray(approach["point"])[:2] + half * d[:2] / n_xy
            centre = mid.round(6).tolist()
            if kind == "sphere":
                rel = curvature.get("relative_error")
                own = size_confidence(None if rel is None else float(rel))
                how = f"curvature radius {radius * 1000:.2f} mm on top, centre between top and bottom"
            else:
                own = size_confidence(max(self.world.tactile_noise, 1e-6) / half)
                how = "from the top and bottom contacts"
            needs = "curvature" if own < self.world.params.confidence_threshold else "surface"
        confidence = EP1_CLASS_PROBABILITY * own
        obj = None
        if kind == "sphere" and half is not None and centre is not None:
            obj = {"shape": "sphere", "radius": round(half, 6), "position": centre, "rpy": [0.0, 0.0, 0.0]}
        shape = {
            "class": kind,
            "grasp_radius": None if half is None else round(half, 6),
            "diameter": None if half is None else round(2.0 * half, 6),
            "centre": centre,
            "confidence": round(confidence, 6),
            "needs": needs,
            "object": obj,
            "pose_known": False,
            "evidence": {
                "contacts": len(contacts),
                "classes": {kind: EP1_CLASS_PROBABILITY},
                "source": "EP1 curvature (top) and the top and bottom contacts; pose assumed upright",
                "size_confidence": round(own, 6),
            },
            "bounds": None,
        }
        self._write(board, curvature, shape)
        size = "" if half is None else f", half-height {half * 1000:.2f} mm"
        asks = {
            "bottom": "asks EP1 to feel the bottom",
            "curvature": f"EP1's size not trusted yet ({own:.0%}): asks EP1 to roll again",
            "surface": "class and extent ambiguous from two curvature readings: asks EP2 for the surface",
        }[needs]
        return ActionResult(
            Outcome.PROGRESS, f"postulated a {kind}{size} ({how}), confidence {confidence:.0%}; {asks}"
        )
