"""A mesh's grip is judged by force closure about its centre of mass, not by the paper's 150°
test: a box and the same box as a mesh, gripped off their centre by sliding the hand along the
gripped faces — the same contacts, in force closure; the primitive's verdict says not good (the
angle across the centre drops below 150°), the mesh's says good, and Drake holds the grip."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.planner import build_world
from eos_svc.drivers.grip_verdict import GOOD_GRASP_ANGLE_DEG, grasp_geometry
from eos_svc.schema.request import ObjectSpec

SIZE = [0.06, 0.04, 0.05]
#: how far the hand slides along the box's long axis (world x, parallel to the gripped faces), m
OFF_CENTRE = 0.015


@pytest.fixture(scope="module")
def box_grip():
    """The box primitive, the same box as a mesh, and the box's planned grip moved off centre."""
    box = ObjectSpec("box", {"size": SIZE})
    result = plan(PlanRequest(obj=box, seed=1))
    assert result.good_grasp
    corners = trimesh.creation.box(extents=SIZE)
    size = {"vertices": corners.vertices.tolist(), "faces": corners.faces.tolist(), "scale": 1.0}
    mesh = ObjectSpec("mesh", size, box.position, box.rpy)
    world = build_world(PlanRequest(obj=box, seed=1))
    q = np.array(result.q_final)
    q[world.hand.wrist_q_index[0]] += OFF_CENTRE
    return box, mesh, result, q


def verdict(spec: ObjectSpec, q: np.ndarray) -> dict:
    world = build_world(PlanRequest(obj=spec, seed=1))
    world.set_q(q)
    return grasp_geometry(world, 0.5)


def test_an_off_centre_grip_in_force_closure_is_good_on_a_mesh_only(box_grip):
    box, mesh, _, q = box_grip
    on_box, on_mesh = verdict(box, q), verdict(mesh, q)
    assert on_box["all_touching"] and on_mesh["all_touching"]
    for finger, contact in on_box["contacts"].items():  # the same contacts on both
        assert np.allclose(contact["point"], on_mesh["contacts"][finger]["point"], atol=1e-6)
    assert on_box["diameter_angle_deg"] == pytest.approx(on_mesh["diameter_angle_deg"], abs=1e-3)
    assert on_box["diameter_angle_deg"] < GOOD_GRASP_ANGLE_DEG  # off the diameter
    assert on_box["quality"]["force_closure"] and on_mesh["quality"]["force_closure"]
    assert on_box["centre_rule"] == "diameter" and not on_box["good"]
    assert on_mesh["centre_rule"] == "force closure" and on_mesh["good"]


def test_a_mesh_grip_without_force_closure_is_not_good(box_grip):
    _, mesh, _, q = box_grip
    world = build_world(PlanRequest(obj=mesh, seed=1))
    world.set_q(q)
    assert not grasp_geometry(world, 0.0)["good"]  # frictionless: no closure with three contacts


@pytest.mark.slow
def test_drake_holds_the_off_centre_grip(box_grip):
    pytest.importorskip("pydrake")
    from eos_svc.validation import validate_grasp

    _, _, result, q = box_grip
    planned = {**result.to_dict(), "q_final": q.tolist()}
    check = validate_grasp(planned)
    assert check.held, check.reason
