"""The rolling QP: structure, Jacobians vs finite differences, no slip, contact, closed forms."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
import qpsolvers

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.hand import KinematicsError
from eos_svc.kinematics.rolling import RollingQP, RollingQPError, available_solvers

R_F = 0.01


def _setup(shape="sphere", size=0.04, finger="finger1"):
    sc = ep1_scene(shape, size, finger=finger)
    q = place_hand_for_ep1(sc, finger)
    st = sc.hand.state(q)
    F = contact_frame(sc.contact(st, finger).normal)
    return sc, st, F


@pytest.fixture(scope="module")
def sphere_setup():
    return _setup()


def test_problem_is_an_inspectable_qpsolvers_problem(sphere_setup):
    sc, st, F = sphere_setup
    rq = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, scene=sc)
    rq.step()
    p = rq.problem
    assert isinstance(p, qpsolvers.Problem)
    assert p.A.shape == (6, 9) and p.b.shape == (6,)
    assert p.lb.shape == (9,) and p.ub.shape == (9,) and np.all(p.lb <= p.ub)
    assert np.allclose(p.b[3:], 0.5 * rq.axis, atol=1e-3)  # ω a (+ ½ dt J̇q̇ correction)
    copy = rq.problem_copy()
    assert copy.A is not p.A and np.array_equal(copy.A, p.A)
    built = rq.build()  # the next step's QP, unsolved
    sol = qpsolvers.solve_problem(built, solver="daqp")
    assert sol.found
    np.testing.assert_allclose(built.A[:2] @ sol.x, built.b[:2], atol=1e-12)


def test_constraint_rows_match_finite_differences(sphere_setup):
    """C = [t1, t2, n]ᵀ J_p ; J_ω — checked against finite differences of the tip body."""
    sc, st, F = sphere_setup
    rng = np.random.default_rng(0)
    rq = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, scene=sc, second_order=False)
    hand, model = sc.hand, sc.hand.model
    fid = hand.tip_frame_id("finger1")
    for _ in range(3):
        rq._q[rq._cols] += rng.uniform(-0.05, 0.05, size=rq.nx) * np.r_[0.2 * np.ones(3), np.ones(6)]
        rq._qa[:] = rq._q[rq._cols]
        rq.kinematics()
        ct = rq.contact()
        rq._build(ct)
        C = rq._C.copy()
        n = ct.normal
        data = model.createData()
        pin.framesForwardKinematics(model, data, rq._q)
        M0 = data.oMf[fid].copy()
        local = M0.actInv(ct.point_tip)  # the material point, in the tip frame
        eps = 1e-7
        for k, j in enumerate(rq._cols):
            dq = np.zeros(model.nv)
            dq[j] = eps
            pin.framesForwardKinematics(model, data, pin.integrate(model, rq._q, dq))
            M1 = data.oMf[fid]
            v = (M1.act(local) - ct.point_tip) / eps
            w = pin.log3(M0.rotation.T @ M1.rotation)
            w = M0.rotation @ w / eps
            t1, t2 = C[0, k], C[1, k]
            assert abs(np.hypot(t1, t2) - np.linalg.norm(v - (v @ n) * n)) < 1e-5
            assert C[2, k] == pytest.approx(v @ n, abs=1e-5)
            np.testing.assert_allclose(C[3:, k], w, atol=1e-5)


@pytest.mark.parametrize(("shape", "size"), [("sphere", 0.02), ("plane", 1.0), ("ellipsoid", 0.04)])
def test_roll_keeps_no_slip_and_contact(shape, size):
    sc, st, F = _setup(shape, size)
    omega, dt, n = 0.5, 0.01, 40
    rq = RollingQP(st, "finger1", F[:, 1], omega, dt, scene=sc)
    R0 = st.tip_placement("finger1").rotation.copy()
    steps = rq.run(n)
    assert max(s.slip_speed for s in steps) < 1e-6  # m/s, the no-slip equality residual
    assert max(s.omega_residual for s in steps) < 1e-6
    assert max(abs(s.contact.distance) for s in steps) < 1e-5  # m, the gap tolerance
    # the tip turned by ω n dt about the fixed axis, without spin
    rq.kinematics()
    R1 = rq._data.oMf[rq._fid].rotation
    rot = R0 @ pin.log3(R0.T @ R1)
    np.testing.assert_allclose(rot, omega * n * dt * rq.axis, atol=1e-6)
    st.update(rq.q)


@pytest.mark.parametrize("R", [0.01, 0.04, math.inf])
def test_arc_rate_matches_closed_form_and_no_slip(R):
    """Contact speed over the tip |ω| r_f R/(r_f + R) (|ω| r_f on a plane); the contact
    travels the same arc on the object as on the fingertip (rolling, no sliding)."""
    sc, st, F = _setup("plane" if math.isinf(R) else "sphere", 1.0 if math.isinf(R) else R)
    omega, dt, n = 0.4, 0.005, 60
    rq = RollingQP(st, "finger1", F[:, 0], omega, dt, scene=sc, tactile=TactileSensor(0.0))
    steps = rq.run(n)
    tip = np.array([s.reading.point_tip for s in steps])
    obj = np.array([s.contact.point_object for s in steps])
    d = tip / np.linalg.norm(tip, axis=1, keepdims=True)
    ang = np.arccos(np.clip(np.sum(d[1:] * d[:-1], axis=1), -1, 1))
    rate_tip = R_F * ang.sum() / ((n - 1) * dt)
    expected = omega * R_F * (1.0 if math.isinf(R) else R / (R_F + R))
    assert rate_tip == pytest.approx(expected, rel=1e-3)
    arc_obj = np.linalg.norm(np.diff(obj, axis=0), axis=1).sum()
    if not math.isinf(R):  # chord → arc on the sphere
        arc_obj = np.sum(2 * R * np.arcsin(np.linalg.norm(np.diff(obj, axis=0), axis=1) / (2 * R)))
    assert arc_obj == pytest.approx(R_F * ang.sum(), rel=1e-3)


@pytest.mark.parametrize("solver", [s for s in available_solvers() if s != "osqp"])
def test_other_backends_agree_with_osqp(sphere_setup, solver):
    sc, st, F = sphere_setup
    a = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, scene=sc)
    b = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, solver, scene=sc)
    for _ in range(5):
        sa, sb = a.step(), b.step()
        np.testing.assert_allclose(sa.qdot, sb.qdot, atol=1e-6)
        assert sb.slip_speed < 1e-9


@pytest.mark.parametrize("solver", available_solvers())
def test_infeasible_qp_raises_with_the_problem(sphere_setup, solver):
    sc, st, F = sphere_setup
    rq = RollingQP(st, "finger1", F[:, 0], 200.0, 0.01, solver, scene=sc)  # beyond the limits
    with pytest.raises(RollingQPError) as ei:
        rq.step()
    assert isinstance(ei.value.problem, qpsolvers.Problem)
    assert ei.value.problem.A.shape == (6, 9)
    assert solver in str(ei.value)


def test_fast_tactile_reading_equals_the_sensor(sphere_setup):
    sc, st, F = sphere_setup
    for noise, pitch in [(0.0, None), (2e-4, None), (2e-4, 5e-4)]:
        rq = RollingQP(
            st.copy(),
            "finger1",
            F[:, 0],
            0.5,
            0.01,
            scene=sc,
            tactile=TactileSensor(noise, pitch, rng=7),
        )
        ref = TactileSensor(noise, pitch, rng=7)
        for _ in range(5):
            rq.kinematics()
            ct = rq.contact()
            fast = rq.read_tactile(ct)
            rq.sync()
            slow = ref.read(rq.state, ct)
            np.testing.assert_allclose(fast.point_tip, slow.point_tip, atol=1e-12)
            assert fast.in_contact == slow.in_contact
            rq.step()
            if noise > 0:
                ref.rng.normal(size=2)  # the draw of the step's own reading


def test_bad_arguments():
    sc, st, F = _setup()
    with pytest.raises(KinematicsError, match="dt"):
        RollingQP(st, "finger1", F[:, 0], 0.5, 0.0, scene=sc)
    with pytest.raises(KinematicsError, match="solver"):
        RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, "nope", scene=sc)
    with pytest.raises(KinematicsError, match="axis"):
        RollingQP(st, "finger1", F[:, 2], 0.5, 0.01, scene=sc)  # the normal: no roll
    with pytest.raises(KinematicsError, match="omega"):
        RollingQP(st, "finger1", F[:, 0], math.nan, 0.01, scene=sc)
