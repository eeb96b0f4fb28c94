"""Cost of one kinematics-and-contact update of the hand3x3 against a sphere.

One update = forward kinematics (with joint Jacobians), the three fingertip–object distances
with witness points and normal (``Scene.contact``), and the three fingertip Jacobians
(``HandState.tip_jacobian``: the tip frame, i.e. the fingertip sphere's centre and its angular
velocity, 6×nv). Printed beside the bare Pinocchio and coal calls doing the same work, measured
in the same run (the floor), and the ratio; also the same update with the Jacobians of the
material points at the contacts. Medians over repeated runs.

    .venv/bin/python benchmarks/bench_kinematics.py [--repeat 31] [--number 2000] [--baseline REV]

``--baseline REV`` also times the same update with ``eos_svc.kinematics`` as it was at git
revision ``REV``, in the same run, interleaved with the current code (the machine is shared).
"""

from __future__ import annotations

import argparse
import gc
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import coal
import numpy as np
import pinocchio as pin

import eos_svc.kinematics as kin_now
from eos_svc.objects import Sphere

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _baseline import load_kinematics


def median_us(fn: Callable[[], object], number: int, repeat: int) -> tuple[float, float]:
    """Median and min over ``repeat`` runs of the mean time of ``number`` calls, µs."""
    runs = []
    for _ in range(number // 10):  # warm up
        fn()
    gc_was_enabled = gc.isenabled()
    gc.disable()  # as timeit does
    try:
        for _ in range(repeat):
            t0 = time.perf_counter()
            for _ in range(number):
                fn()
            runs.append((time.perf_counter() - t0) / number * 1e6)
    finally:
        if gc_was_enabled:
            gc.enable()
    return statistics.median(runs), min(runs)


def setup(kin: ModuleType) -> tuple[Callable[[], None], dict[str, object]]:
    """The update of ``kin`` (a version of eos_svc.kinematics) and its objects."""
    hand = kin.load_hand()
    fingers = hand.finger_names
    q = hand.neutral()
    q[hand.wrist_q_index[:3]] = [0.01, 0.0, 0.0]
    for f in fingers:
        q[hand.finger_q_index(f)] = 0.15
    state = hand.state(q)
    # A sphere on the hand axis, in front of the fingertips, every tip 1–3 mm away (no contact
    # yet: the common case while closing; penetrating tips take the slower exact path).
    R, r = 0.03, hand.tip_radius(fingers[0])
    x0 = max(
        c[0] + np.sqrt((R + r + 1e-3) ** 2 - c[1] ** 2 - c[2] ** 2)
        for c in (state.tip_position(f) for f in fingers)
    )
    sphere = getattr(kin, "Sphere", Sphere)  # a baseline's kinematics held the objects too
    obj = sphere(R, pin.SE3(np.eye(3), np.array([x0, 0.0, 0.0])))
    scene = kin.Scene(hand, obj)
    gaps = [scene.contact(state, f).distance for f in fingers]
    assert all(0.0 < g < 5e-3 for g in gaps), gaps

    # One update: FK (with joint Jacobians), the three fingertip-object contacts with witness
    # points and normal, the three fingertip Jacobians (tip frame: centre velocity and ω).
    def ours() -> None:
        state.update(q)
        for f in fingers:
            scene.contact(state, f)
            state.tip_jacobian(f)

    def with_point_jacobians() -> None:  # the Jacobians at the contact points instead
        state.update(q)
        for c in scene.tip_contacts(state):
            state.tip_point_jacobian(c.finger, c.point_tip)

    return ours, {
        "hand": hand,
        "q": q,
        "state": state,
        "scene": scene,
        "obj": obj,
        "with_point_jacobians": with_point_jacobians,
    }


def interleaved_us(fns: dict[str, Callable[[], None]], number: int, repeat: int) -> dict[str, float]:
    """Median µs per call of each function, timed in interleaved runs (drift hits all alike)."""
    runs: dict[str, list[float]] = {k: [] for k in fns}
    for fn in fns.values():
        for _ in range(number // 10):
            fn()
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        for _ in range(repeat):
            for k, fn in fns.items():
                t0 = time.perf_counter()
                for _ in range(number):
                    fn()
                runs[k].append((time.perf_counter() - t0) / number * 1e6)
    finally:
        if gc_was_enabled:
            gc.enable()
    return {k: statistics.median(v) for k, v in runs.items()}


def main(number: int = 2000, repeat: int = 31, baseline: str | None = None) -> dict[str, float]:
    ours, objs = setup(kin_now)
    hand, q, state, scene, obj = (objs[k] for k in ("hand", "q", "state", "scene", "obj"))
    with_point_jacobians = objs["with_point_jacobians"]
    assert callable(with_point_jacobians)
    assert isinstance(hand, kin_now.HandModel) and isinstance(q, np.ndarray)
    assert isinstance(state, kin_now.HandState) and isinstance(scene, kin_now.Scene)
    assert isinstance(obj, Sphere)
    fingers = hand.finger_names

    # The floor: the same library calls, no validation, no Python objects built.
    model, data = hand.model, hand.model.createData()
    gmodel = hand.collision_model
    gdata = pin.GeometryData(gmodel)
    fids = [hand.tip_frame_id(f) for f in fingers]
    tip = coal.Sphere(hand.tip_radius(fingers[0]))
    tf_obj, tf_tip = coal.Transform3s(), coal.Transform3s()
    tf_obj.setTranslation(obj.placement.translation)
    req, res = coal.DistanceRequest(), coal.DistanceResult()
    LWA = pin.LOCAL_WORLD_ALIGNED

    # live views of the tip centres, fetched once (data.oMf[i] from Python costs ~2 µs)
    centres = [data.oMf[fid].translation for fid in fids]
    work = list(zip(fids, centres, strict=True))

    def floor() -> None:
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        pin.updateGeometryPlacements(model, data, gmodel, gdata)
        for fid, c in work:
            pin.getFrameJacobian(model, data, fid, LWA)
            tf_tip.setTranslation(c)
            res.clear()
            coal.distance(obj.geometry, tf_obj, tip, tf_tip, req, res)
            res.getNearestPoint1()

    def fk_only() -> None:
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)

    def jac_only() -> None:
        pin.computeJointJacobians(model, data, q)
        for fid in fids:
            pin.getFrameJacobian(model, data, fid, LWA)

    def coal_only() -> None:
        res.clear()
        coal.distance(obj.geometry, tf_obj, tip, tf_tip, req, res)

    def update_only() -> None:
        state.update(q)

    pin.computeJointJacobians(model, data, q)  # the floor's own data, for the parts below
    pin.updateFramePlacements(model, data)

    def contact_only() -> None:
        scene.contact(state, "finger1")

    p_contact = scene.contact(state, "finger1").point_tip

    def tip_jac_only() -> None:
        state.tip_jacobian("finger1")

    def point_jac_only() -> None:
        state.tip_point_jacobian("finger1", p_contact)

    rows = {
        "update (FK + 3 tip Jacobians + 3 tip-object distances)": median_us(ours, number, repeat),
        "floor: bare Pinocchio + coal calls, same work": median_us(floor, number, repeat),
        "  update with Jacobians at the contact points": median_us(with_point_jacobians, number, repeat),
        "  Pinocchio FK + frame placements": median_us(fk_only, number, repeat),
        "  Pinocchio joint Jacobians + 3 frame Jacobians": median_us(jac_only, number, repeat),
        "  coal sphere-sphere distance (1)": median_us(coal_only, number, repeat),
        "  HandState.update(q)": median_us(update_only, number, repeat),
        "  Scene.contact (1 finger)": median_us(contact_only, number, repeat),
        "  HandState.tip_point_jacobian (1 finger)": median_us(point_jac_only, number, repeat),
        "  HandState.tip_jacobian (1 finger)": median_us(tip_jac_only, number, repeat),
    }
    print(
        f"python {platform.python_version()}, pinocchio {pin.__version__}, "
        f"{platform.machine()}; median (min) of {repeat} runs x {number} calls"
    )
    for name, (med, best) in rows.items():
        print(f"{name:58s} {med:8.2f} µs  ({best:.2f})")
    ratio = rows[next(iter(rows))][0] / rows["floor: bare Pinocchio + coal calls, same work"][0]
    goal = 20.0
    med = rows[next(iter(rows))][0]
    print(
        f"ratio update / floor: {ratio:.2f}; goal ≤ {goal:.0f} µs on THIS machine: "
        f"{'met' if med <= goal else 'NOT met'}"
    )
    # a yardstick of this machine's speed: compare machines (or loads) by it, not by the rows
    fk = rows["  Pinocchio FK + frame placements"][0]
    floor_us = rows["floor: bare Pinocchio + coal calls, same work"][0]
    print(
        f"calibration: FK + frame placements {fk:.2f} µs here; update = {med / fk:.1f} FK, "
        f"floor = {floor_us / fk:.1f} FK"
    )
    out = {"update_us": med, "ratio": ratio}
    if baseline is not None:
        old, _ = setup(load_kinematics(baseline))
        both = interleaved_us({"current": ours, "baseline": old, "floor": floor}, number, repeat)
        print(
            f"\nsame run, interleaved: update now {both['current']:.2f} µs, at {baseline} "
            f"{both['baseline']:.2f} µs (ratio {both['baseline'] / both['current']:.2f}); "
            f"floor {both['floor']:.2f} µs"
        )
        out["baseline_us"] = both["baseline"]
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--number", type=int, default=2000, help="calls per run")
    ap.add_argument("--repeat", type=int, default=31, help="runs (the median is reported)")
    ap.add_argument("--baseline", default=None, help="git revision to time beside the current code")
    a = ap.parse_args()
    main(a.number, a.repeat, a.baseline)
