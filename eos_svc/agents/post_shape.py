"""post_shape: postulates the object's shape and size from what EP1 felt.

Classes, from the principal curvatures k1 ≥ k2 on the object's top and their σ (1/m):

- ``plane``: both flat;
- ``cylinder``: k2 flat, k1 not;
- ``sphere``: |k1 − k2| within max(2σ, 15 % of the mean curvature);
- ``ellipsoid``: otherwise.

Size along the closing direction (the vertical half-extent, what the grasp
needs): the top's curvature cannot size a plane, a cylinder or an ellipsoid (and
mistakes an ellipsoid's top for a bigger sphere), so post_shape asks EP1 to feel
the bottom too (``needs: "bottom"``); the half-extent is half the height between
the two sensed contacts, the centre's height their midpoint, and its horizontal
position one half-extent behind the surface point nearest the hand along the
approach (the object taken as about as deep as it is high: exact for spheres
and for cylinders lying across the approach). The curvature radius of the top
(1/H) is reported beside it.

Confidence: the probability, under the estimate's Gaussian uncertainty, that the
true size lies within ±10 % of the postulated one: ``erf(0.1 / (√2 · σ/size))``.
For a sphere σ/size is EP1's relative radius error (the paper's criterion: EP1
repeats until its curvature radius is trusted); for the other classes it is the
tactile noise over the half-extent. 0 while the bottom is not felt. 60 % needs
σ/size ≤ 0.12. (The plain complement ``1 − σ_R/R`` would
accept a 40 % error at 60 %, too loose to tell d/h ≥ 1.) Opportunistic
sub-rating: 1 right after EP1 wrote a new estimate, else 0.
"""

from __future__ import annotations

import math

import numpy as np

from eos_svc.agent import ActionResult, CycleContext, Outcome
from eos_svc.agents import keys
from eos_svc.agents.base import INFO, GraspAgent
from eos_svc.agents.world import GraspWorld
from eos_svc.board import Board

#: relative anisotropy below which the two curvatures count as equal (sphere)
SPHERE_TOLERANCE = 0.15
#: the size tolerance the confidence refers to (relative)
SIZE_TOLERANCE = 0.10


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


class PostShapeAgent(GraspAgent):
    """Turns the curvature estimate into a shape postulate with a confidence."""

    reads = frozenset({keys.CURVATURE, keys.EP1_CONTACT, keys.APPROACH})
    writes = frozenset({keys.SHAPE, keys.D_OVER_H})

    def __init__(self, default: float, world: GraspWorld) -> None:
        super().__init__("post_shape", (INFO,), default, world)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 1.0 if ctx.changed(keys.CURVATURE) or ctx.changed(keys.CURVATURE_BOTTOM) else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        curvature = board.get(keys.CURVATURE)
        contacts = board.get(keys.EP1_CONTACT, {})
        if curvature is None or "top" not in contacts:
            return ActionResult(Outcome.CANNOT_ACT, "no curvature estimate of the object's top to ponder yet")
        kind, radius = classify(curvature)
        top = contacts["top"]
        needs = None
        centre: list[float] | None = None
        half: float | None = None
        if "bottom" not in contacts:
            confidence = 0.0
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
                # surface point nearest the hand along the approach (exact for spheres and
                # for cylinders lying across the approach)
                d = np.asarray(approach["direction"], dtype=float)
                d_xy = np.array([d[0], d[1], 0.0])
                n_xy = float(np.linalg.norm(d_xy))
                if n_xy > 1e-6:
                    mid[:2] = np.asarray(approach["point"])[:2] + half * d_xy[:2] / n_xy
            centre = mid.round(6).tolist()
            if kind == "sphere":
                # the paper's EP1 criterion: how sure is the top's curvature radius
                rel = curvature.get("relative_error")
                confidence = size_confidence(None if rel is None else float(rel))
                how = f"curvature radius {radius * 1000:.2f} mm on top, centre between top and bottom"
            else:
                noise = max(self.world.sensor.noise_std, 1e-6)
                confidence = size_confidence(noise / half)
                how = "from the top and bottom contacts"
        shape = {
            "class": kind,
            "grasp_radius": None if half is None else round(half, 6),
            "diameter": None if half is None else round(2.0 * half, 6),
            "centre": centre,
            "confidence": round(confidence, 6),
            "principal_curvatures": curvature["principal_curvatures"],
            "curvature_radius": round(radius, 6) if math.isfinite(radius) else None,
            "needs": needs,
        }
        board.set(keys.SHAPE, shape)
        if half is not None:
            board.set(keys.D_OVER_H, round(2.0 * half / self.world.hand.hand_height, 6))
        size = "" if half is None else f", half-height {half * 1000:.2f} mm"
        return ActionResult(
            Outcome.PROGRESS, f"postulated a {kind}{size} ({how}), confidence {confidence:.0%}"
        )
