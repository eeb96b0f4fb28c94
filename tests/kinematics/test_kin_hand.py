"""Hand model and state: FK, fingertip Jacobians vs finite differences, hand height, motions,
bad input, and a second hand (Allegro) through the same description path."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy
from hypothesis import given, settings
from hypothesis import strategies as hyp_st

from eos_svc.kinematics import (
    HAND3X3_URDF,
    ConfigurationError,
    FingerDescription,
    HandDescription,
    HandDescriptionError,
    HandModel,
    UnknownNameError,
    UrdfLoadError,
    WorkspaceError,
    load_hand,
)

RandQ = Callable[..., np.ndarray]


def _fd_point_jacobian(
    hand: HandModel, q: np.ndarray, finger: str, p_world: np.ndarray, eps: float = 1e-6
) -> np.ndarray:
    st = hand.state(q)
    p_local = st.tip_placement(finger).actInv(p_world)
    J = np.zeros((3, hand.nv))
    for i in range(hand.nv):
        dv = np.zeros(hand.nv)
        dv[i] = eps
        qp = pin.integrate(hand.model, q, dv)
        qm = pin.integrate(hand.model, q, -dv)
        st.update(qp)
        pp = st.tip_placement(finger).act(p_local)
        st.update(qm)
        pm = st.tip_placement(finger).act(p_local)
        J[:, i] = (pp - pm) / (2 * eps)
    return J


def _fd_angular_jacobian(hand: HandModel, q: np.ndarray, finger: str, eps: float = 1e-6) -> np.ndarray:
    st = hand.state(q)
    J = np.zeros((3, hand.nv))
    for i in range(hand.nv):
        dv = np.zeros(hand.nv)
        dv[i] = eps
        st.update(pin.integrate(hand.model, q, dv))
        Rp = st.tip_placement(finger).rotation
        st.update(pin.integrate(hand.model, q, -dv))
        Rm = st.tip_placement(finger).rotation
        J[:, i] = pin.log3(Rp @ Rm.T) / (2 * eps)
    return J


@pytest.mark.parametrize("hand_name", ["hand", "allegro"])
def test_tip_jacobians_match_finite_differences(
    hand_name: str, request: pytest.FixtureRequest, random_q: RandQ
) -> None:
    hand: HandModel = request.getfixturevalue(hand_name)
    rng = np.random.default_rng(7)
    for _ in range(4):
        q = random_q(hand, rng)
        st = hand.state(q)
        for f in hand.finger_names:
            c = st.tip_position(f)
            # a material point on the tip surface and one off it
            for offset in (hand.tip_radius(f) * np.array([0.6, -0.0, 0.8]), rng.normal(size=3) * 0.02):
                p = c + offset
                J = st.tip_point_jacobian(f, p)
                assert J.shape == (3, hand.nv)
                np.testing.assert_allclose(J, _fd_point_jacobian(hand, q, f, p), atol=1e-7)
            Jw = st.tip_angular_jacobian(f)
            np.testing.assert_allclose(Jw, _fd_angular_jacobian(hand, q, f), atol=1e-7)


@pytest.mark.parametrize("hand_name", ["hand", "allegro"])
def test_lazy_jacobians_equal_eager(hand_name: str, request: pytest.FixtureRequest, random_q: RandQ) -> None:
    """HandState.update computes the joint Jacobians only when a Jacobian is asked for
    (joint_jacobians): placements and Jacobians equal, to the bit, those of the eager
    computeJointJacobians(model, data, q) + updateFramePlacements at the same q — also after
    updates whose Jacobians were never asked for."""
    hand: HandModel = request.getfixturevalue(hand_name)
    rng = np.random.default_rng(11)
    st = hand.state()
    eager = hand.model.createData()
    for k in range(30):
        q = random_q(hand, rng)
        st.update(q)
        if k % 3 == 1:
            continue  # no Jacobian asked at this q: the next update must not depend on it
        pin.computeJointJacobians(hand.model, eager, q)
        pin.updateFramePlacements(hand.model, eager)
        for f in hand.finger_names:
            fid = hand.tip_frame_id(f)
            assert np.array_equal(st.data.oMf[fid].homogeneous, eager.oMf[fid].homogeneous)
            J = pin.getFrameJacobian(hand.model, eager, fid, pin.LOCAL_WORLD_ALIGNED)
            got = st.tip_angular_jacobian(f) if k % 2 else st.tip_jacobian(f)
            assert np.array_equal(got, J[3:] if k % 2 else J)
            p = st.tip_position(f) + rng.normal(size=3) * 0.01
            jid = int(hand.model.frames[fid].parentJoint)
            Jp = pin.getFrameJacobian(
                hand.model, eager, jid, pin.SE3(np.eye(3), eager.oMi[jid].actInv(p)), pin.LOCAL_WORLD_ALIGNED
            )
            assert np.array_equal(st.tip_point_jacobian(f, p), Jp[:3])
        assert np.array_equal(st.data.J, eager.J)
        for i in range(1, hand.model.njoints):
            assert np.array_equal(st.data.oMi[i].homogeneous, eager.oMi[i].homogeneous)


def test_state_consistency(hand: HandModel, random_q: RandQ) -> None:
    rng = np.random.default_rng(1)
    q = random_q(hand, rng)
    st = hand.state(q)
    data = hand.model.createData()
    pin.framesForwardKinematics(hand.model, data, q)
    for f in hand.finger_names:
        assert st.tip_placement(f).isApprox(data.oMf[hand.tip_frame_id(f)], 1e-12)
    gid = hand.tip_geometry_id("finger1")
    assert gid is not None
    assert np.allclose(st.geometry_data.oMg[gid].translation, st.tip_position("finger1"))
    # q is copy-safe
    qq = st.q
    qq[:] = 0.0
    assert np.allclose(st.q, q)


def test_live_views_follow_every_update(hand: HandModel, random_q: RandQ) -> None:
    rng = np.random.default_rng(7)
    state = hand.state()
    palm_t, palm_r = state.frame_views(hand.palm_frame_id)
    geometry = state.geometry_views()
    assert state.frame_views(hand.palm_frame_id)[0] is palm_t  # made once per state
    assert state.geometry_views() is geometry
    for view in (palm_t, palm_r, *geometry[0]):
        with pytest.raises(ValueError, match="read-only"):
            view[0] = 1.0
    for _ in range(5):
        state.update(random_q(hand, rng))
        palm = state.palm_placement()
        np.testing.assert_array_equal(palm_t, palm.translation)
        np.testing.assert_array_equal(palm_r, palm.rotation)
        oMg = state.geometry_data.oMg  # the placements at this q: the views follow them
        assert len(geometry) == hand.collision_model.ngeoms
        for gid, (t, r) in enumerate(geometry):
            np.testing.assert_array_equal(t, oMg[gid].translation)
            np.testing.assert_array_equal(r, oMg[gid].rotation)
    copy = state.copy()  # a copy has its own data, and views of it
    assert copy.frame_views(hand.palm_frame_id)[0] is not palm_t


def test_neutral_geometry(hand: HandModel) -> None:
    st = hand.state()
    p1, p2, p3 = (st.tip_position(f) for f in ("finger1", "finger2", "finger3"))
    h = hand.hand_height
    assert p1[1] > 0 and p2[1] < 0 and abs(p3[1]) < 1e-12
    assert np.isclose(p1[2], h / 2) and np.isclose(p2[2], h / 2) and np.isclose(p3[2], -h / 2)
    assert p1[0] == pytest.approx(p3[0])  # fingers straight along +x, same length
    palm = st.palm_placement().translation
    for p in (p1, p2, p3):
        assert p[0] > palm[0] + 0.1


def test_hand_height_from_geometry(hand: HandModel) -> None:
    """h equals the z distance between the upper and the lower finger bases in the URDF."""
    u = yourdfpy.URDF.load(str(HAND3X3_URDF), load_meshes=False)
    z = {j: u.joint_map[j].origin[2, 3] for j in ("finger1_j1", "finger2_j1", "finger3_j1")}
    assert z["finger1_j1"] == z["finger2_j1"]
    assert hand.hand_height == pytest.approx(z["finger1_j1"] - z["finger3_j1"], abs=1e-12)
    assert hand.hand_height == pytest.approx(0.12)


def test_link_lengths_equal(hand: HandModel) -> None:
    u = yourdfpy.URDF.load(str(HAND3X3_URDF), load_meshes=False)
    lengths = [
        np.linalg.norm(u.joint_map[j].origin[:3, 3])
        for i in (1, 2, 3)
        for j in (f"finger{i}_j2", f"finger{i}_j3", f"finger{i}_tip_joint")
    ]
    assert np.allclose(lengths, 0.04)
    assert all(hand.tip_radius(f) == 0.01 for f in hand.finger_names)


def test_closing_curls_toward_midplane(hand: HandModel) -> None:
    st = hand.state()
    for f, sign in (("finger1", -1), ("finger2", -1), ("finger3", +1)):
        q, at_limit = st.close_finger(f, 0.3)
        assert not at_limit
        assert np.allclose(q[hand.finger_q_index(f)], 0.3)
        z0 = st.tip_position(f)[2]
        z1 = hand.state(q).tip_position(f)[2]
        assert np.sign(z1 - z0) == sign
    q, at_limit = st.close_finger("finger2", 5.0)
    assert at_limit and np.allclose(q[hand.finger_q_index("finger2")], 1.8)
    q, at_limit = st.close_finger("finger2", -5.0)
    assert at_limit and np.allclose(q[hand.finger_q_index("finger2")], -0.3)


def test_move_wrist_and_integrate(hand: HandModel) -> None:
    st = hand.state()
    q = st.move_wrist(np.array([0.1, -0.05, 0.02]), drpy=np.array([0.0, 0.1, 0.0]))
    assert np.allclose(q[hand.wrist_q_index], [0.1, -0.05, 0.02, 0.0, 0.1, 0.0])
    st2 = hand.state(hand.state().move_wrist(np.array([0.1, -0.05, 0.02])))
    assert np.allclose(st2.palm_placement().translation, [0.1, -0.05, 0.02])
    assert np.allclose(st2.tip_position("finger1") - st.tip_position("finger1"), [0.1, -0.05, 0.02])
    with pytest.raises(WorkspaceError, match="wrist_x"):
        st.move_wrist(np.array([0.6, 0.0, 0.0]))
    assert np.isclose(st.move_wrist(np.array([0.6, 0.0, 0.0]), clip=True)[0], 0.5)
    v = np.zeros(hand.nv)
    v[hand.finger_v_index("finger3")] = 1.0
    q = st.integrate(v, 0.1)
    assert np.allclose(q[hand.finger_q_index("finger3")], 0.1)


def test_bad_configurations(hand: HandModel) -> None:
    st = hand.state()
    with pytest.raises(ConfigurationError, match=r"q: expected shape \(15,\)"):
        st.update(np.zeros(14))
    q = hand.neutral()
    q[3] = np.nan
    with pytest.raises(ConfigurationError, match="non-finite entries at indices \\[3\\]"):
        st.update(q)
    with pytest.raises(ConfigurationError):
        hand.validate_q("abc")
    assert np.allclose(st.q, hand.neutral())  # a rejected update leaves the state unchanged
    with pytest.raises(ValueError):
        st.integrate(np.zeros(3), 0.1)


def test_unknown_names(hand: HandModel) -> None:
    st = hand.state()
    with pytest.raises(UnknownNameError, match="finger4"):
        st.tip_position("finger4")
    with pytest.raises(UnknownNameError, match="frame"):
        st.frame_placement("nope")
    with pytest.raises(UnknownNameError, match="joint"):
        hand.joint_q_index("nope")
    with pytest.raises(ValueError):
        hand.finger_q_index("thumb")


def test_bad_urdf(tmp_path: Path) -> None:
    with pytest.raises(UrdfLoadError, match="no such file"):
        load_hand(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(UrdfLoadError, match="urdf_path"):
        load_hand(bad)


def _desc(**changes: object) -> HandDescription:
    d = HandDescription.hand3x3()
    fingers = list(d.fingers)
    f0 = changes.pop("finger0", None)
    if isinstance(f0, FingerDescription):
        fingers[0] = f0
    return HandDescription(
        fingers=tuple(fingers),
        wrist_joints=changes.pop("wrist_joints", d.wrist_joints),  # type: ignore[arg-type]
        opposing_finger=changes.pop("opposing_finger", d.opposing_finger),  # type: ignore[arg-type]
        palm_frame=changes.pop("palm_frame", d.palm_frame),  # type: ignore[arg-type]
    )


def _f1(**kw: object) -> HandDescription:
    args: dict[str, object] = {
        "name": "finger1",
        "joints": ("finger1_j1", "finger1_j2", "finger1_j3"),
        "tip_frame": "finger1_tip",
        "tip_radius": 0.01,
        "tip_geometry": "finger1_tip_0",
    }
    args.update(kw)
    return _desc(finger0=FingerDescription(**args))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: _f1(joints=("finger1_j1", "nope")), "finger1.joints"),
        (lambda: _f1(tip_frame="no_frame", tip_geometry=None), "finger1.tip_frame"),
        (lambda: _f1(tip_radius=0.02), "finger1.tip_radius"),
        (lambda: _f1(tip_geometry="ghost"), "finger1.tip_geometry"),
        (lambda: _f1(tip_frame="finger1_link3"), "finger1.tip"),
        (lambda: _desc(palm_frame="hand"), "palm_frame"),
        (lambda: _desc(wrist_joints=("wrist_x", "wrist_q")), "wrist_joints"),
    ],
)
def test_description_mismatch(make: Callable[[], HandDescription], field: str) -> None:
    with pytest.raises(HandDescriptionError) as exc:
        load_hand(HAND3X3_URDF, make())
    assert exc.value.field.startswith(field)


def test_description_validation() -> None:
    with pytest.raises(HandDescriptionError, match="tip_radius"):
        FingerDescription("f", ("a",), "t", -0.01)
    with pytest.raises(HandDescriptionError, match="tip_radius"):
        FingerDescription("f", ("a",), "t", float("nan"))
    with pytest.raises(HandDescriptionError, match="opposing_finger"):
        _desc(opposing_finger="finger9")
    with pytest.raises(HandDescriptionError, match="already belongs"):
        _desc(wrist_joints=("finger1_j1",))


def test_allegro_second_hand(allegro: HandModel) -> None:
    assert allegro.nq == 16
    assert allegro.finger_names == ("index", "middle", "ring", "thumb")
    assert allegro.opposing_finger == "thumb"
    assert len(allegro.wrist_q_index) == 0
    assert allegro.hand_height > 0.0
    st = allegro.state()
    assert np.isfinite(st.tip_position("thumb")).all()
    _, at_limit = st.close_finger("index", 0.2)
    assert not at_limit
    with pytest.raises(WorkspaceError):
        st.move_wrist(np.zeros(3))


@settings(max_examples=60, deadline=None)
@given(
    st_q=hyp_st.lists(hyp_st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=0, max_size=17)
)
def test_validate_q_fuzz(hand: HandModel, st_q: list[float]) -> None:
    """Any list either validates (15 finite numbers) or raises ConfigurationError."""
    ok = len(st_q) == 15 and all(np.isfinite(st_q))
    if ok:
        assert np.array_equal(hand.validate_q(st_q), np.array(st_q))
        assert np.array_equal(hand.validate_q(np.array(st_q)), np.array(st_q))
    else:
        with pytest.raises(ConfigurationError):
            hand.validate_q(st_q)
        with pytest.raises(ConfigurationError):
            hand.validate_q(np.array(st_q))


def test_point_jacobian_accepts_lists(hand: HandModel) -> None:
    st = hand.state()
    p = st.tip_position("finger1")
    assert np.allclose(st.tip_point_jacobian("finger1", p.tolist()), st.tip_point_jacobian("finger1", p))
    with pytest.raises(ConfigurationError, match="point_world"):
        st.tip_point_jacobian("finger1", [1.0, 2.0])
