"""Other hands: the planner with the Allegro hand of example-robot-data.

The Allegro URDF is found from the installed example-robot-data distribution and put on the
planner's six wrist joints (its description ``eos_svc/hands/data/allegro.toml``, loaded by the
``eos_load_hand`` fixture of ``eos_svc.testing.pytest_plugin``); the planner takes its fingers,
sweeps, probe fingers and world parameters from the hand.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, build_agents, build_world, plan
from eos_svc.agents.planner import DEFAULT_RATINGS, default_hand, finger_ratings
from eos_svc.world.parameters import WorldParameters

SPHERE = ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.02, -0.015))


@pytest.fixture(scope="module")
def hand(eos_load_hand):
    return eos_load_hand("allegro")


@pytest.fixture(scope="module")
def result(hand):
    return plan(PlanRequest(obj=SPHERE, seed=1), hand=hand)


def test_allegro_loads_on_the_wrist_from_the_installed_distribution(hand):
    assert hand.urdf_path.is_file()
    assert "site-packages" in str(hand.urdf_path) or "dist-packages" in str(hand.urdf_path)
    assert hand.nq == hand.nv == 22  # six wrist joints + the Allegro's sixteen
    assert hand.description.wrist_joints[:3] == ("wrist_x", "wrist_y", "wrist_z")
    assert hand.finger_names == ("index", "middle", "ring", "thumb")
    assert hand.opposing_finger == "thumb"
    assert all(hand.tip_radius(f) == 0.012 for f in hand.finger_names)
    assert hand.load_warnings == ""
    assert len(hand.collision_model.geometryObjects) == 21  # palm box, link boxes, tip spheres
    # the pre-shape holds in the neutral configuration, within the joint limits
    q = hand.neutral()
    for joint, value in hand.spec.preshape.items():
        assert q[hand.joint_q_index(joint)] == value
    assert hand.within_limits(q)


def test_allegro_mounting_palm_faces_the_approach_thumb_opposes(hand):
    st = hand.state()
    palm = st.palm_placement()
    assert np.allclose(palm.rotation, np.eye(3))
    # straight fingers point up (+z), the thumb sits below them
    for f in ("index", "middle", "ring"):
        assert st.tip_position(f)[2] > 0.05
    assert st.tip_position("thumb")[2] < -0.08
    assert 0.15 < hand.hand_height < 0.25
    # closing: the upper fingertips come forward and down, the thumb comes up
    for f, sign in (("middle", -1.0), ("thumb", 1.0)):
        z0 = st.tip_position(f)[2]
        q, _ = st.close_finger(f, 0.5)
        moved = hand.state(q).tip_position(f)
        assert sign * (moved[2] - z0) > 0.02
        assert moved[0] > 0.05  # in front of the palm


def test_allegro_world_is_derived_from_the_hand(hand):
    params = WorldParameters.for_hand(hand)
    assert params != WorldParameters()
    assert 0.06 < params.grasp_centre[0] < 0.11 and params.grasp_centre[1:] == (0.0, 0.0)
    world = build_world(PlanRequest(obj=SPHERE, seed=1), hand)
    assert world.params == params
    assert world.probe.top == "middle" and world.probe.bottom == "thumb"
    agents = build_agents(world)
    names = [a.name for a in agents]
    assert names == [
        "index",
        "middle",
        "ring",
        "thumb",
        "wrist",
        "ep1",
        "ep2",
        "post_shape",
        "grasp_points",
        "end",
    ]
    assert [a.default for a in agents[:4]] == [0.8, 0.7, 0.6, 0.5]


def test_hand3x3_keeps_its_parameters_and_agents():
    h = default_hand()
    assert WorldParameters.for_hand(h) == WorldParameters()
    world = build_world(PlanRequest(seed=1))
    assert world.probe.top == "finger1" and world.probe.angles == {"finger1": 0.0, "finger3": 0.0}
    assert [a.name for a in build_agents(world)] == list(DEFAULT_RATINGS)
    assert finger_ratings(h.finger_names) == {"finger1": 0.8, "finger2": 0.7, "finger3": 0.6}


def test_allegro_plans_a_sphere_grasp(result):
    r = result
    assert r.status == "success", r.reason
    assert r.stages_completed == ("search", "information", "grasping")
    assert set(r.contacts) == {"index", "middle", "ring", "thumb"}
    assert all(c["touching"] for c in r.contacts.values())
    assert r.ep1_runs >= 1
    assert r.shape["class"] == "sphere"
    assert r.shape["grasp_radius"] == pytest.approx(0.03, rel=0.1)
    assert r.shape["confidence"] >= 0.6
    assert {"index", "middle", "ring", "thumb", "wrist", "ep1", "post_shape", "grasp_points", "end"} <= set(
        r.agents_run()
    )
    # the thumb's contact is below the object's centre, the others above it
    centre_z = SPHERE.position[2]
    assert r.contacts["thumb"]["point"][2] < centre_z
    for f in ("index", "middle", "ring"):
        assert r.contacts[f]["point"][2] > centre_z
    json.loads(r.to_json())


def test_allegro_plan_is_deterministic(hand, result):
    again = plan(PlanRequest(obj=SPHERE, seed=1), hand=hand)
    assert again.agents_run() == result.agents_run()
    assert [c.detail for c in again.trace] == [c.detail for c in result.trace]


@pytest.mark.parametrize(("radius", "seed"), [(0.025, 2), (0.04, 3)])
def test_allegro_grasps_other_spheres(hand, radius, seed):
    obj = ObjectSpec("sphere", {"radius": radius}, (0.2, 0.0, 0.0))
    r = plan(PlanRequest(obj=obj, seed=seed), hand=hand)
    assert r.status == "success", r.reason
    assert all(c["touching"] for c in r.contacts.values())


def test_eos_plan_hand_allegro(capsys):
    from eos_svc.cli import main

    code = main(["plan", "--hand", "allegro", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0
    assert data["status"] == "success"
    assert set(data["contacts"]) == {"index", "middle", "ring", "thumb"}
