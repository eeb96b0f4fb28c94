"""Resting poses: the random draw on a table turns each object by the smallest rotation that
lets it rest (checked against the axes' closed forms), and in Drake an object put down in that
pose stays where it was put while the drawn pose topples."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.agents import PlanRequest, build_world
from eos_svc.drivers.drake_world import DrakeDriver
from eos_svc.experiments.grasp_suite import random_draw
from eos_svc.experiments.resting_pose import resting_rotation, resting_rpy

DRAW = 40
#: the draw rounds angles to 1e-4 rad
TOL = 3e-4


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation from a to b, rad."""
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1.0) / 2.0, -1.0, 1.0)))


def test_every_drawn_object_is_turned_to_a_stable_rest_by_the_smallest_rotation() -> None:
    anywhere, resting = random_draw(DRAW, 3), random_draw(DRAW, 3, resting=True)
    for drawn, rest in zip(anywhere, resting, strict=True):
        same = (drawn.spec.size, drawn.spec.position, drawn.seed)
        assert same == (rest.spec.size, rest.spec.position, rest.seed)
        before = np.asarray(pin.rpy.rpyToMatrix(*drawn.spec.rpy))
        after = np.asarray(pin.rpy.rpyToMatrix(*rest.spec.rpy))
        vertical = np.abs(after[2, :])  # each local axis's |cos| with the vertical
        shape = drawn.spec.shape
        if shape == "sphere":
            np.testing.assert_allclose(after, before, atol=1e-12)
        elif shape == "box":  # a face down: a local axis vertical, turned by at most acos(1/√3)
            assert np.max(vertical) == pytest.approx(1.0, abs=TOL)
            assert _angle(before, after) <= math.acos(1 / math.sqrt(3)) + TOL
        elif shape == "ellipsoid":  # the shortest axis vertical
            assert vertical[int(np.argmin(drawn.spec.size["radii"]))] == pytest.approx(1.0, abs=TOL)
        elif shape == "capsule":  # lying: the axis horizontal
            assert vertical[2] == pytest.approx(0.0, abs=TOL)
        else:  # a cylinder upright within 45° of it, else lying
            upright = abs(before[2, 2]) >= math.cos(math.radians(45))
            assert vertical[2] == pytest.approx(1.0 if upright else 0.0, abs=TOL)
        if shape in ("capsule", "cylinder"):  # the axis's heading kept
            heading = math.atan2(before[1, 2], before[0, 2])
            if vertical[2] < 0.5 and math.hypot(before[0, 2], before[1, 2]) > 1e-6:
                assert math.atan2(after[1, 2], after[0, 2]) == pytest.approx(heading, abs=TOL)


def test_a_pose_already_at_rest_is_kept_and_an_unknown_shape_is_refused() -> None:
    upright = np.asarray(pin.rpy.rpyToMatrix(0.0, 0.0, 0.7))
    box = {"size": (0.05, 0.06, 0.07)}
    np.testing.assert_allclose(resting_rotation("box", box, upright), upright, atol=1e-12)
    lying = resting_rpy("capsule", {"radius": 0.02, "length": 0.05}, (math.pi / 2, 0.0, 0.3))
    np.testing.assert_allclose(lying, (math.pi / 2, 0.0, 0.3), atol=1e-12)
    with pytest.raises(ValueError, match="shape"):
        resting_rotation("torus", {}, upright)


@pytest.mark.parametrize("index", [10, 15])  # a box drawn on an edge, a capsule drawn tilted
def test_in_drake_the_resting_pose_stays_put_where_the_drawn_pose_topples(index: int) -> None:
    def settled_drop(obj) -> float:  # type: ignore[no-untyped-def]
        """How far the centre fell while the object came to rest on the table, m."""
        request = PlanRequest(obj=obj.spec, seed=1, world="drake")
        driver = DrakeDriver(build_world(request), request.obj, request.friction)
        return float(obj.spec.position[2] - driver._start[2])

    drawn, rest = random_draw(20, 1)[index], random_draw(20, 1, resting=True)[index]
    assert settled_drop(rest) < 1e-3  # put down at rest: it stays (the 0.1 mm drop, the table sinks)
    assert settled_drop(drawn) > 5e-3  # put down on an edge or an end: it topples, its centre falls
