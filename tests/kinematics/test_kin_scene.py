"""Scene contacts: signed distances, witness points and normals against closed forms, for every
object shape, on random hand configurations."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.kinematics import HandModel, KinematicsError, Scene, UnknownNameError, load_hand
from eos_svc.objects import Box, Capsule, Cylinder, Ellipsoid, Sphere, SurfaceObject

RandQ = Callable[..., np.ndarray]


def _sd_box(p: np.ndarray, h: np.ndarray) -> float:
    q = np.abs(p) - h
    return float(np.linalg.norm(np.maximum(q, 0)) + min(q.max(), 0.0))


def _sd_cylinder(p: np.ndarray, r: float, hz: float) -> float:
    dr, dz = np.hypot(p[0], p[1]) - r, abs(p[2]) - hz
    return float(np.hypot(max(dr, 0.0), max(dz, 0.0)) + min(max(dr, dz), 0.0))


# Closed-form signed distance from a local point to each object (written here, independently).
SHAPES: dict[str, tuple[Callable[[], SurfaceObject], Callable[[np.ndarray], float]]] = {
    "sphere": (lambda: Sphere(0.03), lambda p: float(np.linalg.norm(p) - 0.03)),
    "box": (lambda: Box([0.04, 0.06, 0.05]), lambda p: _sd_box(p, np.array([0.02, 0.03, 0.025]))),
    "cylinder": (lambda: Cylinder(0.025, 0.08), lambda p: _sd_cylinder(p, 0.025, 0.04)),
    "capsule": (
        lambda: Capsule(0.02, 0.06),
        lambda p: float(np.linalg.norm(p - np.array([0, 0, np.clip(p[2], -0.03, 0.03)])) - 0.02),
    ),
}


def _random_placement(rng: np.random.Generator, near: np.ndarray) -> pin.SE3:
    return pin.SE3(pin.exp3(rng.normal(size=3)), near + rng.normal(size=3) * 0.03)


@pytest.mark.parametrize("shape", list(SHAPES))
def test_fingertip_distance_and_witnesses(shape: str, hand: HandModel, random_q: RandQ) -> None:
    make, sd = SHAPES[shape]
    obj = make()
    scene = Scene(hand, obj)
    rng = np.random.default_rng(21)
    st = hand.state()
    checked = 0
    for _ in range(30):
        st.update(random_q(hand, rng))
        f = hand.finger_names[int(rng.integers(3))]
        c = st.tip_position(f)
        scene.set_object_placement(_random_placement(rng, c))
        r = hand.tip_radius(f)
        expected = sd(obj.to_local(c)) - r
        con = scene.contact(st, f)
        assert con.finger == f
        tol = 1e-7 if expected > 0 else 1e-5  # EPA (penetration) converges to ~1e-6
        assert con.distance == pytest.approx(expected, abs=tol)
        assert abs(sd(obj.to_local(con.point_object))) < tol  # on the object surface
        assert abs(np.linalg.norm(con.point_tip - c) - r) < 1e-9  # on the tip sphere
        assert np.linalg.norm(con.normal) == pytest.approx(1.0)
        if expected > 1e-6:  # normal from object toward the tip centre; witnesses along it
            assert np.allclose(con.normal, (c - con.point_object) / np.linalg.norm(c - con.point_object))
            assert np.allclose(con.point_tip - con.point_object, con.distance * con.normal, atol=1e-7)
        checked += 1
    assert checked == 30


@pytest.mark.parametrize(("exact", "tol"), [(False, 1e-5), (True, 1e-9)])
def test_ellipsoid_on_axis(hand: HandModel, exact: bool, tol: float) -> None:
    st = hand.state()
    c = st.tip_position("finger3")
    a = np.array([0.05, 0.03, 0.02])
    obj = Ellipsoid(a, pin.SE3(np.eye(3), c - np.array([0.0, 0.0, 0.035])))
    scene = Scene(hand, obj, exact_tips=exact)
    con = scene.contact(st, "finger3")  # tip centre on the +z axis, 0.035 from the centre
    assert con.distance == pytest.approx(0.035 - 0.02 - 0.01, abs=1e-7)
    # coal's GJK witness on an ellipsoid is a few µm off tangentially; exact_tips is exact
    assert np.allclose(con.point_object, c - [0, 0, 0.015], atol=tol)
    assert np.allclose(con.normal, [0, 0, 1], atol=tol / 0.01)


def test_exact_tips_agree_with_coal(hand: HandModel, random_q: RandQ) -> None:
    rng = np.random.default_rng(4)
    st = hand.state()
    for make, _ in SHAPES.values():
        obj = make()
        fast, exact = Scene(hand, obj), Scene(hand, obj, exact_tips=True)
        for _ in range(5):
            st.update(random_q(hand, rng))
            c = st.tip_position("finger2")
            fast.set_object_placement(_random_placement(rng, c))
            a, b = fast.contact(st, "finger2"), exact.contact(st, "finger2")
            assert a.distance == pytest.approx(b.distance, abs=1e-5 if b.distance < 0 else 1e-8)
            if b.distance > 0:
                assert np.allclose(a.point_object, b.point_object, atol=1e-6)
                assert np.allclose(a.normal, b.normal, atol=1e-6)


def test_penetration_sphere_sphere(hand: HandModel) -> None:
    st = hand.state()
    c = st.tip_position("finger1")
    scene = Scene(hand, Sphere(0.03, pin.SE3(np.eye(3), c + np.array([0.035, 0.0, 0.0]))))
    con = scene.contact(st, "finger1")
    assert con.distance == pytest.approx(0.035 - 0.04, abs=1e-7)
    assert np.allclose(con.normal, [-1, 0, 0], atol=1e-7)
    assert np.allclose(con.point_tip, c + np.array([0.01, 0, 0]), atol=1e-7)


def test_result_is_not_stale(hand: HandModel) -> None:
    st = hand.state()
    c = st.tip_position("finger1")
    obj = Sphere(0.02)
    scene = Scene(hand, obj)
    for gap in (0.05, 0.001, 0.03):
        scene.set_object_placement(pin.SE3(np.eye(3), c + np.array([0.03 + gap, 0.0, 0.0])))
        assert scene.contact(st, "finger1").distance == pytest.approx(gap)
        assert scene.distance(st, "finger1_tip_0").distance == pytest.approx(gap)


def test_any_geometry_and_min_distance(hand: HandModel) -> None:
    st = hand.state()
    R = 0.02
    centre = np.array([-0.05, 0.0, 0.0])  # behind the palm box (half extents 0.01, 0.03, 0.075)
    scene = Scene(hand, Sphere(R, pin.SE3(np.eye(3), centre)))
    palm = scene.distance(st, "palm_0")
    assert palm.finger == "palm_0"
    assert palm.distance == pytest.approx(0.05 - 0.01 - R, abs=1e-7)
    best = scene.min_distance(st)
    assert best.finger == "palm_0" and best.distance == pytest.approx(palm.distance)
    contacts = scene.tip_contacts(st)
    assert [c.finger for c in contacts] == list(hand.finger_names)
    assert all(c.distance > palm.distance for c in contacts)


def test_link_geometry_distance_closed_form(hand: HandModel) -> None:
    """A sphere right above the middle of finger1's link2 (cylinder radius 8 mm)."""
    st = hand.state()
    M = st.geometry_placement("finger1_link2_0")
    centre = M.translation + np.array([0.0, 0.0, 0.05])
    scene = Scene(hand, Sphere(0.01, pin.SE3(np.eye(3), centre)))
    con = scene.distance(st, "finger1_link2_0")
    assert con.distance == pytest.approx(0.05 - 0.008 - 0.01, abs=1e-7)
    assert np.allclose(con.normal, [0, 0, -1], atol=1e-6)


