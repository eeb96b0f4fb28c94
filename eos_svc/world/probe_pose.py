"""The hand configuration of a guarded probe (EP2), apart from where the wrist is: what
:func:`eos_svc.world.probe_motion.guarded_probe` sets before every probe (the hand's context
keeps EP2's: :attr:`eos_svc.world.hand_context.HandContext.probe_poses`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eos_svc.kinematics import HandModel


@dataclass(frozen=True)
class ProbePose:
    """What a probe of ``finger`` at joint angle ``angle`` sets and checks: the ``values`` (rad)
    of the wrist's roll, pitch, yaw and every finger joint at ``indices`` (the probing finger at
    the angle, the others open), the wrist's x, y, z indices and limits (m), and the collision
    geometries ``others`` than the probing tip."""

    indices: np.ndarray
    values: np.ndarray
    wrist_xyz: list[int]
    wrist_lo: list[float]
    wrist_hi: list[float]
    others: list[int]

    def apply(self, q: np.ndarray) -> None:
        """Set the probe's configuration in ``q`` (in place; the wrist's x, y, z untouched)."""
        q[self.indices] = self.values

    @classmethod
    def build(cls, hand: HandModel, finger: str, angle: float, yaw: float = 0.0) -> ProbePose:
        """The pose of a probe of ``finger`` at joint angle ``angle`` (rad) on ``hand``, the
        wrist turned by ``yaw`` (rad) about the vertical."""
        wq = hand.wrist_q_index
        parts_i = [np.asarray(wq[3:6], dtype=np.intp)]
        parts_v = [np.array([0.0, 0.0, yaw])]
        for f in hand.finger_names:
            idx = np.asarray(hand.finger_q_index(f), dtype=np.intp)
            parts_i.append(idx)
            parts_v.append(np.full(len(idx), angle) if f == finger else hand.lower[idx].copy())
        xyz = wq[:3]
        tip_gid = hand.tip_geometry_id(finger)
        n_geoms = len(hand.collision_model.geometryObjects)
        indices, values = np.concatenate(parts_i), np.concatenate(parts_v)
        indices.flags.writeable = values.flags.writeable = False  # shared by every plan's probes
        return cls(
            indices=indices,
            values=values,
            wrist_xyz=[int(i) for i in xyz],
            wrist_lo=hand.lower[xyz].tolist(),
            wrist_hi=hand.upper[xyz].tolist(),
            others=[g for g in range(n_geoms) if g != tip_gid],
        )
