"""post_shape: postulates the object's shape and size from EP1's curvature estimate.

Classes, from the principal curvatures k1 ≥ k2 and their σ (1/m):

- ``plane``: both flat (EP1 alone cannot size it);
- ``cylinder``: k2 flat, k1 not;
- ``sphere``: |k1 − k2| within max(2σ, 15 % of the mean curvature);
- ``ellipsoid``: otherwise.

Size: the grasp radius is 1/H (mean curvature) for a sphere or ellipsoid and
1/k1 for a cylinder; the centre lies that far behind the sensed contact along
the object normal. Confidence is the probability, under the estimate's Gaussian
uncertainty, that the true grasp radius lies within ±10 % of the postulated one:
``erf(0.1 / (√2 · σ_R/R))`` (0 for a plane) — 60 % needs σ_R/R ≤ 0.12. (The
plain complement ``1 − σ_R/R`` would accept a 40 % error at 60 %, too loose to
tell d/h ≥ 1.) Opportunistic sub-rating: 1 right after EP1 wrote a new
estimate, else 0.
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

    def __init__(self, default: float, world: GraspWorld) -> None:
        super().__init__("post_shape", (INFO,), default, world)

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return 1.0 if ctx.changed(keys.CURVATURE) else 0.0

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        curvature = board.get(keys.CURVATURE)
        contact = board.get(keys.EP1_CONTACT)
        if curvature is None or contact is None:
            return ActionResult(Outcome.CANNOT_ACT, "no curvature estimate to ponder yet")
        kind, radius = classify(curvature)
        rel = curvature.get("relative_error")
        confidence = 0.0 if kind == "plane" or rel is None else size_confidence(float(rel))
        if kind == "plane" or not math.isfinite(radius) or radius <= 0.0:
            centre = None
            diameter = math.inf
        else:
            centre = (np.asarray(contact["point"]) - radius * np.asarray(contact["normal"])).round(6).tolist()
            diameter = 2.0 * radius
        shape = {
            "class": kind,
            "grasp_radius": None if centre is None else round(radius, 6),
            "diameter": None if centre is None else round(diameter, 6),
            "centre": centre,
            "confidence": round(confidence, 6),
            "principal_curvatures": curvature["principal_curvatures"],
        }
        board.set(keys.SHAPE, shape)
        if centre is not None:
            board.set(keys.D_OVER_H, round(diameter / self.world.hand.hand_height, 6))
        size = "size unknown" if centre is None else f"radius {radius * 1000:.2f} mm"
        return ActionResult(Outcome.PROGRESS, f"postulated a {kind}, {size}, confidence {confidence:.0%}")