def test_bad_names(hand: HandModel) -> None:
    scene = Scene(hand, Sphere(0.02))
    st = hand.state()
    with pytest.raises(UnknownNameError, match="finger9"):
        scene.contact(st, "finger9")
    with pytest.raises(UnknownNameError, match="geometry"):
        scene.distance(st, "nope")
    with pytest.raises(KinematicsError, match="obj"):
        Scene(hand, "sphere")  # type: ignore[arg-type]


def test_allegro_contacts(allegro: HandModel, random_q: RandQ) -> None:
    rng = np.random.default_rng(8)
    st = allegro.state(random_q(allegro, rng))
    c = st.tip_position("thumb")
    obj = Sphere(0.03, pin.SE3(np.eye(3), c + np.array([0.0, 0.05, 0.0])))
    con = Scene(allegro, obj).contact(st, "thumb")
    assert con.distance == pytest.approx(0.05 - 0.03 - 0.012, abs=1e-9)
    assert np.allclose(con.normal, [0, -1, 0])


@pytest.mark.parametrize("shape", list(SHAPES))
def test_tip_contacts_batched_closed_form(shape: str, hand: HandModel, random_q: RandQ) -> None:
    """Scene.tip_contacts (one computeDistances for every tip) against the closed forms, and
    equal to the one-finger-at-a-time contact()."""
    make, sd = SHAPES[shape]
    obj = make()
    scene = Scene(hand, obj)
    rng = np.random.default_rng(33)
    st = hand.state()
    for _ in range(20):
        st.update(random_q(hand, rng))
        centres = [st.tip_position(f) for f in hand.finger_names]
        scene.set_object_placement(_random_placement(rng, np.mean(centres, axis=0)))
        batch = scene.tip_contacts(st)
        assert [c.finger for c in batch] == list(hand.finger_names)
        for con, c in zip(batch, centres, strict=True):
            expected = sd(obj.to_local(c)) - hand.tip_radius(con.finger)
            assert con.distance == pytest.approx(expected, abs=1e-7 if expected > 0 else 1e-5)
            one = scene.contact(st, con.finger)
            assert con.distance == pytest.approx(one.distance, abs=1e-12)
            assert np.allclose(con.point_tip, one.point_tip, atol=1e-12)
            assert np.allclose(con.point_object, one.point_object, atol=1e-12)
            assert np.allclose(con.normal, one.normal, atol=1e-12)


