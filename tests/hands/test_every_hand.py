"""Every registered hand, through the fixtures eos_svc ships (eos_svc.testing.pytest_plugin):
loaded from its description, its fingers close toward the grasp centre, it plans the scene's
sphere to a good grasp and Drake finds the grasp held."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import plan
from eos_svc.hands import DescribedHand, HandRegistry
from eos_svc.validation import validate_grasp


def test_the_fixtures_cover_every_registered_hand(eos_hand_names):
    assert eos_hand_names == HandRegistry().names
    assert {"hand3x3", "allegro", "trifinger", "panda", "g1_dex3"} <= set(eos_hand_names)


def test_hand_matches_its_description(eos_hand):
    assert isinstance(eos_hand, DescribedHand)
    spec = eos_hand.spec
    assert eos_hand.finger_names == spec.finger_names
    assert eos_hand.opposing_finger == spec.opposing_finger
    assert len(eos_hand.wrist_q_index) == 6
    q = eos_hand.neutral()
    assert eos_hand.within_limits(q)
    for f in spec.fingers:
        assert eos_hand.tip_radius(f.name) == f.tip.radius
        # the tip geometry is a coal sphere of the described radius
        gid = eos_hand.tip_geometry_id(f.name)
        assert gid is not None
        assert eos_hand.collision_model.geometryObjects[gid].geometry.radius == pytest.approx(f.tip.radius)


def test_closing_brings_each_tip_nearer_the_grasp_centre(eos_hand, eos_hand_context):
    """The closing direction of every joint is right: from the finger's open end of its sweep,
    closing by half its range brings the tip nearer the grasp centre (palm frame)."""
    centre = np.asarray(eos_hand_context.params.grasp_centre)
    for finger, sweep in eos_hand_context.sweeps.items():
        start = float(np.linalg.norm(sweep.points[0] - centre))
        half = float(np.linalg.norm(sweep.points[len(sweep.points) // 2] - centre))
        assert half < start, finger


def test_the_scene_world_holds_the_hand_and_the_object(
    eos_world, eos_hand, eos_hand_context, eos_scene_request
):
    assert eos_world.hand is eos_hand
    reach = 0.8 * eos_hand_context.opening.curved
    assert eos_world.obj.diameter == pytest.approx(min(0.5 * eos_hand.hand_height, reach))
    assert np.array_equal(eos_world.state.q, eos_hand.neutral())
    assert eos_scene_request.obj.shape == "sphere"


def test_every_hand_grasps_the_scene_sphere_and_drake_holds_it(eos_hand, eos_hand_context, eos_scene_request):
    result = plan(eos_scene_request, context=eos_hand_context, keep_trace=False)
    assert result.status == "success", result.reason
    assert result.good_grasp and result.force_closure
    assert all(c["touching"] for c in result.contacts.values())
    check = validate_grasp(result, hand=eos_hand, directions=2, seconds=0.5)
    assert check.held, check.reason


def test_every_hand_builds_the_drake_world_and_its_table_carries_the_object(
    eos_hand_context, eos_scene_request
):
    """The Drake world (``--world drake``) is built from the same description for every hand:
    stepped for half a second with the hand open above, the object stays on the table and the
    table carries its weight."""
    from eos_svc.agents import build_world
    from eos_svc.drivers.drake_world import DrakeDriver
    from eos_svc.drivers.lift_test import GRAVITY

    world = build_world(eos_scene_request, context=eos_hand_context)
    driver = DrakeDriver(world, eos_scene_request.obj, eos_scene_request.friction)
    assert driver.hand is eos_hand_context.hand
    plant = driver._plant
    plant.advance(0.5)
    assert driver.object_moved() < 5e-4
    table = [f for other, _, _normal, f in plant.object_contacts() if other == 0]
    assert sum(table) == pytest.approx(plant.settings.mass * GRAVITY, rel=0.02)
