"""The cheap gap lower bounds (eos_svc.kinematics.gap_bounds) never exceed coal's exact gap."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from eos_svc.kinematics.gap_bounds import ball_gap_lower_bounds, hand_bound_table, shape_bound


def _exact_gap(geometry, placement: pin.SE3, centre: np.ndarray, radius: float) -> float:
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    ball = coal.Sphere(radius)
    coal.distance(
        geometry,
        coal.Transform3s(placement.rotation, placement.translation),
        ball,
        coal.Transform3s(np.eye(3), centre),
        request,
        result,
    )
    return float(result.min_distance)


def test_bounds_never_exceed_the_exact_gap_and_are_tight_for_a_sphere():
    rng = np.random.default_rng(11)
    geometries = [
        coal.Box(0.04, 0.02, 0.06),
        coal.Capsule(0.01, 0.05),
        coal.Cylinder(0.012, 0.04),
        coal.Sphere(0.01),
    ]
    table = [shape_bound(g) for g in geometries]
    near = 0
    for _ in range(200):
        placements = [pin.SE3(pin.exp3(rng.normal(size=3)), rng.uniform(-0.1, 0.1, 3)) for _ in geometries]
        views = [(p.translation, p.rotation) for p in placements]
        centre = rng.uniform(-0.12, 0.12, 3)
        radius = float(rng.uniform(0.005, 0.05))
        for lower, gid in ball_gap_lower_bounds(table, views, range(len(geometries)), centre, radius):
            exact = _exact_gap(geometries[gid], placements[gid], centre, radius)
            assert lower <= exact + 1e-9, (gid, lower, exact)
            if gid == 3:  # sphere against a ball: the bound is the exact gap (less the margin)
                assert abs(lower - exact) < 1e-6
            near += exact < 0.02
    assert near > 50  # many poses close to contact, where a loose bound would show


def test_hand_bound_table_is_shape_bound_of_every_geometry(eos_hand):
    table = hand_bound_table(eos_hand)
    assert table == [shape_bound(go.geometry) for go in eos_hand.collision_model.geometryObjects]
