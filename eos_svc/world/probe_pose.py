"""The hand configuration of a guarded probe (EP2), apart from where the wrist is: what
:meth:`eos_svc.world.world.GraspWorld.guarded_probe` sets before every probe, computed once
per hand, probing finger and joint angle (it never changes; a default plan makes ~40 probes
with two fingers).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eos_svc.kinematics import HandModel
from eos_svc.kinematics.hand_cache import PerHandCache


@dataclass(frozen=True)
class ProbePose:
    """What a probe of ``finger`` at joint angle ``angle`` sets and checks.

    Attributes:
        indices: q indices of the wrist's roll, pitch and yaw joints, then every finger's joints.
        values: their values (rad): wrist rotation 0, the probing finger's joints at the angle,
            every other finger open (its lower limits).
        wrist_xyz: q indices of the wrist's x, y, z joints (a list of ints).
        wrist_lo, wrist_hi: their limits (m), as floats.
        others: collision geometry ids other than the probing finger's tip.
    """

    indices: np.ndarray
    values: np.ndarray
    wrist_xyz: list[int]
    wrist_lo: list[float]
    wrist_hi: list[float]
    others: list[int]

    def apply(self, q: np.ndarray) -> None:
        """Set the probe's configuration in ``q`` (in place; the wrist's x, y, z untouched):
        the same values as the joint-by-joint assignments, in one indexed write."""
        q[self.indices] = self.values


def _build(hand: HandModel, finger: str, angle: float) -> ProbePose:
    wq = hand.wrist_q_index
    parts_i = [np.asarray(wq[3:6], dtype=np.intp)]
    parts_v = [np.zeros(len(wq[3:6]))]
    for f in hand.finger_names:
        idx = np.asarray(hand.finger_q_index(f), dtype=np.intp)
        parts_i.append(idx)
        parts_v.append(np.full(len(idx), angle) if f == finger else hand.lower[idx].copy())
    xyz = wq[:3]
    tip_gid = hand.tip_geometry_id(finger)
    n_geoms = len(hand.collision_model.geometryObjects)
    indices, values = np.concatenate(parts_i), np.concatenate(parts_v)
    indices.flags.writeable = values.flags.writeable = False  # shared by every plan's probes
    return ProbePose(
        indices=indices,
        values=values,
        wrist_xyz=[int(i) for i in xyz],
        wrist_lo=hand.lower[xyz].tolist(),
        wrist_hi=hand.upper[xyz].tolist(),
        others=[g for g in range(n_geoms) if g != tip_gid],
    )


#: per (hand, finger, angle): its probe pose
_POSES: PerHandCache[ProbePose] = PerHandCache(keep=32)


def probe_pose(hand: HandModel, finger: str, angle: float) -> ProbePose:
    """The :class:`ProbePose` of ``finger`` at ``angle`` rad on ``hand``, computed once and kept
    (a few hands, fingers and angles)."""
    a = float(angle)
    return _POSES.get((hand,), lambda: _build(hand, finger, a), finger, a)
