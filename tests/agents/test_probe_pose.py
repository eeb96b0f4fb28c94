"""probe_pose: a guarded probe's configuration set in one indexed write equals the plain
joint-by-joint assignments (wrist rotation 0, the probing finger at its angle, the others
open), to the bit, on hand3x3 and the Allegro hand; and the limits and other geometries it keeps."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.kinematics import HandModel, UnknownNameError
from eos_svc.world.probe_pose import ProbePose


def _plain(hand: HandModel, q: np.ndarray, finger: str, angle: float) -> np.ndarray:
    """What guarded_probe did joint by joint."""
    out = q.copy()
    wq = hand.wrist_q_index
    out[wq[3:6]] = 0.0
    for f in hand.finger_names:
        idx = hand.finger_q_index(f)
        out[idx] = angle if f == finger else hand.lower[idx]
    return out


def test_probe_pose_equals_the_plain_assignments(eos_hand) -> None:
    """Every registered hand (the eos_hand fixture of eos_svc.testing.pytest_plugin)."""
    hand = eos_hand
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = hand.lower + (hand.upper - hand.lower) * rng.random(hand.nq)
        finger = hand.finger_names[int(rng.integers(len(hand.finger_names)))]
        angle = float(rng.uniform(-0.3, 0.8))
        got = q.copy()
        pose = ProbePose.build(hand, finger, angle)
        pose.apply(got)
        assert got.tobytes() == _plain(hand, q, finger, angle).tobytes()
        xyz = hand.wrist_q_index[:3]
        assert pose.wrist_lo == hand.lower[xyz].tolist() and pose.wrist_hi == hand.upper[xyz].tolist()
        tip = hand.tip_geometry_id(finger)
        n = len(hand.collision_model.geometryObjects)
        assert pose.others == [g for g in range(n) if g != tip]
    with pytest.raises(UnknownNameError):
        ProbePose.build(hand, "thumb9", 0.0)
