"""What the view draws matches the models: object poses, hand parts, every shape end to end."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.planner import make_object
from eos_svc.schema.request import ObjectSpec
from eos_svc.view.replay_html import plan_scene
from eos_svc.view.scene import CONTACTS, OBJECT, HandDrawing, object_shape, touching_contacts

SHAPES = [
    ObjectSpec("sphere", {"radius": 0.025}, (0.2, -0.01, 0.0), (0.0, 0.0, 0.0)),
    ObjectSpec("ellipsoid", {"radii": (0.03, 0.025, 0.02)}, (0.21, 0.0, -0.01), (0.1, -0.2, 0.4)),
    ObjectSpec("cylinder", {"radius": 0.02, "length": 0.07}, (0.2, 0.01, 0.0), (0.3, 0.0, 0.2)),
    ObjectSpec("capsule", {"radius": 0.018, "length": 0.05}, (0.22, 0.0, 0.01), (0.0, 0.4, 0.0)),
    ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.22, 0.01, 0.0), (0.0, 0.0, 0.4)),
]


@pytest.mark.parametrize("spec", SHAPES, ids=[s.shape for s in SHAPES])
def test_object_pose_is_the_planners(spec):
    _, pose = object_shape(spec)
    placement = make_object(spec).placement
    assert np.allclose(pose.rotation().matrix(), placement.rotation, atol=1e-12)
    assert np.allclose(pose.translation(), placement.translation, atol=1e-12)


def test_fingertips_are_drawn_at_the_tip_frames(eos_hand):
    """Every registered hand (the eos_hand fixture): the 3-D view draws each from its model."""
    hand = eos_hand
    drawing = HandDrawing(hand)
    rng = np.random.default_rng(7)
    wrist = hand.wrist_q_index
    for _ in range(5):
        q = hand.neutral()
        q[wrist[:3]] = rng.uniform(-0.05, 0.05, 3)
        q[wrist[3:6]] = rng.uniform(-0.3, 0.3, 3)
        for finger in hand.finger_names:
            idx = hand.finger_q_index(finger)
            q[idx] = rng.uniform(hand.lower[idx], hand.upper[idx])
        poses = drawing.poses(q)
        state = hand.state(q)
        for finger in hand.finger_names:
            tip = hand.tip_geometry_id(finger)
            assert drawing.parts[tip].path.endswith(hand.collision_model.geometryObjects[tip].name)
            assert np.allclose(poses[tip].translation(), state.tip_position(finger), atol=1e-9)


@pytest.mark.parametrize(
    ("spec", "seed"), list(zip(SHAPES, (11, 12, 13, 14, 15), strict=True)), ids=[s.shape for s in SHAPES]
)
def test_every_shape_planned_and_drawn(spec, seed):
    result = plan(PlanRequest(obj=spec, seed=seed))
    scene = plan_scene(result.request, [r.to_dict() for r in result.trace], result.to_dict())
    assert scene.meshcat.HasPath(OBJECT)
    touching = touching_contacts(result.contacts)
    assert scene.contacts == len(touching)
    assert all(scene.meshcat.HasPath(f"{CONTACTS}/{finger}") for finger, _, _ in touching)
    assert len(scene.info["cycles"]) == result.cycles
    if result.q_final is not None:
        assert np.allclose(scene.timeline.keyframes[-1][1], result.q_final, atol=1e-7)


def test_a_damaged_result_draws_no_contacts():
    """Contacts that are not a mapping, points or normals that are not 3-vectors, a friction that
    is not a number: nothing drawn for them, nothing raised."""
    result = plan(PlanRequest(seed=1))
    records = [r.to_dict() for r in result.trace]
    for contacts in (
        ["a", "list"],
        {"finger1": {"touching": True, "point": [0, 0], "normal": [0, 0, 1]}},
        {"finger1": {"touching": True, "point": [0, 0, 0], "normal": "up"}},
    ):
        for record in records:  # the end agent's verdict too
            for change in record["changes"]:
                if change["key"] == "grasp_outcome":
                    change["new"] = {**change["new"], "contacts": contacts}
        scene = plan_scene(result.request, records, {"contacts": contacts, "friction": "high"})
        assert scene.contacts == 0 and not scene.meshcat.HasPath(CONTACTS)
    good = plan_scene(result.request, records, {"contacts": result.contacts, "friction": "high"})
    assert good.contacts == 3  # drawn with the default μ
