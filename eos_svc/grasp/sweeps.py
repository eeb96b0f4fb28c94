"""The fingers' closing sweeps: fingertip-centre paths in the palm frame as each finger closes,
computed once per hand, and what follows from them alone (the hand's forward reach, the
geometries each finger moves)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eos_svc.kinematics import HandModel


@dataclass
class FingerSweep:
    """Fingertip-centre positions in the palm frame as the finger closes (all joints equal).

    Attributes:
        angles: joint angle of every sample (rad), increasing (closing).
        points: (N, 3) tip-centre positions in the palm frame (m).
    """

    angles: np.ndarray
    points: np.ndarray

    def index_at(self, angle: float) -> int:
        """Index of the first sample at or beyond ``angle``."""
        return int(np.searchsorted(self.angles, angle - 1e-12))


#: sweep resolution of a finger with a prismatic joint (m): about the tip travel of 0.01 rad at
#: a 0.1 m lever, the resolution of a revolute finger
PRISMATIC_RESOLUTION = 0.001


def build_sweeps(hand: HandModel, resolution: float = 0.01) -> dict[str, FingerSweep]:
    """Tip-centre paths in the palm frame of every finger closing from its lower to its upper
    limit, every ``resolution`` rad (:data:`PRISMATIC_RESOLUTION` m for a prismatic finger)."""
    state = hand.state(hand.neutral())
    palm = state.palm_placement()
    sweeps: dict[str, FingerSweep] = {}
    for finger in hand.finger_names:
        idx = hand.finger_q_index(finger)
        lo, hi = float(np.max(hand.lower[idx])), float(np.min(hand.upper[idx]))
        joints = [hand.model.joints[hand.model.getJointId(j)] for j in hand.description.finger(finger).joints]
        prismatic = any(j.shortname().startswith("JointModelP") for j in joints)
        step = PRISMATIC_RESOLUTION if prismatic else resolution
        n = max(2, math.ceil((hi - lo) / step) + 1)
        angles = np.linspace(lo, hi, n)
        points = np.empty((n, 3))
        q = hand.neutral()
        for k, a in enumerate(angles):
            q[idx] = a
            state.update(q)
            points[k] = palm.actInv(state.tip_position(finger))
        sweeps[finger] = FingerSweep(angles, points)
    return sweeps


def forward_reach(hand: HandModel, sweeps: dict[str, FingerSweep]) -> float:
    """How far ahead of the wrist the hand reaches (m): the largest x of any fingertip centre
    over its closing path, plus its radius (0.14 m for hand3x3). The search's findability rule
    (:func:`eos_svc.world.coverage.findable`) needs it."""
    return max(float(s.points[:, 0].max()) + hand.tip_radius(f) for f, s in sweeps.items())


def finger_link_geometries(hand: HandModel) -> dict[str, list[int]]:
    """Per finger, the collision geometries that move when it closes, except its tip:
    those on the bodies its first listed joint carries."""
    model = hand.model
    geometries = hand.collision_model.geometryObjects
    out: dict[str, list[int]] = {}
    for finger in hand.finger_names:
        first = model.getJointId(hand.description.finger(finger).joints[0])
        moving = set(model.subtrees[first])
        tip = hand.tip_geometry_id(finger)
        out[finger] = [i for i, g in enumerate(geometries) if g.parentJoint in moving and i != tip]
    return out
