"""eos_svc.view.picture: meshes of every primitive and the guard on missing hand state."""

from __future__ import annotations

import coal
import numpy as np
import pytest

from eos_svc.agents import PlanRequest
from eos_svc.view.picture import bounding_box_mesh, draw_result, scene_solids, shape_mesh


def _vertices(shape):
    return np.vstack(shape_mesh(shape))


def test_sphere_and_ellipsoid_meshes_lie_on_the_surface():
    v = _vertices(coal.Sphere(0.02))
    assert np.allclose(np.linalg.norm(v, axis=1), 0.02)
    radii = np.array([0.01, 0.02, 0.03])
    v = _vertices(coal.Ellipsoid(*radii))
    assert np.allclose(np.sum((v / radii) ** 2, axis=1), 1.0)


def test_box_cylinder_capsule_meshes_span_their_extent():
    v = _vertices(coal.Box(0.02, 0.04, 0.06))
    assert np.allclose(v.max(axis=0), [0.01, 0.02, 0.03]) and np.allclose(
        v.min(axis=0), [-0.01, -0.02, -0.03]
    )
    v = _vertices(coal.Cylinder(0.01, 0.05))
    assert np.allclose(np.abs(v[:, 2]).max(), 0.025) and np.linalg.norm(
        v[:, :2], axis=1
    ).max() == pytest.approx(0.01)
    v = _vertices(coal.Capsule(0.01, 0.05))
    assert v[:, 2].max() == pytest.approx(0.035) and v[:, 2].min() == pytest.approx(-0.035)


def test_unknown_shape_is_a_type_error():
    with pytest.raises(TypeError, match="cannot draw"):
        shape_mesh(coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0))


def test_scene_solids_place_the_hand_geometry():
    from eos_svc.agents import default_hand

    hand = default_hand()
    solids = scene_solids(hand.neutral(), PlanRequest(), hand)
    names = [s[0] for s in solids]
    assert names[0] == "object" and len(names) == 1 + len(hand.collision_model.geometryObjects)
    tip = dict((s[0], s[1]) for s in solids)["finger1_tip_0"]
    centre = np.vstack(tip).mean(axis=0)
    state = hand.state(hand.neutral())
    assert np.allclose(centre, state.tip_position("finger1"), atol=1e-3)


def test_draw_result_needs_the_final_configuration(tmp_path):
    data = {"q_final": None, "request": PlanRequest().to_dict(), "contacts": {}}
    with pytest.raises(ValueError, match="q_final"):
        draw_result(data, tmp_path / "x.png")


def test_other_geometry_is_drawn_as_its_bounding_box():
    v = np.vstack(bounding_box_mesh(coal.Cone(0.01, 0.04)))
    assert np.allclose(v.max(axis=0), [0.01, 0.01, 0.02]) and np.allclose(
        v.min(axis=0), [-0.01, -0.01, -0.02]
    )
