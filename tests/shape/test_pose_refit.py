"""Re-locating a known object from fresh touches: the pose refit recovers a known move."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.grasp.postulate import make_object
from eos_svc.schema.request import ObjectSpec
from eos_svc.shape.pose_refit import moved_spec, refit_pose, touch_misses

TIP = 0.008  # fingertip radius, m


def touches_on(
    spec: ObjectSpec, directions: list[tuple[float, float, float]]
) -> tuple[np.ndarray, np.ndarray]:
    """Fingertip centres one tip radius off the surface of ``spec`` where rays from its centre
    along ``directions`` leave it, and the outward normals there."""
    obj = make_object(spec)
    centres, normals = [], []
    for d in directions:
        u = np.asarray(d, dtype=float) / np.linalg.norm(d)
        point = obj.centre + obj.half_extent(u) * u
        _, grad = obj.signed_distances(point[None])
        n = grad[0] / np.linalg.norm(grad[0])
        centres.append(point + TIP * n)
        normals.append(n)
    return np.array(centres), np.array(normals)


RAYS = [
    (-1.0, 0.0, 0.0),
    (-1.0, 0.0, 0.4),
    (0.0, 0.0, 1.0),
    (0.0, 1.0, 0.0),
    (0.0, -1.0, 0.0),
    (-1, 0.5, -0.3),
]


@pytest.mark.parametrize(
    "believed",
    [
        ObjectSpec("box", {"size": (0.05, 0.04, 0.03)}, (0.2, 0.0, -0.03), (0.0, 0.0, 0.3)),
        ObjectSpec("cylinder", {"radius": 0.02, "length": 0.08}, (0.2, 0.0, -0.02), (np.pi / 2, 0.0, 0.2)),
        ObjectSpec("sphere", {"radius": 0.03}, (0.2, 0.0, -0.015)),
    ],
)
def test_a_slid_and_turned_object_is_found_where_it_went(believed: ObjectSpec) -> None:
    """The object slid 9 mm and 6 mm on its table and turned 12° about the vertical: the refit of
    the believed object to six exact touches recovers the true pose (its surface within 0.1 mm of
    every touch, the centre within 0.2 mm)."""
    shift = np.array([0.009, -0.006, 0.0])
    truth = moved_spec(believed, shift, pin.rpy.rpyToMatrix(0.0, 0.0, np.radians(12)))
    support = float(make_object(truth).centre[2] - make_object(truth).depth_below_centre())
    centres, normals = touches_on(truth, RAYS)
    radii = np.full(len(centres), TIP)
    before = touch_misses(make_object(believed), centres, radii)
    assert np.max(np.abs(before)) > 0.002  # the believed pose is off by more than the 2 mm rule
    fit = refit_pose(believed, centres, normals, radii, support, noise=1e-4)
    assert fit.rms < 1e-4
    assert np.linalg.norm(np.asarray(fit.spec.position) - np.asarray(truth.position)) < 2e-4
    assert np.max(np.abs(touch_misses(make_object(fit.spec), centres, radii))) < 1e-4


def test_a_toppled_capsule_is_found_lying() -> None:
    """An upright capsule fell over onto its side (its axis now along y): the quarter-turn starts
    find it lying, its surface within 0.2 mm of every touch."""
    upright = ObjectSpec("capsule", {"radius": 0.02, "length": 0.05}, (0.2, 0.0, 0.025))
    lying = ObjectSpec(
        "capsule", {"radius": 0.02, "length": 0.05}, (0.215, 0.01, -0.0175), (np.pi / 2, 0.0, 0.0)
    )
    centres, normals = touches_on(lying, RAYS)
    radii = np.full(len(centres), TIP)
    fit = refit_pose(upright, centres, normals, radii, support_height=-0.0375, noise=1e-4)
    assert np.max(np.abs(touch_misses(make_object(fit.spec), centres, radii))) < 2e-4
    axis = pin.rpy.rpyToMatrix(*fit.spec.rpy)[:, 2]
    assert abs(axis[2]) < 0.05  # lying down
