"""The roller steps on its hand state's Pinocchio data: reading ``rq.state`` makes the state
consistent at the roller's q, and a state the roller leaves for another is put back at its own q."""

from __future__ import annotations

import numpy as np

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.hand import HandState
from eos_svc.kinematics.rolling import RollingQP


def _consistent(state: HandState, finger: str) -> bool:
    fresh = state.hand.state(state.q)
    return bool(np.array_equal(state.tip_position(finger), fresh.tip_position(finger)))


def test_the_state_follows_the_roll_when_read_and_is_restored_when_left() -> None:
    sc = ep1_scene("sphere", 0.04)
    hand = sc.hand
    q0 = place_hand_for_ep1(sc, "finger1")
    first, second = hand.state(q0), hand.state(q0)
    F = contact_frame(sc.contact(first, "finger1").normal)
    rq = RollingQP(first, "finger1", F[:, 0], 1.0, 0.01, scene=sc, tactile=TactileSensor(0.0))
    for _ in range(10):
        rq.step()
    assert not np.array_equal(rq.q, q0)
    assert not _consistent(first, "finger1")  # its data are the roll's, its q the start's
    rolled = rq.state
    assert rolled is first and np.array_equal(first.q, rq.q) and _consistent(first, "finger1")
    for _ in range(5):
        rq.step()
    rq.retarget(F[:, 1], 1.0, state=second)  # leave `first` for `second`
    assert _consistent(first, "finger1")
    rq.step()
    assert np.array_equal(rq.state.q, rq.q) and _consistent(second, "finger1")
