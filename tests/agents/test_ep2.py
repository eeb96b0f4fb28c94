"""EP2 and post_shape: guarded probes, the postulate's object fields, EP1 before EP2."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.agents.planner import build_world, default_hand
from eos_svc.hands import load_hand_named
from eos_svc.world.hand_context import side_fingers
from eos_svc.world.probe_motion import guarded_probe


def world_with(spec: ObjectSpec, noise: float = 2e-4, seed: int = 1):
    return build_world(PlanRequest(obj=spec, tactile_noise=noise, seed=seed))


def test_guarded_probe_stops_at_first_touch_with_the_sensed_normal():
    world = world_with(ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.0, 0.0)), noise=2e-4)
    r = world.hand.tip_radius("finger1")
    out = guarded_probe(world, "finger1", np.array([0.15, 0.0, 0.01]), np.array([1.0, 0.0, 0.0]), 0.1, 0.0)
    assert out.event == "touched"
    assert 0.0 <= world.tip_distance("finger1") <= world.params.contact_tolerance  # touched, not pushed
    assert world.hand_clearance() >= 0.0
    true_normal = (out.centre - np.array([0.21, 0.0, 0.0])) / np.linalg.norm(
        out.centre - np.array([0.21, 0, 0])
    )
    # the tactile noise (0.2 mm on a 10 mm tip) tilts the sensed normal by ~0.02 rad
    assert math.acos(min(1.0, float(out.normal @ true_normal))) < 5 * 2e-4 / r


def test_a_probe_that_misses_records_its_free_path():
    world = world_with(ObjectSpec("sphere", {"radius": 0.02}, (0.21, 0.0, 0.0)))
    out = guarded_probe(world, "finger1", np.array([0.15, 0.0, 0.06]), np.array([1.0, 0.0, 0.0]), 0.1, 0.0)
    assert out.event == "missed"
    r = world.hand.tip_radius("finger1")
    assert len(out.free) > 5
    assert all(world.obj.signed_distance(p) >= r for p in out.free)  # the tip never touched there


def test_a_probe_another_part_would_touch_first_is_abandoned():
    # a straight finger lowered beyond a sphere's apex: its links, behind the tip, land first
    world = world_with(ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.0, 0.0)))
    out = guarded_probe(world, "finger1", np.array([0.235, 0.0, 0.06]), np.array([0.0, 0.0, -1.0]), 0.1, 0.0)
    assert out.event == "blocked"
    assert world.hand_clearance() > 0.0  # the link stopped short of the object
    assert world.tip_distance("finger1") > world.params.contact_tolerance  # the tip touches nothing


@pytest.fixture(scope="module")
def box_plan():
    spec = ObjectSpec("box", {"size": [0.046, 0.052, 0.036]}, (0.205, 0.01, -0.02), (0.0, 0.0, 0.25))
    return spec, plan(PlanRequest(obj=spec, seed=5))


def test_the_postulate_is_an_object_in_the_request_form(box_plan):
    spec, result = box_plan
    shape = result.shape
    assert shape["class"] == "box"
    assert shape["confidence"] >= 0.6
    assert shape["pose_known"] is True
    posited = ObjectSpec.from_dict(shape["object"])  # the postulate's object: what the request accepts
    assert posited.shape == "box"
    np.testing.assert_allclose(sorted(posited.size["size"]), sorted(spec.size["size"]), atol=2e-3)
    np.testing.assert_allclose(posited.position, spec.position, atol=2e-3)
    evidence = shape["evidence"]
    assert 2 < evidence["contacts"] <= 13  # EP1's two and EP2's active touch (#30: at most 13)
    assert sum(evidence["classes"].values()) == pytest.approx(1.0, abs=1e-5)
    assert "fit_rms" in evidence
    assert result.to_dict()["shape"]["object"] == shape["object"]


def test_ep1_runs_first_and_ep2_when_post_shape_asks(box_plan):
    _, result = box_plan
    info = [r for r in result.trace if r.stage == "information"]
    chosen = [r.chosen for r in info]
    assert chosen[0] == "ep1"
    first_ep2 = chosen.index("ep2")
    assert "ep1" in chosen[:first_ep2]
    before = info[first_ep2 - 1]
    assert before.chosen == "post_shape" and "asks EP2" in before.detail
    assert info[first_ep2].rating_of("ep2").opportunistic > 0.0


def test_a_capsule_is_told_from_an_ellipsoid():
    spec = ObjectSpec(
        "capsule", {"radius": 0.017, "length": 0.045}, (0.215, 0.0, -0.01), (math.pi / 2, 0.0, 0.3)
    )
    result = plan(PlanRequest(obj=spec, seed=3))
    assert result.shape["class"] == "capsule", result.shape["evidence"]


def test_ep1_repeats_while_its_curvature_is_not_trusted_then_ep2():
    # the paper's EP1 behaviour is kept: post_shape asks EP1 to roll again while EP1's own size
    # confidence is under 60 %, and only then asks EP2 for the surface
    result = plan(PlanRequest(seed=1))
    info = [r for r in result.trace if r.stage == "information"]
    details = [(r.chosen, r.detail) for r in info]
    again = next(i for i, (who, d) in enumerate(details) if who == "post_shape" and "roll again" in d)
    first_ep2 = next(i for i, (who, _) in enumerate(details) if who == "ep2")
    assert details[again + 1][0] == "ep1" and again < first_ep2
    assert result.ep1_runs >= 3
    assert result.shape["class"] == "sphere" and result.shape["confidence"] >= 0.6


@pytest.mark.parametrize(
    "make_hand", [default_hand, lambda: load_hand_named("allegro")], ids=["hand3x3", "allegro"]
)
def test_side_fingers_lead_along_plus_and_minus_y(make_hand):
    hand = make_hand()
    state = hand.state(hand.neutral())
    upper = [f for f in hand.finger_names if f != hand.description.opposing_finger]
    sides = side_fingers(hand)
    ys = {f: float(state.tip_position(f)[1]) for f in upper}
    assert set(sides) == {+1, -1} and sides[+1] in upper and sides[-1] in upper
    assert ys[sides[+1]] == max(ys.values()) and ys[sides[-1]] == min(ys.values())
