"""EP2's guarded probe: it stops at first touch, never lets another part of the hand touch, and
reports where it touched; for every object shape, on random probes and on a closed form.
"""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world
from eos_svc.world.probe_motion import guarded_probe

OBJECTS = [
    ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.0, 0.0)),
    ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.21, 0.0, 0.0), (0.2, 0.3, 0.1)),
    ObjectSpec("cylinder", {"radius": 0.025, "length": 0.08}, (0.21, 0.0, 0.0), (1.2, 0.1, 0.0)),
    ObjectSpec("ellipsoid", {"radii": (0.035, 0.03, 0.025)}, (0.21, 0.0, 0.0), (0.3, 0.2, 0.5)),
    ObjectSpec("capsule", {"radius": 0.02, "length": 0.06}, (0.21, 0.0, 0.0), (1.5708, 0.0, 0.0)),
]


def random_probes(world, rng, n):
    """Probes toward (and past) the object from around it: down onto the top, up under it,
    sideways, slanted; short and long travels; both exploring fingers."""
    centre = np.asarray(world.obj.placement.translation)
    for k in range(n):
        finger = world.probe.finger("top" if k % 3 else "bottom")
        direction = rng.normal(size=3)
        direction[2] += -2.0 if finger == world.probe.finger("top") else 2.0
        direction /= np.linalg.norm(direction)
        # every fourth from far away: exact_clearance's plain bound (gap − hand_bound) there
        reach = rng.uniform(0.25, 0.3) if k % 4 == 3 else rng.uniform(0.03, 0.08)
        start = centre - direction * reach + rng.uniform(-0.03, 0.03, size=3)
        yield finger, start, direction, float(rng.uniform(0.005, 0.12)), world.probe.angles[finger]


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
def test_a_probe_stops_at_first_touch_and_only_the_tip_touches(spec):
    world = build_world(PlanRequest(obj=spec, seed=3))
    hand = world.hand
    tol = world.params.contact_tolerance
    events = set()
    for finger, start, direction, travel, angle in random_probes(world, np.random.default_rng(7), 40):
        out = guarded_probe(world, finger, start, direction, travel, angle)
        events.add(out.event)
        tip = hand.tip_geometry_id(finger)
        others = [g for g in range(hand.collision_model.ngeoms) if g != tip]
        if out.event in ("touched", "missed"):  # no other geometry within half the tolerance
            assert min(world.scene.gap(world.state, g) for g in others) > 0.5 * tol - 1e-9
        if out.event == "touched":  # stopped within the tolerance, not inside the object
            assert 0.0 <= world.tip_distance(finger) <= tol
            assert out.travelled <= travel + 0.06 + 1e-12  # a start backed off by up to 6 cm
        elif out.event == "missed":  # the whole travel, the tip never within the tolerance
            back = out.travelled - travel  # the whole travel from a start backed off 0–6 cm
            assert min(abs(back - b) for b in (0.0, 0.02, 0.04, 0.06)) < 1e-9
            assert world.tip_distance(finger) > tol
    assert {"touched", "missed"} <= events  # the probes exercise the paths that matter


def test_a_probe_down_onto_a_sphere_touches_its_top():
    """Straight down over a sphere's centre: the tip stops on the vertical through it, its
    centre R + tip radius above the sphere's centre within the contact tolerance."""
    radius, centre = 0.03, np.array([0.21, 0.0, 0.0])
    world = build_world(
        PlanRequest(obj=ObjectSpec("sphere", {"radius": radius}, tuple(centre)), seed=1, tactile_noise=0.0)
    )
    finger = world.probe.finger("top")
    out = guarded_probe(
        world,
        finger,
        centre + np.array([0.0, 0.0, 0.08]),
        np.array([0.0, 0.0, -1.0]),
        0.1,
        world.probe.angles[finger],
    )
    assert out.event == "touched"
    tip_radius = np.linalg.norm(out.centre - centre) - radius - world.tip_distance(finger)
    assert out.centre[:2] == pytest.approx(centre[:2], abs=1e-9)
    assert out.travelled == pytest.approx(0.08 - radius - tip_radius, abs=world.params.contact_tolerance)
    assert out.normal == pytest.approx([0.0, 0.0, 1.0], abs=1e-6)
