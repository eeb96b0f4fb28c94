"""RollingQP.step against a slow, independent reference written from the QP of the module
docstring: the full (not chain-reduced) Pinocchio model, the contact in closed form from the
object's geometry (not coal), the material point's Jacobian J_p = J_v − [r]ₓ J_ω, any tangent
basis (the least-norm solution does not depend on it), and the equality-constrained
minimum-W-norm problem solved with numpy's ``lstsq`` — on several fingers, shapes, weights and
solvers, over re-targeted rolls with a fixed seed.
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
    J = pin.getFrameJacobian(model, data, fid, LWA)[:, rq.active]
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
    qa = q[rq.active]
    lo, hi, vmax = hand.lower[rq.active], hand.upper[rq.active], hand.velocity_limit[rq.active]
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
    ({"solver": "daqp", "closed_form": False}, "finger2", "sphere", 1e-10),
    ({"closed_form": False}, "finger1", "sphere", 2e-6),  # OSQP at eps = 1e-7
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
    others = np.setdiff1d(np.arange(hand.model.nv), rq.active)
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
            tip = rq.hand.state(q).tip_position(finger)
            np.testing.assert_allclose(s.contact.point_tip, tip - rq.radius * n, atol=1e-12)
            assert s.reading is not None
            slow = twin.read(hand.state(q), s.contact)
            np.testing.assert_allclose(s.reading.point_tip, slow.point_tip, atol=1e-15)
            assert s.reading.in_contact == slow.in_contact and s.reading.distance == slow.distance
            # q̇: the reference's minimum-W-norm solution when it is within the bounds
            x = s.qdot[rq.active]
            assert np.all(s.qdot[others] == 0.0)
            ref = _min_w_norm(C, b, w)
            if np.all(ref >= lb + 1e-6) and np.all(ref <= ub - 1e-6):
                np.testing.assert_allclose(x, ref, rtol=0, atol=tol * max(1.0, float(np.abs(ref).max())))
                compared += 1
            else:  # a bound active: the backend's answer, feasible
                assert not s.closed_form and np.all(x >= lb - 1e-6) and np.all(x <= ub + 1e-6)
            # the residuals the step reports, from the reference's rows and targets
            e = C @ x - b
            assert s.slip_speed == pytest.approx(np.linalg.norm(e[:2]), abs=1e-12)
            assert s.normal_residual == pytest.approx(abs(e[2]), abs=1e-12)
            assert s.omega_residual == pytest.approx(np.linalg.norm(e[3:]), abs=1e-12)
            assert s.slip_speed < max(1e-8, 10 * tol)
            # the integration, and contact kept after the step: the gap shrinks by (1 − β)
            np.testing.assert_array_equal(rq.q, q + s.qdot * rq.dt)
            after, _ = _analytic_contact(sc, shape, rq.state.tip_position(finger), rq.radius)
            # O(dt²) curvature error without the second-order targets (first step of a roll), O(dt³) with
            assert abs(after - (1.0 - rq.gap_gain) * gap) < (2e-6 if second_order and k > 0 else 1e-4)
            v_prev = s.qdot
    assert compared >= 40  # most steps have the bounds inactive
