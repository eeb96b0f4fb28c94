"""RollingQP.step against a slow, independent reference written from the QP of the module
docstring: the full (not chain-reduced) Pinocchio model, the contact in closed form from the
object's geometry (not coal), the material point's Jacobian J_p = J_v − [r]ₓ J_ω, any tangent
basis (the least-norm solution does not depend on it), and the equality-constrained
minimum-W-norm problem solved with numpy's ``lstsq`` — on several fingers, shapes, weights and
solvers, over re-targeted rolls with a fixed seed. Plus the bounds against numpy's clipping and the
reduced chain model against the full one, bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.rolling import RollingQP

LWA = pin.LOCAL_WORLD_ALIGNED
SIZE = 0.04


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _analytic_contact(sc: Any, shape: str, c: np.ndarray, r_f: float) -> tuple[float, np.ndarray]:
    """Signed gap and normal (object → tip) of a tip sphere (centre c) from the object's geometry
    (ep1_scene's objects, unrotated)."""
    M = sc.object.placement
    assert np.array_equal(np.asarray(M.rotation), np.eye(3))
    o = np.asarray(M.translation)
    if shape == "sphere":
        d = c - o
        return float(np.linalg.norm(d)) - SIZE - r_f, d / np.linalg.norm(d)
    if shape == "cylinder":  # axis along world z, touched on its side
        d = (c - o) * np.array([1.0, 1.0, 0.0])
        return float(np.linalg.norm(d)) - SIZE - r_f, d / np.linalg.norm(d)
    assert shape == "plane"  # the −x face of a 5 cm box
    return float((o[0] - 0.025) - c[0]) - r_f, np.array([-1.0, 0.0, 0.0])


def _reference_qp(
    rq: RollingQP, shape: str, q: np.ndarray, v_prev: np.ndarray, second_order: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """The QP of the step at q (last q̇ v_prev): C, b, lb, ub over the active joints, the gap and
    the normal — all from the full model and the closed-form contact."""
    hand, sc = rq.hand, rq.scene
    model = hand.model
    data = model.createData()
    fid = hand.tip_frame_id(rq.finger)
    pin.forwardKinematics(model, data, q, v_prev, np.zeros(model.nv))
    pin.computeJointJacobians(model, data)
    pin.updateFramePlacements(model, data)
    J = pin.getFrameJacobian(model, data, fid, LWA)[:, rq._cols]
    r_f = hand.tip_radius(rq.finger)
    gap, n = _analytic_contact(sc, shape, data.oMf[fid].translation.copy(), r_f)
    rv = -r_f * n  # the material point at the contact, from the tip centre
    Jp = J[:3] - _skew(rv) @ J[3:]
    T = np.linalg.svd(n[None, :])[2][1:]  # any orthonormal basis of the tangent plane
    bt, bn, bw = np.zeros(2), -rq.gap_gain * gap / rq.dt, rq.omega * rq.axis
    if second_order:  # targets of the step's average velocities: − ½ dt · (the tip's J̇q̇)
        acc = pin.getFrameClassicalAcceleration(model, data, fid, LWA)
        a_c, alpha = acc.linear, acc.angular
        h = 0.5 * rq.dt
        bt = bt - h * T @ (a_c + np.cross(alpha, rv))
        bn = bn - h * n @ a_c
        bw = bw - h * alpha
    C = np.vstack([T @ Jp, n @ Jp, J[3:]])
    b = np.r_[bt, bn, bw]
    qa = q[rq._cols]
    lo, hi, vmax = hand.lower[rq._cols], hand.upper[rq._cols], hand.velocity_limit[rq._cols]
    lb = np.maximum(-vmax, (lo - qa) / rq.dt)
    ub = np.minimum(vmax, (hi - qa) / rq.dt)
    return C, b, lb, ub, gap, n


def _min_w_norm(C: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """argmin ½ xᵀ W x subject to C x = b (full row rank): W^-½ · lstsq(C W^-½, b)."""
    s = 1.0 / np.sqrt(w)
    z = np.linalg.lstsq(C * s, b, rcond=None)[0]
    return np.asarray(s * z)


CASES = [
    # (RollingQP keywords, finger, shape, q̇ tolerance)
    ({}, "finger1", "sphere", 1e-12),
    ({}, "finger2", "cylinder", 1e-12),
    ({}, "finger3", "sphere", 1e-12),  # split active joints (index arrays, not a slice)
    ({}, "finger1", "plane", 1e-12),
    ({"second_order": False}, "finger1", "sphere", 1e-12),
    ({"weights": np.r_[2.0 * np.ones(3), 0.5 * np.ones(3), np.ones(3)]}, "finger1", "cylinder", 1e-12),
    ({"solver": "daqp", "direct": False}, "finger2", "sphere", 1e-10),
    ({"direct": False}, "finger1", "sphere", 2e-6),  # OSQP at eps = 1e-7
]


@pytest.mark.parametrize(("kw", "finger", "shape", "tol"), CASES)
def test_step_solves_the_documented_qp(kw: dict[str, Any], finger: str, shape: str, tol: float) -> None:
    if kw.get("solver", "osqp") != "osqp":
        pytest.importorskip(kw["solver"])
    sc = ep1_scene(shape, SIZE, finger=finger)
    hand = sc.hand
    st = hand.state(place_hand_for_ep1(sc, finger))
    F = contact_frame(sc.contact(st, finger).normal)
    sensor = TactileSensor(2e-4, rng=11)
    twin = TactileSensor(2e-4, rng=11)  # the same draws, read the slow way
    rq = RollingQP(st, finger, F[:, 0], 0.5, 0.01, scene=sc, tactile=sensor, **kw)
    second_order = kw.get("second_order", True)
    w = np.asarray(kw.get("weights", np.ones(rq.nx)))
    rng = np.random.default_rng(0)
    others = np.setdiff1d(np.arange(hand.model.nv), rq._cols)
    compared = 0
    for leg in range(4):
        if leg:  # a new roll: random tangent axis and rate
            a, om = rng.normal(size=2), rng.uniform(0.3, 2.0) * rng.choice([-1.0, 1.0])
            rq.retarget(a[0] * F[:, 0] + a[1] * F[:, 1], om)
        v_prev = np.zeros(hand.model.nv)
        for k in range(15):
            q = rq.q
            C, b, lb, ub, gap, n = _reference_qp(rq, shape, q, v_prev, second_order and k > 0)
            s = rq.step()
            # the contact and the reading at the start of the step
            assert s.contact.distance == pytest.approx(gap, abs=1e-12)
            np.testing.assert_allclose(s.contact.normal, n, atol=1e-12)
            np.testing.assert_allclose(s.contact.point_tip, rq.hand.state(q).tip_position(finger) - rq._r * n,
                                       atol=1e-12)  # fmt: skip
            assert s.reading is not None
            slow = twin.read(hand.state(q), s.contact)
            np.testing.assert_allclose(s.reading.point_tip, slow.point_tip, atol=1e-15)
            assert s.reading.in_contact == slow.in_contact and s.reading.distance == slow.distance
            # q̇: the reference's minimum-W-norm solution when it is within the bounds
            x = s.qdot[rq._cols]
            assert np.all(s.qdot[others] == 0.0)
            ref = _min_w_norm(C, b, w)
            if np.all(ref >= lb + 1e-6) and np.all(ref <= ub - 1e-6):
                np.testing.assert_allclose(x, ref, rtol=0, atol=tol * max(1.0, float(np.abs(ref).max())))
                compared += 1
            else:  # a bound active: the backend's answer, feasible
                assert s.iterations > 0 and np.all(x >= lb - 1e-6) and np.all(x <= ub + 1e-6)
            # the residuals the step reports, from the reference's rows and targets
            e = C @ x - b
            assert s.slip_speed == pytest.approx(np.linalg.norm(e[:2]), abs=1e-12)
            assert s.normal_residual == pytest.approx(abs(e[2]), abs=1e-12)
            assert s.omega_residual == pytest.approx(np.linalg.norm(e[3:]), abs=1e-12)
            assert s.slip_speed < max(1e-8, 10 * tol)
            # the integration, and contact kept after the step: the gap shrinks by (1 − β)
            np.testing.assert_array_equal(rq.q, q + s.qdot * rq.dt)
            after, _ = _analytic_contact(sc, shape, rq.state.tip_position(finger), rq._r)
            # O(dt²) curvature error without the second-order targets (first step of a roll), O(dt³) with
            assert abs(after - (1.0 - rq.gap_gain) * gap) < (2e-6 if second_order and k > 0 else 1e-4)
            v_prev = s.qdot
    assert compared >= 40  # most steps have the bounds inactive


def test_bounds_equal_numpys_clipping_bit_for_bit() -> None:
    """_bounds (in floats) against max(−q̇max, (q_min − q)/dt), min(q̇max, (q_max − q)/dt) in
    numpy, at random configurations across and beyond the joint ranges."""
    sc = ep1_scene("sphere", 0.04)
    st = sc.hand.state(place_hand_for_ep1(sc, "finger1"))
    F = contact_frame(sc.contact(st, "finger1").normal)
    rq = RollingQP(st, "finger1", F[:, 0], 0.5, 0.01, scene=sc)
    rng = np.random.default_rng(0)
    lo, hi = sc.hand.lower[rq._cols], sc.hand.upper[rq._cols]
    vmax = sc.hand.velocity_limit[rq._cols]
    for _ in range(300):
        q = lo + (hi - lo) * rng.uniform(-0.05, 1.05, size=rq.nx)
        rq._qa[:] = q
        rq._free_steps = 0
        rq._bounds()
        qs = q * (1.0 / rq.dt)
        lb = np.maximum(-vmax, lo / rq.dt - qs)
        ub = np.minimum(vmax, hi / rq.dt - qs)
        assert rq._lb.tobytes() == lb.tobytes() and rq._ub.tobytes() == ub.tobytes()
        assert rq._lb_tol == [x - rq.eps for x in lb.tolist()]
        assert rq._ub_tol == [x + rq.eps for x in ub.tolist()]


@pytest.mark.parametrize("finger", ["finger1", "finger3"])  # contiguous / split active joints
def test_reduced_chain_model_gives_the_full_models_kinematics_bit_for_bit(finger: str) -> None:
    """The roller's kinematics run on a model reduced to the tip's chain (wrist + finger): tip
    placement, Jacobian (active columns) and classical acceleration equal the full model's, with
    the other fingers anywhere and still (q̇ = 0 there, as in a roll)."""
    sc = ep1_scene("sphere", 0.04, finger=finger)
    st = sc.hand.state(place_hand_for_ep1(sc, finger))
    F = contact_frame(sc.contact(st, finger).normal)
    rq = RollingQP(st, finger, F[:, 0], 0.5, 0.01, scene=sc)
    assert rq._reduced and rq._model.nv == rq.nx
    full = sc.hand.model
    data = full.createData()
    fid = sc.hand.tip_frame_id(finger)
    rng = np.random.default_rng(0)
    for _ in range(100):
        q = pin.randomConfiguration(full)
        v = np.zeros(full.nv)
        v[rq._cols] = rng.normal(size=rq.nx)
        rq._q[:] = q
        rq._qa[:] = q[rq._cols]
        rq._qdot[:] = v
        if rq._qdot_r is not None:
            rq._qdot_r[:] = v[rq._cols]
        rq.kinematics()
        pin.forwardKinematics(full, data, q, v, np.zeros(full.nv))
        pin.computeJointJacobians(full, data)
        J = pin.getFrameJacobian(full, data, fid, LWA)
        acc = pin.getFrameClassicalAcceleration(full, data, fid, LWA).vector
        acc_r = pin.getFrameClassicalAcceleration(rq._model, rq._data, rq._fid, LWA).vector
        assert rq._J.tobytes() == np.ascontiguousarray(J[:, rq._cols]).tobytes()
        assert acc_r.tobytes() == acc.tobytes()
        assert rq._c_view.tobytes() == data.oMf[fid].translation.tobytes()
        assert rq._R_view.tobytes() == data.oMf[fid].rotation.tobytes()
