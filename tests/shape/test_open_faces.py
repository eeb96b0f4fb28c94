"""The faces a fit leaves open: exactly those no touch sees."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from eos_svc.objects import Box, Cylinder
from eos_svc.shape import select_class
from eos_svc.shape.open_faces import open_faces
from tests.shape.synthetic import touches_on


def test_a_box_felt_from_the_front_leaves_its_back_open():
    box = Box([0.16, 0.05, 0.05], pin.SE3(np.eye(3), np.array([0.25, 0.0, 0.0])))
    rng = np.random.default_rng(3)
    # probes moving forward (+x) or sideways only: nothing sees the face at x = 0.33
    front = touches_on(box, rng, n=30, keep=lambda d: d[0] > 0.5)
    fit = select_class(front).fits["box"]
    faces = open_faces(fit, front)
    assert faces, "the back face is open"
    back = faces[0]
    assert back.normal[0] > 0.99  # the face turned away from the hand
    # the open face lies on the fitted surface, at the fitted half size along its normal
    centre = np.asarray(fit.geometry.placement.translation)
    assert float(np.dot(back.centre - centre, back.normal)) == pytest.approx(back.half, abs=1e-9)
    assert back.delta_chi2 < 2.0


def test_a_box_felt_all_round_has_no_open_face():
    box = Box([0.16, 0.05, 0.05], pin.SE3(np.eye(3), np.array([0.25, 0.0, 0.0])))
    rng = np.random.default_rng(3)
    front = touches_on(box, rng, n=30, keep=lambda d: d[0] > 0.5)
    back = touches_on(box, rng, n=6, keep=lambda d: d[0] < -0.9)  # probes from behind
    touches = dataclasses.replace(
        front,
        centres=np.vstack([front.centres, back.centres]),
        normals=np.vstack([front.normals, back.normals]),
        radii=np.concatenate([front.radii, back.radii]),
    )
    fit = select_class(touches).fits["box"]
    assert open_faces(fit, touches) == []


def test_a_cylinder_open_along_its_axis_only():
    cyl = Cylinder(0.02, 0.12, pin.SE3(pin.rpy.rpyToMatrix(0.0, np.pi / 2, 0.0), np.array([0.25, 0.0, 0.0])))
    rng = np.random.default_rng(5)
    touches = touches_on(cyl, rng, n=30, keep=lambda d: d[0] > 0.5)
    fit = select_class(touches).fits["cylinder"]
    faces = open_faces(fit, touches)
    assert len(faces) == 1 and abs(faces[0].normal[0]) > 0.99  # its far end, along the axis (x)