def test_tip_contacts_follow_the_object_and_the_state(hand: HandModel) -> None:
    st = hand.state()
    c = st.tip_position("finger1")
    scene = Scene(hand, Sphere(0.02))
    for gap in (0.05, 0.001, -0.004, 0.03):  # not stale; penetration takes the exact path
        scene.set_object_placement(pin.SE3(np.eye(3), c + np.array([0.03 + gap, 0.0, 0.0])))
        assert scene.tip_contacts(st)[0].distance == pytest.approx(gap, abs=1e-9)
    with pytest.raises(KinematicsError, match="state"):
        scene.tip_contacts(load_hand().state())  # another HandModel's state


def test_tip_contacts_allegro(allegro: HandModel, random_q: RandQ) -> None:
    rng = np.random.default_rng(9)
    st = allegro.state(random_q(allegro, rng))
    centre = st.tip_position("thumb") + np.array([0.0, 0.05, 0.0])
    scene = Scene(allegro, Sphere(0.03, pin.SE3(np.eye(3), centre)))
    for con in scene.tip_contacts(st):
        one = scene.contact(st, con.finger)
        assert con.distance == pytest.approx(one.distance, abs=1e-12)
        assert np.allclose(con.point_tip, one.point_tip, atol=1e-12)


def test_contacts_own_their_arrays(hand: HandModel, random_q: RandQ) -> None:
    """A returned Contact does not change when the scene is queried again (coal's result
    object is reused between queries)."""
    rng = np.random.default_rng(5)
    st = hand.state(random_q(hand, rng))
    scene = Scene(hand, Box([0.04, 0.06, 0.05], pin.SE3(np.eye(3), st.tip_position("finger1") + 0.04)))
    first = scene.contact(st, "finger1")
    batch = scene.tip_contacts(st)
    saved = [(c.normal.copy(), c.point_tip.copy(), c.point_object.copy()) for c in (first, *batch)]
    moved = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), st.tip_position("finger3") - 0.05)
    scene.set_object_placement(moved)
    scene.contact(st, "finger2")
    scene.tip_contacts(st)
    scene.distance(st, "palm_0")
    for c, (n, pt, po) in zip((first, *batch), saved, strict=True):
        assert np.array_equal(c.normal, n)
        assert np.array_equal(c.point_tip, pt)
        assert np.array_equal(c.point_object, po)
