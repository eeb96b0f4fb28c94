"""Active touch: EP2 probes the faces a fit leaves open, with a finger hooked round the object
for a face turned away from the hand."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.agents.planner import build_world
from eos_svc.agents.probe_plan import HOOK_ANGLE, HOOK_ANGLES, REACH_FRACTIONS, targeted_probes
from eos_svc.world.probe_motion import guarded_probe


@pytest.mark.parametrize("finger", ["finger1", "finger3"])
def test_a_hooked_finger_touches_a_face_turned_away(finger):
    spec = ObjectSpec("box", {"size": [0.2, 0.09, 0.1]}, (0.3, 0.04, -0.12))
    world = build_world(PlanRequest(obj=spec, seed=1))
    back = 0.3 + 0.1
    for dz in (0.02, 0.0, -0.02):
        start = np.array([back + 0.04, 0.04, -0.12 + dz])
        out = guarded_probe(world, finger, start, np.array([-1.0, 0.0, 0.0]), 0.08, HOOK_ANGLE)
        assert out.event == "touched"
        # the tip, not a link, met the back face: its centre one tip radius behind it
        assert out.centre[0] - back == pytest.approx(world.hand.tip_radius(finger), abs=2e-4)
        assert out.normal[0] > 0.99
    # a straight finger cannot: its links lead
    west = np.array([-1.0, 0.0, 0.0])
    out = guarded_probe(world, finger, np.array([back + 0.04, 0.04, -0.12]), west, 0.08, 0.0)
    assert out.event == "blocked"


def test_probes_of_open_faces_start_beyond_and_move_inward():
    spec = ObjectSpec("box", {"size": [0.2, 0.06, 0.06]}, (0.25, 0.0, 0.0))
    world = build_world(PlanRequest(obj=spec, seed=1))
    faces = [
        {"centre": [0.3, 0.0, 0.0], "normal": [1.0, 0.0, 0.0], "half": 0.05, "delta_chi2": 0.0},
        {"centre": [0.25, 0.03, 0.0], "normal": [0.0, 1.0, 0.0], "half": 0.03, "delta_chi2": 0.0},
    ]
    probes = targeted_probes(world, faces, 0.03)
    # the first of each face's group: from beyond the fitted face by twice its half size and
    # the stand-off, moving inward past it
    back = next(p for p in probes if p.group == 0)
    side = next(p for p in probes if p.group == 1)
    assert back.angle == HOOK_ANGLE and side.angle == world.probe.angles[side.finger]
    for probe, face in zip((back, side), faces, strict=True):
        n = np.asarray(face["normal"])
        assert np.allclose(probe.direction, -n)
        assert float((probe.start - face["centre"]) @ n) == pytest.approx(max(0.05, 2 * face["half"]) + 0.03)
        assert probe.travel > float((probe.start - face["centre"]) @ n)
    # the alternatives of a face: the other finger, a deeper hook, nearer starts, off-centre points
    alternatives = [p for p in probes if p.group == 0 and p.yaw == 0.0]
    assert {p.finger for p in alternatives} == {"finger1", "finger3"}
    assert {p.angle for p in alternatives} == set(HOOK_ANGLES)
    # 5 points per reach; reaches 0.1 m, then 0.05 m (the least) twice
    assert len({tuple(np.round(p.start, 6)) for p in alternatives}) == 2 * 5 < len(REACH_FRACTIONS) * 5
    out = guarded_probe(world, back.finger, back.start, back.direction, back.travel, back.angle)
    assert out.event == "touched" and out.centre[0] == pytest.approx(0.35 + 0.01, abs=2e-4)
    # after the hooks, the face turned away from the side: the wrist turned a quarter turn either
    # way, the start shifted toward the hand; a side face gets none
    turned = [p for p in probes if p.yaw != 0.0]
    assert turned and all(p.group == 0 for p in turned)
    order = [p.yaw != 0.0 for p in probes if p.group == 0]
    assert order == sorted(order)  # every turned probe after the unturned ones
    assert {round(p.yaw, 5) for p in turned} == {round(np.pi / 2, 5), round(-np.pi / 2, 5)}
    for p in turned:
        assert np.allclose(p.direction, [-1.0, 0.0, 0.0]) and p.start[0] > 0.3


def test_a_parallel_jaw_feels_a_face_turned_away_only_from_the_side():
    """The Panda's jaw cannot curl a finger back, and its hand body, 204 mm tall, sits 38 mm
    behind the tips: a straight probe onto a 50 mm cube's back face is blocked; with the wrist
    turned a quarter turn, the hand beside the cube, the tip touches the back face (its centre
    one tip radius behind it, the normal along +x)."""
    from eos_svc.hands import load_hand_named
    from eos_svc.world.hand_context import HandContext

    context = HandContext.build(load_hand_named("panda"))
    spec = ObjectSpec("box", {"size": [0.05, 0.05, 0.05]}, (0.21, 0.02, -0.015))
    world = build_world(PlanRequest(obj=spec, seed=1), context=context)
    finger, back = world.probe.top, 0.235
    angle = world.probe.angles[finger]
    start = np.array([back + 0.05, 0.02 - 0.012, -0.015])
    west = np.array([-1.0, 0.0, 0.0])
    assert guarded_probe(world, finger, start, west, 0.08, angle).event == "blocked"
    for yaw in (np.pi / 2, -np.pi / 2):
        side_start = start if yaw > 0 else start + np.array([0.0, 0.024, 0.0])
        out = guarded_probe(world, finger, side_start, west, 0.08, angle, yaw)
        assert out.event == "touched", out.why
        assert out.centre[0] - back == pytest.approx(world.hand.tip_radius(finger), abs=2e-4)
        assert out.normal[0] > 0.99


def test_a_long_box_is_known_and_grasped_with_its_back_felt():
    # 20 cm along the approach: the hand's first probes cannot see its back face
    spec = ObjectSpec("box", {"size": [0.2, 0.06, 0.06]}, (0.27, 0.0, 0.0))
    result = plan(PlanRequest(obj=spec, seed=2))
    assert result.good_grasp and result.status == "success"
    details = [c.detail for c in result.trace if c.chosen == "ep2"]
    assert any("active" in d for d in details)  # EP2's active touch found the back
    size = sorted(result.shape["object"]["size"])
    assert size[-1] == pytest.approx(0.2, rel=0.03)


def test_the_result_counts_touches_and_probes():
    spec = ObjectSpec("box", {"size": [0.2, 0.06, 0.06]}, (0.27, 0.0, 0.0))
    result = plan(PlanRequest(obj=spec, seed=2))
    # the touches the postulate rests on, as post_shape counted them
    assert result.touches == result.shape["evidence"]["contacts"]
    rounds = [c.detail for c in result.trace if c.chosen == "ep2"]
    assert result.probes >= result.touches and result.probes > len(rounds)
    assert result.to_dict()["touches"] == result.touches


def test_an_unsure_postulate_says_why():
    from eos_svc.agents.grasp_points import unsure

    shape = {
        "class": "box",
        "confidence": 0.05,
        "evidence": {"contacts": 30, "classes": {"box": 1.0}, "fit_rms": 0.8},
        "open_faces": [{"centre": [0.3, 0, 0], "normal": [1.0, 0.0, 0.0], "half": 0.05, "delta_chi2": 0.0}],
    }
    why = unsure(shape, 0.6)
    assert "box postulated from 30 contacts is 5% sure (the grasp needs 60%)" in why
    assert "no touch bounds its face toward [+1.00, +0.00, +0.00]" in why
    shape["open_faces"] = []
    shape["evidence"]["classes"] = {"box": 0.55, "cylinder": 0.45}
    assert "fit a box (55%) and a cylinder (45%) alike" in unsure(shape, 0.6)
    assert unsure(None, 0.6) == ""
