"""The hand's dimensions allow a precision grip (all three fingertips touching, no other part)
of spheres with d/h from 0.2 to 0.95 placed on the hand axis, for some closing angle and
wrist x (the object's x relative to the palm)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.kinematics import HandModel, Scene
from eos_svc.objects import Sphere


def _first_touch(hand: HandModel, scene: Scene, finger: str) -> float | None:
    """Closing all joints of ``finger`` equally from straight: the first angle where its tip
    touches, provided no other part of that finger or the palm touches."""
    st = hand.state()
    idx = hand.finger_q_index(finger)
    others = [
        g.name
        for g in hand.collision_model.geometryObjects
        if g.name.startswith(finger) and "tip" not in g.name
    ] + ["palm_0"]
    for th in np.arange(0.0, 1.8, 0.01):
        q = hand.neutral()
        q[idx] = th
        st.update(q)
        if scene.contact(st, finger).distance <= 0.0:
            ok = all(scene.distance(st, g).distance > 0.0 for g in others)
            return float(th) if ok else None
    return None


@pytest.mark.parametrize("ratio", [0.2, 0.35, 0.5, 0.65, 0.8, 0.95])
def test_precision_grip_reachable(hand: HandModel, ratio: float) -> None:
    R = ratio * hand.hand_height / 2
    for x in np.arange(0.05, 0.3, 0.005):
        scene = Scene(hand, Sphere(R, pin.SE3(np.eye(3), np.array([x, 0.0, 0.0]))))
        if scene.min_distance(hand.state()).distance <= 0.0:
            continue  # the open hand already hits it
        angles = [_first_touch(hand, scene, f) for f in hand.finger_names]
        if all(a is not None for a in angles):
            return
    pytest.fail(f"no wrist x gives a precision grip of a sphere with d/h = {ratio}")
