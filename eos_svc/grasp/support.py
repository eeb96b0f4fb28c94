"""How far the touches support a candidate grasp on an approximate postulate.

The convex hull of the touches (:mod:`eos_svc.shape.hull`) is exact only where the hand has
touched: between the touches a hull facet may span air over a concavity, a stem or a slanted
underside. A contact predicted on such a facet lands elsewhere on the real object, with another
normal, and the grip loses force closure (on pybullet's random objects 500–539, the failed grips'
predicted contacts were all ≥ 6 mm from every touch; the good ones had two or three within
5 mm). A predicted contact is *supported* when a touch lies within :data:`SUPPORT_RADIUS` of it
with a normal within :data:`SUPPORT_ANGLE_DEG` of its own: the surface was measured there.
Grasp synthesis ranks candidates on such a postulate by how many of their contacts are
supported before ε (:class:`~eos_svc.grasp.synthesis.GraspSynthesis`).

SI units: metres; angles in degrees where named so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eos_svc.grasp.candidate import GraspCandidate

#: a touch within this distance (m) of a predicted contact can support it
SUPPORT_RADIUS = 0.005
#: ... when its sensed normal is within this angle (deg) of the predicted normal
SUPPORT_ANGLE_DEG = 30.0


@dataclass(frozen=True)
class TouchSupport:
    """The sensed surface: touch points (N, 3) on the object (world, m) and their outward unit
    normals (N, 3)."""

    points: np.ndarray
    normals: np.ndarray

    def supported(self, point: np.ndarray, normal: np.ndarray) -> bool:
        """Whether a touch within :data:`SUPPORT_RADIUS` of ``point`` has a normal within
        :data:`SUPPORT_ANGLE_DEG` of ``normal``."""
        near = np.linalg.norm(self.points - point, axis=1) <= SUPPORT_RADIUS
        if not near.any():
            return False
        return bool(np.max(self.normals[near] @ normal) >= math.cos(math.radians(SUPPORT_ANGLE_DEG)))

    def rank(self, candidate: GraspCandidate, opposing: str) -> tuple[bool, int]:
        """(the opposing finger's predicted contact is supported, how many of ``candidate``'s
        predicted contacts are): the larger, the better. The opposing finger's contact comes
        first: it lands alone across the others, on the side a table hides and the hull of the
        touches guesses (the failed grips' unsupported contact was the opposing finger's)."""
        support = {f: self.supported(hit.point, hit.normal) for f, hit in candidate.landings.items()}
        return support[opposing], sum(support.values())
