"""The rolling step's velocity bounds: ``∓q̇max`` reused while no position limit is within reach
(:func:`steps_at_speed_limits`) are the bounds :func:`velocity_bounds` computes at every step."""

from __future__ import annotations

import numpy as np

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.rolling import RollingQP, RollingQPError
from eos_svc.kinematics.rolling_problem import JointBox, steps_at_speed_limits, velocity_bounds


def test_steps_at_speed_limits_hold_at_full_speed_toward_the_nearest_limit() -> None:
    rng = np.random.default_rng(3)
    lower, upper = np.array([-1.0, 0.0, -0.5]), np.array([1.0, 1.5, 0.5])
    box = JointBox(lower, upper, np.array([2.0, 1.0, 0.5]))
    dt = 0.01
    for _ in range(200):
        q = rng.uniform(lower, upper)
        k = steps_at_speed_limits(q, box, dt)
        lb, ub = velocity_bounds(q, box, dt)
        at_limits = bool(np.all(lb == -box.velocity) and np.all(ub == box.velocity))
        assert (k > 0) == at_limits  # 0 exactly when a position limit binds now
        # the worst case: every joint at full speed (and the solver's margin) toward its nearest limit
        toward = np.where(q - lower < upper - q, -1.0, 1.0) * box.velocity * 1.0099
        for _ in range(k):
            lb, ub = velocity_bounds(q, box, dt)
            np.testing.assert_array_equal(lb, -box.velocity)
            np.testing.assert_array_equal(ub, box.velocity)
            q = q + toward * dt


def test_rolling_near_the_joint_limits_uses_the_bounds_of_every_step() -> None:
    sc = ep1_scene("sphere", 0.04)
    hand = sc.hand
    st = hand.state(place_hand_for_ep1(sc, "finger1"))
    F = contact_frame(sc.contact(st, "finger1").normal)
    rq = RollingQP(st, "finger1", F[:, 0], 2.0, 0.01, scene=sc, tactile=TactileSensor(0.0))
    near_limit = 0
    for leg in range(6):
        rq.retarget(F[:, leg % 2], 2.0 * (-1.0) ** (leg // 2), state=st)
        for _ in range(60):
            q = rq.q[rq.active]
            try:
                rq.step()
            except RollingQPError:  # rolled into a joint limit: this leg ends
                break
            qp = rq._qp
            assert qp is not None
            lb, ub = velocity_bounds(q, rq.box, rq.dt)
            np.testing.assert_array_equal(qp.lb, lb)
            np.testing.assert_array_equal(qp.ub, ub)
            near_limit += int(np.any(lb > -rq.box.velocity) or np.any(ub < rq.box.velocity))
    assert near_limit > 0  # some steps had a position limit within reach
