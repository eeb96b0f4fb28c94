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
from eos_svc.kinematics.rolling import RollingQP, RollingQPError
from eos_svc.kinematics.rolling_solvers import BACKEND_SETTINGS

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
    rq = RollingQP(st.copy(), "finger1", F[:, 0], 0.5, 0.01, scene=sc)
    rq.step()
    p = rq.problem
    assert isinstance(p, qpsolvers.Problem)
    assert p.A.shape == (6, 9) and p.b.shape == (6,)
    assert p.lb.shape == (9,) and p.ub.shape == (9,) and np.all(p.lb <= p.ub)
    assert np.allclose(p.b[3:], 0.5 * rq.axis, atol=1e-3)  # ω a (+ ½ dt J̇q̇ correction)
    built = rq.build()  # the next step's QP, unsolved
    sol = qpsolvers.solve_problem(built, solver="daqp")
    assert sol.found
    np.testing.assert_allclose(built.A[:2] @ sol.x, built.b[:2], atol=1e-12)


@pytest.mark.parametrize(
    ("omega", "solver", "tol"), [(0.5, "osqp", 1e-6), (0.5, "daqp", 1e-9), (2.0, "daqp", 1e-9)]
)
def test_runner_gives_the_joint_velocities_of_qpsolvers_on_the_built_problem(omega, solver, tol):
    """The Problem the formulation builds, solved by qpsolvers directly, gives the runner's q̇
    (closed form when no bound is active, else the backend): within 1e-6 rad/s of OSQP (eps 1e-7)
    and 1e-9 rad/s of DAQP. At 2 rad/s the wrist yaw rolls at its velocity limit; the problem is
    nearly degenerate there and OSQP meets the bound only to its tolerance (q̇ within ~1e-5), so
    that case is compared with DAQP's exact active set."""
    sc, st, F = _setup()
    rq = RollingQP(st, "finger1", F[:, 0], omega, 0.01, solver, scene=sc, project_axis=False)
    for _ in range(30):
        problem = rq.build()
        ref = qpsolvers.solve_problem(problem, solver=solver, **BACKEND_SETTINGS.get(solver, {}))
        assert ref.found
        s = rq.step()
        np.testing.assert_allclose(rq.problem.A, problem.A, atol=0)  # the step solved that problem
        np.testing.assert_allclose(s.qdot[rq.active], ref.x, atol=tol)
        assert s.slip_speed < 1e-8


def test_constraint_rows_match_finite_differences(sphere_setup):
    """C = [t1, t2, n]ᵀ J_p ; J_ω — checked against finite differences of the tip body."""
    sc, st, F = sphere_setup
    rng = np.random.default_rng(0)
    hand, model = sc.hand, sc.hand.model
    fid = hand.tip_frame_id("finger1")
    for _ in range(3):
        q = st.q
        rq = RollingQP(hand.state(q), "finger1", F[:, 0], 0.5, 0.01, scene=sc, second_order=False)
        q[rq.active] += rng.uniform(-0.05, 0.05, size=rq.nx) * np.r_[0.2 * np.ones(3), np.ones(6)]
        rq.retarget(F[:, 0], 0.5, state=hand.state(q))
        C = rq.build().A
        ct = sc.contact(hand.state(q), "finger1")
        n = ct.normal
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        M0 = data.oMf[fid].copy()
        local = M0.actInv(ct.point_tip)  # the material point, in the tip frame
        eps = 1e-7
        for k, j in enumerate(rq.active):
            dq = np.zeros(model.nv)
            dq[j] = eps
            pin.framesForwardKinematics(model, data, pin.integrate(model, q, dq))
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
    R1 = rq.state.tip_placement("finger1").rotation
    rot = R0 @ pin.log3(R0.T @ R1)
    np.testing.assert_allclose(rot, omega * n * dt * rq.axis, atol=1e-6)


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


@pytest.mark.parametrize("solver", [s for s in qpsolvers.available_solvers if s != "osqp"])
def test_other_backends_agree_with_osqp(sphere_setup, solver):
    sc, st, F = sphere_setup
    a = RollingQP(st.copy(), "finger1", F[:, 0], 0.5, 0.01, scene=sc, closed_form=False)
    b = RollingQP(st.copy(), "finger1", F[:, 0], 0.5, 0.01, solver, scene=sc, closed_form=False)
    for _ in range(5):
        sa, sb = a.step(), b.step()
        np.testing.assert_allclose(sa.qdot, sb.qdot, atol=1e-6)
        assert sb.slip_speed < 1e-9


@pytest.mark.parametrize("solver", qpsolvers.available_solvers)
def test_infeasible_qp_raises_with_the_problem(sphere_setup, solver):
    sc, st, F = sphere_setup
    rq = RollingQP(st.copy(), "finger1", F[:, 0], 200.0, 0.01, solver, scene=sc)  # beyond the limits
    with pytest.raises(RollingQPError) as ei:
        rq.step()
    assert isinstance(ei.value.problem, qpsolvers.Problem)
    assert ei.value.problem.A.shape == (6, 9)
    assert solver in str(ei.value)


def test_readings_are_the_sensors_reading_of_each_steps_contact(sphere_setup):
    sc, st, F = sphere_setup
    rq = RollingQP(st.copy(), "finger1", F[:, 0], 0.5, 0.01, scene=sc, tactile=TactileSensor(0.0))
    for _ in range(5):
        state = sc.hand.state(rq.q)
        s = rq.step()
        expected = TactileSensor(0.0).read(state, sc.contact(state, "finger1"))
        np.testing.assert_allclose(s.reading.point_tip, expected.point_tip, atol=1e-12)
        assert s.reading.in_contact


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
