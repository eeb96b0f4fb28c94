"""A re-targeted roller behaves as a new one; the fast paths of the step give the QP's answer."""

from __future__ import annotations

import numpy as np
import pytest
import qpsolvers

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.rolling import RollingQP


def _setup(finger="finger1"):
    sc = ep1_scene("sphere", 0.04, finger=finger)
    st = sc.hand.state(place_hand_for_ep1(sc, finger))
    F = contact_frame(sc.contact(st, finger).normal)
    return sc, st, F


@pytest.mark.parametrize("finger", ["finger1", "finger3"])  # contiguous / split active joints
def test_retarget_equals_a_new_roller(finger):
    sc, st, F = _setup(finger)
    legs = [(F[:, 0], 2.0, 8), (F[:, 0], -2.0, 16), (F[:, 1], 0.5, 8)]
    # new roller per leg
    st_a = st.copy()
    sa = TactileSensor(2e-4, rng=5)
    fresh = []
    for axis, omega, n in legs:
        new = RollingQP(st_a, finger, axis, omega, 0.01, scene=sc, tactile=sa, project_axis=False)
        fresh += new.run(n)
        st_a.update(new.q)
    # one roller, re-targeted
    st_b = st.copy()
    sb = TactileSensor(2e-4, rng=5)
    rq: RollingQP | None = None
    reused = []
    for axis, omega, n in legs:
        if rq is None:
            rq = RollingQP(st_b, finger, axis, omega, 0.01, scene=sc, tactile=sb, project_axis=False)
        else:
            rq.retarget(axis, omega, project_axis=False)
        reused += rq.run(n)
    assert rq is not None
    rq.sync()
    for a, b in zip(fresh, reused, strict=True):
        np.testing.assert_array_equal(a.qdot, b.qdot)
        assert a.reading is not None and b.reading is not None
        np.testing.assert_array_equal(a.reading.point_tip, b.reading.point_tip)
    np.testing.assert_array_equal(st_a.q, st_b.q)


def test_direct_solution_is_the_qp_optimum_and_bounds_are_exact():
    sc, st, F = _setup()
    # 0.5 rad/s: no bound near (at 2 rad/s the wrist yaw rolls at its velocity limit, where
    # the problem is nearly degenerate and backends agree only to their tolerance)
    rq = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, scene=sc, project_axis=False)
    direct = 0
    for _ in range(40):
        s = rq.step()
        p = rq.problem_copy()
        assert p.lb is not None and p.ub is not None
        # the bounds of this step, evaluated in full
        qa = (rq._q[rq._cols] - s.qdot[rq._cols] * rq.dt) / rq.dt
        lb = np.maximum(-sc.hand.velocity_limit[rq._cols], sc.hand.lower[rq._cols] / rq.dt - qa)
        ub = np.minimum(sc.hand.velocity_limit[rq._cols], sc.hand.upper[rq._cols] / rq.dt - qa)
        np.testing.assert_allclose(p.lb, lb, atol=1e-9)
        np.testing.assert_allclose(p.ub, ub, atol=1e-9)
        ref = qpsolvers.solve_problem(p, solver="daqp")
        assert ref.found and ref.x is not None
        np.testing.assert_allclose(s.qdot[rq._cols], ref.x, atol=1e-6)
        direct += s.iterations == 0
        assert s.slip_speed < 1e-12
    assert direct == 40  # no bound active here: every step solved in closed form


@pytest.mark.parametrize(
    ("finger", "noise", "pitch"),
    [("finger1", 2e-4, None), ("finger3", 2e-4, 5e-4), ("finger1", 0.0, None)],
)
def test_advance_is_the_step_without_its_records(finger, noise, pitch):
    """advance() (EP1's lean step) rolls as step() does, bit for bit: the same q, the same
    tactile points and random draws, gaps and no-slip residuals — over three legs (re-targeted)
    and with the OSQP path forced on one of them."""
    sc, st, F = _setup(finger)
    legs = [(F[:, 0], 2.0, 12, True), (F[:, 1], -2.0, 10, False), (F[:, 1], 2.0, 6, True)]

    def roll(lean: bool) -> tuple[list, list, float]:
        # one roll after the other: the rollers share the thread's OSQP object (warm start)
        rq = RollingQP(
            st.copy(), finger, F[:, 0], 2.0, 0.01, scene=sc, tactile=TactileSensor(noise, pitch, rng=3),
            project_axis=False,
        )
        out, qs = [], []
        for axis, omega, n, direct in legs:
            rq.retarget(axis, omega, project_axis=False)
            rq.direct = direct
            for _ in range(n):
                if lean:
                    out.append(rq.advance())
                else:
                    s = rq.step()
                    assert s.reading is not None
                    out.append((s.contact.distance, s.reading.in_contact, *s.reading.point_tip.tolist(),
                                s.slip_speed))
                qs.append(rq.q)
        assert rq.tactile is not None
        return out, qs, rq.tactile.rng.random()  # the next draw: the same draws consumed

    plain, lean = roll(False), roll(True)
    assert lean[0] == plain[0]
    np.testing.assert_array_equal(np.array(lean[1]), np.array(plain[1]))
    assert lean[2] == plain[2]
    assert all(isinstance(x, float) for row in lean[0] for x in (row[0], *row[2:]))


def test_a_roller_moved_to_another_scene_rolls_as_a_new_one():
    """use_scene + retarget on a roller that rolled on a sphere gives, on a cylinder of another
    scene (same hand), the roll of a roller built there: q and readings bit for bit."""
    sphere = ep1_scene("sphere", 0.04)
    cylinder = ep1_scene("cylinder", 0.03, hand=sphere.hand)
    st_s = sphere.hand.state(place_hand_for_ep1(sphere, "finger1"))
    st_c = cylinder.hand.state(place_hand_for_ep1(cylinder, "finger1"))
    F = contact_frame(cylinder.contact(st_c, "finger1").normal)

    def roll(rq: RollingQP) -> tuple[list, list]:
        steps = rq.run(12)
        return [s.reading.point_tip.tolist() for s in steps if s.reading is not None], rq.q.tolist()

    fresh = RollingQP(st_c.copy(), "finger1", F[:, 1], 2.0, 0.01, scene=cylinder,
                      tactile=TactileSensor(2e-4, rng=9), project_axis=False)
    expected = roll(fresh)
    moved = RollingQP(st_s.copy(), "finger1", F[:, 0], -2.0, 0.01, scene=sphere,
                      tactile=TactileSensor(2e-4, rng=1), project_axis=False)
    moved.run(10)
    moved.tactile = TactileSensor(2e-4, rng=9)
    moved.use_scene(cylinder)
    moved.retarget(F[:, 1], 2.0, state=st_c.copy(), project_axis=False)
    assert moved.object_geometry is cylinder.object.geometry
    assert roll(moved) == expected


def test_use_scene_refuses_another_hand():
    from eos_svc.kinematics import KinematicsError, load_hand

    sc, st, F = _setup()
    rq = RollingQP(st, "finger1", F[:, 0], 2.0, 0.01, scene=sc)
    other = ep1_scene("sphere", 0.04, hand=load_hand())
    with pytest.raises(KinematicsError, match="scene"):
        rq.use_scene(other)
