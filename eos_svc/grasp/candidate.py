"""A candidate grasp on the postulated object: a wrist pose and the contacts its fingers land on.

SI units: metres, radians (angles across the centre in degrees, as the end agent reports them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eos_svc.grasp.landing import Landing

#: smallest predicted angle (deg) across the centre a candidate must reach (the end agent's
#: good-grasp test asks 150°; the margin absorbs the difference between postulate and object)
MIN_PREDICTED_ANGLE_DEG = 160.0


@dataclass(frozen=True)
class GraspCandidate:
    """One candidate grasp on the postulated object.

    Attributes:
        label: how it grasps, in words (e.g. "across the axis").
        rotation: palm orientation in the world (3×3; columns: approach x, y, closing z).
        wrist_rpy: the wrist's roll, pitch, yaw joint values giving ``rotation`` (rad).
        wrist: palm origin at the grasp (world, m).
        depth: the object's centre ahead of the palm along the approach (m).
        extent: the object's half-extent along the closing axis through its centre (m).
        landings: per finger, where its tip touches when it closes from open.
        angle_deg: angle between the opposing contact and the others' midpoint seen from the
            centre (deg; 180 = straight across).
        epsilon: Ferrari–Canny ε of the predicted contacts (0 until scored).
        turn: rotation angle of the palm from the unrotated hand (rad), the tie-breaker.
    """

    label: str
    rotation: np.ndarray
    wrist_rpy: tuple[float, float, float]
    wrist: np.ndarray
    depth: float
    extent: float
    landings: dict[str, Landing]
    angle_deg: float
    epsilon: float = 0.0
    turn: float = 0.0

    @property
    def about_centre(self) -> bool:
        """The predicted contacts lie about the centre (``MIN_PREDICTED_ANGLE_DEG``)."""
        return self.angle_deg >= MIN_PREDICTED_ANGLE_DEG

    @property
    def approach(self) -> np.ndarray:
        """Unit approach direction (world): the palm's x axis."""
        return self.rotation[:, 0]

    @property
    def closing(self) -> np.ndarray:
        """Unit closing direction (world): the palm's z axis (opposing finger → the others)."""
        return self.rotation[:, 2]


def diameter_angle_deg(centre: np.ndarray, opposing: np.ndarray, others: list[np.ndarray]) -> float:
    """Angle (deg) between the opposing contact and the others' midpoint, seen from ``centre``
    (the end agent's Fig. 2 test)."""
    u = opposing - centre
    v = sum(others) / len(others) - centre
    cos = float(u @ v) / max(math.sqrt(float(u @ u) * float(v @ v)), 1e-12)
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))
