"""urdf/hand3x3.urdf: loads cleanly in Pinocchio, passes yourdfpy, has the agreed structure."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

from eos_svc.kinematics import HAND3X3_URDF, HandModel, load_hand

WRIST = ["wrist_x", "wrist_y", "wrist_z", "wrist_roll", "wrist_pitch", "wrist_yaw"]
FINGER_JOINTS = [f"finger{i}_j{k}" for i in (1, 2, 3) for k in (1, 2, 3)]


def test_file_is_in_repo() -> None:
    assert HAND3X3_URDF.is_file()
    assert HAND3X3_URDF.parent.name == "urdf"


def test_pinocchio_loads_without_warnings(capfd: pytest.CaptureFixture[str]) -> None:
    model = pin.buildModelFromUrdf(str(HAND3X3_URDF))
    gmodel = pin.buildGeomFromUrdf(model, str(HAND3X3_URDF), pin.COLLISION)
    vmodel = pin.buildGeomFromUrdf(model, str(HAND3X3_URDF), pin.VISUAL)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert model.nq == model.nv == 15
    assert gmodel.ngeoms == vmodel.ngeoms == 13
    assert load_hand().load_warnings == ""


def test_joint_order_and_names(hand: HandModel) -> None:
    assert list(hand.model.names)[1:] == WRIST + FINGER_JOINTS
    for i in (1, 2, 3):
        assert hand.model.existFrame(f"finger{i}_tip")


def test_limits(hand: HandModel) -> None:
    m = hand.model
    assert np.allclose(m.lowerPositionLimit[:3], -0.5) and np.allclose(m.upperPositionLimit[:3], 0.5)
    assert np.allclose(m.lowerPositionLimit[6:], -0.3) and np.allclose(m.upperPositionLimit[6:], 1.8)
    assert np.allclose(m.velocityLimit[6:], 2.0)
    assert np.all(m.velocityLimit > 0) and np.all(m.effortLimit > 0)


def test_collision_primitives(hand: HandModel) -> None:
    kinds = {g.name: type(g.geometry).__name__ for g in hand.collision_model.geometryObjects}
    assert kinds["palm_0"] == "Box"
    for i in (1, 2, 3):
        assert kinds[f"finger{i}_tip_0"] == "Sphere"
        for k in (1, 2, 3):
            assert kinds[f"finger{i}_link{k}_0"] == "Cylinder"


def test_inertias_valid(hand: HandModel) -> None:
    for inertia in list(hand.model.inertias)[1:]:
        assert inertia.mass > 0
        w = np.linalg.eigvalsh(inertia.inertia)
        assert np.all(w > 0)
        a, b, c = sorted(w)
        assert a + b >= c * (1 - 1e-9)  # triangle inequality of principal moments


def test_yourdfpy_parses_and_agrees(hand: HandModel) -> None:
    u = yourdfpy.URDF.load(str(HAND3X3_URDF), build_scene_graph=True, load_meshes=False)
    assert u.validate()
    assert list(u.actuated_joint_names) == WRIST + FINGER_JOINTS
    # Same forward kinematics at a random configuration.
    rng = np.random.default_rng(3)
    q = hand.lower + (hand.upper - hand.lower) * rng.random(hand.nq)
    u.update_cfg(q)
    st = hand.state(q)
    for i in (1, 2, 3):
        T = u.get_transform(f"finger{i}_tip", "world")
        assert np.allclose(T[:3, 3], st.tip_position(f"finger{i}"), atol=1e-9)
        assert np.allclose(T[:3, :3], st.tip_placement(f"finger{i}").rotation, atol=1e-9)
