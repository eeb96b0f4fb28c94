"""The grasp world's gap lower bounds never exceed the exact gaps they stand for."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world
from eos_svc.hands import load_hand_named

OBJECTS = [
    ObjectSpec("sphere", {"radius": 0.03}, (0.12, 0.0, 0.0)),
    ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.12, 0.0, 0.0), (0.2, 0.3, 0.1)),
    ObjectSpec("cylinder", {"radius": 0.025, "length": 0.08}, (0.12, 0.0, 0.0), (1.2, 0.1, 0.0)),
    ObjectSpec("ellipsoid", {"radii": (0.035, 0.03, 0.025)}, (0.12, 0.0, 0.0), (0.3, 0.2, 0.5)),
    ObjectSpec("capsule", {"radius": 0.02, "length": 0.06}, (0.12, 0.0, 0.0), (1.5708, 0.0, 0.0)),
]


def random_poses(world, rng, n):
    """Configurations around the start: wrist shifted toward the object, fingers anywhere."""
    hand = world.hand
    q0 = world.state.q
    for _ in range(n):
        q = q0.copy()
        q[hand.wrist_q_index[:3]] += rng.uniform([-0.02, -0.03, -0.03], [0.08, 0.03, 0.03])
        for finger in hand.finger_names:
            idx = hand.finger_q_index(finger)
            q[idx] = rng.uniform(hand.lower[idx], hand.upper[idx])
        yield q


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
@pytest.mark.parametrize("hand_name", ["hand3x3", "allegro"])
def test_lower_bounds_never_exceed_the_exact_gaps(spec, hand_name):
    hand = load_hand_named("allegro") if hand_name == "allegro" else None
    request = PlanRequest(obj=spec)
    if hand is not None:
        request = PlanRequest(obj=ObjectSpec(spec.shape, spec.size, (0.12, 0.0, 0.0), spec.rpy))
    world = build_world(request, hand)
    rng = np.random.default_rng(3)
    n_geoms = len(world.hand.collision_model.geometryObjects)
    checked = 0
    for q in random_poses(world, rng, 40):
        world.set_q(q)
        for lower, gid in world.lower_bounds(range(n_geoms)):
            gap = world.scene.gap(world.state, gid)
            # coal's depth of a deep penetration is approximate (e.g. a sphere well inside a
            # cylinder: not the least separating translation), beyond what any bound from
            # bounding balls can promise; the guarded motions only ever probe shallow ones
            if gap > -0.01:
                assert lower <= gap
                checked += 1
    assert checked > 100
