"""RollingQP.step (one inlined body) against the same step composed from the roller's helpers
(kinematics, contact, the tactile reading, _build, _solve_direct, the backends): every field of
every step bit for bit, over rolls that exercise each branch (second order or not, tactile fast or
not, noise, pitch, weights, contiguous or split joints, closed form or backend, re-targeted rolls).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.rolling import RollingQP, RollingQPError, RollingStep


def _reference_step(rq: RollingQP) -> RollingStep:
    """The step as the sequence of the roller's helpers (the pre-inlining code)."""
    rq.kinematics()
    contact = rq.contact()
    n = rq._n
    reading = rq._read(contact, n) if rq.tactile is not None else None
    rq._build(contact, n)
    x = rq._solve_direct() if rq.direct else None
    it = 0
    if x is None:
        if rq._bounds_infeasible():
            raise RollingQPError("joint limits leave no feasible velocity", rq.problem_copy(), rq.solver, "")
        x, it = rq._solve_osqp() if rq.solver == "osqp" else rq._solve_generic()
    res = np.matmul(rq._C, x)
    np.subtract(res, rq._b, out=res)
    r0, r1, r2, r3, r4, r5 = res.tolist()
    rq._qdot[rq._sel] = x
    if rq._qdot_r is not None:  # the reduced model's own q̇ (split active joints)
        rq._qdot_r[:] = x
    rq._qa += x * rq.dt
    if type(rq._sel) is not slice:
        rq._q[rq._sel] = rq._qa
    rq._stale = True
    rq.steps += 1
    return RollingStep(
        contact, reading, rq._qdot.copy(), math.sqrt(r0 * r0 + r1 * r1), abs(r2),
        math.sqrt(r3 * r3 + r4 * r4 + r5 * r5), it,
    )  # fmt: skip


def _fields(s: RollingStep) -> tuple[Any, ...]:
    c, rd = s.contact, s.reading
    out: tuple[Any, ...] = (
        s.qdot.tobytes(), s.slip_speed, s.normal_residual, s.omega_residual, s.iterations,
        c.finger, c.distance, c.point_tip.tobytes(), c.point_object.tobytes(), c.normal.tobytes(),
    )  # fmt: skip
    if rd is not None:
        out += (rd.finger, rd.point_tip.tobytes(), rd.normal_tip.tobytes(), rd.in_contact, rd.distance)
    return out


class _SensorSubclass(TactileSensor):
    """Not a plain TactileSensor: the step must call its read()."""


def _roll(stepper: str, kw: dict[str, Any], sensor_kw: dict[str, Any] | None, finger: str,
          shape: str, size: float, sensor_cls: type = TactileSensor) -> list[Any]:  # fmt: skip
    sc = ep1_scene(shape, size, finger=finger)
    st = sc.hand.state(place_hand_for_ep1(sc, finger))
    F = contact_frame(sc.contact(st, finger).normal)
    sensor = None if sensor_kw is None else sensor_cls(**sensor_kw)
    fast = kw.pop("fast_tactile", True)
    rq = RollingQP(st, finger, F[:, 0], 0.5, 0.01, scene=sc, tactile=sensor, **kw)
    rq.fast_tactile = fast
    out: list[Any] = []
    for leg, (axis, omega) in enumerate([(F[:, 0], 0.5), (F[:, 1], -0.8), (F[:, 0] + F[:, 1], 1.2)]):
        if leg:
            rq.retarget(axis, omega)
        for _ in range(12):
            s = rq.step() if stepper == "step" else _reference_step(rq)
            out.append(_fields(s))
    out.append(rq.q.tobytes())
    return out


CASES = [
    ({}, {"noise_std": 2e-4, "rng": 3}, "finger1", "sphere", 0.04),
    ({"direct": False}, {"noise_std": 2e-4, "rng": 3}, "finger1", "sphere", 0.04),
    ({"second_order": False}, {"noise_std": 0.0}, "finger1", "sphere", 0.04),
    ({}, None, "finger3", "sphere", 0.03),  # split active joints (index arrays, not a slice)
    ({}, {"noise_std": 1e-4, "pitch": 1e-3, "rng": 5}, "finger1", "cylinder", 0.03),
    ({"weights": np.r_[2.0 * np.ones(6), np.ones(3)]}, {"rng": 1}, "finger1", "sphere", 0.04),
    ({"fast_tactile": False}, {"noise_std": 2e-4, "rng": 2}, "finger1", "sphere", 0.04),
    ({"solver": "daqp", "direct": False}, {"noise_std": 2e-4, "rng": 4}, "finger2", "sphere", 0.04),
]


@pytest.mark.parametrize(("kw", "sensor_kw", "finger", "shape", "size"), CASES)
def test_step_equals_the_helper_sequence_bit_for_bit(kw, sensor_kw, finger, shape, size) -> None:
    if kw.get("solver", "osqp") != "osqp":
        pytest.importorskip(kw["solver"])
    a = _roll("step", dict(kw), sensor_kw, finger, shape, size)
    b = _roll("reference", dict(kw), sensor_kw, finger, shape, size)
    assert len(a) == len(b) == 37
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        assert x == y, f"step {i} differs"


def test_step_calls_a_sensor_subclass_read() -> None:
    a = _roll("step", {}, {"noise_std": 2e-4, "rng": 7}, "finger1", "sphere", 0.04, _SensorSubclass)
    b = _roll("reference", {}, {"noise_std": 2e-4, "rng": 7}, "finger1", "sphere", 0.04, _SensorSubclass)
    assert a == b


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
    import pinocchio as pin

    sc = ep1_scene("sphere", 0.04, finger=finger)
    st = sc.hand.state(place_hand_for_ep1(sc, finger))
    F = contact_frame(sc.contact(st, finger).normal)
    rq = RollingQP(st, finger, F[:, 0], 0.5, 0.01, scene=sc)
    assert rq._reduced and rq._model.nv == rq.nx
    full = sc.hand.model
    data = full.createData()
    fid = sc.hand.tip_frame_id(finger)
    lwa = pin.LOCAL_WORLD_ALIGNED
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
        J = pin.getFrameJacobian(full, data, fid, lwa)
        acc = pin.getFrameClassicalAcceleration(full, data, fid, lwa).vector
        acc_r = pin.getFrameClassicalAcceleration(rq._model, rq._data, rq._fid, lwa).vector
        assert rq._J.tobytes() == np.ascontiguousarray(J[:, rq._cols]).tobytes()
        assert acc_r.tobytes() == acc.tobytes()
        assert rq._c_view.tobytes() == data.oMf[fid].translation.tobytes()
        assert rq._R_view.tobytes() == data.oMf[fid].rotation.tobytes()
