"""``Scene.gap`` and ``Scene.point_gap`` give the distances of a fresh ``coal.distance`` query, bit
for bit, for every object shape, in any order of queries (the scene's reused request, result and
transforms keep nothing from one query to the next)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from eos_svc.hands import load_hand_named
from eos_svc.kinematics import Scene
from eos_svc.objects import Box, Capsule, Cylinder, Ellipsoid, Sphere


def _objects():
    placement = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.7), np.array([0.12, 0.01, -0.02]))
    return [
        Sphere(0.03, placement),
        Box((0.05, 0.04, 0.06), placement),
        Cylinder(0.025, 0.08, placement),
        Capsule(0.02, 0.06, placement),
        Ellipsoid((0.035, 0.03, 0.025), placement),
    ]


def _plain_distance(scene, shape, transform) -> float:
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    request.enable_signed_distance = True
    request.gjk_tolerance = scene._req.gjk_tolerance
    coal.distance(scene.object.geometry, scene._tf_obj, shape, transform, request, result)
    return float(result.min_distance)


@pytest.mark.parametrize("obj", _objects(), ids=lambda o: o.kind)
@pytest.mark.parametrize("hand_name", ["hand3x3", "allegro"])
def test_functor_gaps_are_coal_distance_bit_for_bit(obj, hand_name, hand):
    if hand_name == "allegro":
        hand = load_hand_named("allegro")  # on the planner's wrist (the conftest fixture has none)
    scene = Scene(hand, obj)
    state = hand.state(hand.neutral())
    rng = np.random.default_rng(4)
    wrist = hand.wrist_q_index
    n_geoms = len(hand.collision_model.geometryObjects)
    signs = set()
    for _ in range(30):
        q = rng.uniform(hand.lower, hand.upper)
        q[wrist[:3]] = rng.uniform([-0.05, -0.06, -0.06], [0.1, 0.06, 0.06])
        state.update(q)
        for gid in rng.permutation(n_geoms).tolist():  # any order: no state kept between queries
            plain = _plain_distance(
                scene,
                hand.collision_model.geometryObjects[gid].geometry,
                coal.Transform3s(state.geometry_data.oMg[gid]),
            )
            assert scene.gap(state, gid) == plain
            signs.add(plain < 0.0)
        for point in rng.uniform([0.0, -0.1, -0.1], [0.25, 0.1, 0.1], (10, 3)):
            plain = _plain_distance(scene, coal.Sphere(1e-9), coal.Transform3s(np.eye(3), point))
            assert scene.point_gap(point) == plain
            signs.add(plain < 0.0)
    assert signs == {True, False}  # separated and penetrating pairs were compared
