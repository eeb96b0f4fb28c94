"""The table: in the request, at admission, and known to the planner — no hand pose below it,
no probe from under it, a grasp from above or the side — and in the Drake validation; mesh
requests through the service's decoder."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from eos_svc.agents import plan
from eos_svc.agents.planner import default_hand
from eos_svc.errors import ValidationError
from eos_svc.schema import keys
from eos_svc.schema.request import MAX_MESH_VERTICES, ObjectSpec, PlanRequest, Table
from eos_svc.service.protocol import RequestError, decode_request
from eos_svc.validation import validate_grasp
from eos_svc.world.admission import check_default
from eos_svc.world.table import hand_table_gap, table_shape

BOX = ObjectSpec("box", {"size": (0.05, 0.06, 0.05)}, (0.21, 0.02, 0.0))
TABLE = Table(-0.025)  # the box's bottom


def test_the_table_round_trips_and_bad_tables_name_the_field():
    request = PlanRequest(obj=BOX, table=TABLE)
    assert PlanRequest.from_dict(request.to_dict()) == request
    assert "table" not in PlanRequest(obj=BOX).to_dict()  # the paper's scene: as it was
    for bad, field in (({"height": "low"}, "table.height"), ({"z": 0.0}, "table.z"), (3, "table")):
        with pytest.raises(ValidationError) as err:
            PlanRequest.from_dict({"table": bad})
        assert err.value.field == field


def test_admission_refuses_an_object_reaching_into_the_table():
    check_default(PlanRequest(obj=BOX, table=TABLE))
    with pytest.raises(ValidationError) as err:
        check_default(PlanRequest(obj=BOX, table=Table(-0.02)))
    assert err.value.field == "object.position[2]" and "5.0 mm into the table" in err.value.reason


def hand_poses(result) -> list[np.ndarray]:
    """Every hand configuration the plan's cycles ended in, and EP1's rolling paths."""
    out = []
    for record in result.trace:
        for change in record.changes:
            if change.key == keys.HAND_Q:
                out.append(np.asarray(change.new))
            elif change.key == keys.HAND_PATH:
                out.extend(np.asarray(q) for q in change.new)
    return out


def test_a_box_on_a_table_is_grasped_with_the_hand_above_the_table_all_along():
    result = plan(PlanRequest(obj=BOX, seed=1, table=TABLE))
    assert result.status == "success" and result.good_grasp
    hand = default_hand()
    table = table_shape(TABLE.height)
    poses = hand_poses(result)
    assert len(poses) > 20
    gaps = [hand_table_gap(hand.state(q), table) for q in poses]
    assert min(gaps) >= -1e-9  # no hand geometry ever in the table
    touches = [c.new for rec in result.trace for c in rec.changes if c.key == keys.EP2_TOUCHES]
    assert touches and touches[-1] and all(t["face"] != "bottom" for t in touches[-1])  # none from under it
    # the same box floating: the hand goes under it (the paper's scene)
    floating = plan(PlanRequest(obj=BOX, seed=1))
    assert min(hand_table_gap(hand.state(q), table) for q in hand_poses(floating)) < -0.01
    # Drake: the table welded under the box, the grasp held
    check = validate_grasp(result, directions=2, seconds=0.5)
    assert check.held


def box_mesh_request(**extra) -> dict:
    box = trimesh.creation.box(extents=(0.05, 0.06, 0.05))
    return {
        "schema": 1,
        "goal_id": "g-mesh-1",
        "object": {"shape": "mesh", "vertices": box.vertices.tolist(), "faces": box.faces.tolist(), **extra},
        "table": {"height": -0.025},
    }


def test_the_service_takes_a_mesh_inline_and_refuses_files_and_oversized_meshes():
    payload = box_mesh_request(position=[0.21, 0.02, 0.0])
    _, request = decode_request(json.dumps(payload).encode())
    assert request.obj.shape == "mesh" and request.table == TABLE
    with pytest.raises(RequestError) as err:
        decode_request(json.dumps({**payload, "object": {"shape": "mesh", "file": "/etc/x.obj"}}).encode())
    assert err.value.field == "object.file"
    big = box_mesh_request()
    big["object"]["vertices"] = [[0.0, 0.0, 0.0]] * (MAX_MESH_VERTICES + 1)
    with pytest.raises(RequestError) as err:
        decode_request(json.dumps(big).encode(), max_bytes=10**7)
    assert err.value.field == "object.vertices" and "exceed the limit" in err.value.reason


def test_a_box_mesh_on_a_table_is_planned_as_the_box():
    _, request = decode_request(json.dumps(box_mesh_request(position=[0.21, 0.02, 0.0])).encode())
    result = plan(request)
    assert result.status == "success" and result.good_grasp
    assert result.shape is not None and result.shape["class"] == "box"


def table_synthesis(spec: ObjectSpec, table: float | None):
    from eos_svc.agents.planner import build_world
    from eos_svc.grasp.postulate import make_object
    from eos_svc.grasp.synthesis import GraspSynthesis
    from eos_svc.world.hand_context import context_for

    hand = default_hand()
    world = build_world(PlanRequest(), hand)
    params = context_for(hand).params
    return GraspSynthesis(hand, world.sweeps, params, make_object(spec), 0.5, table_height=table)


def test_on_a_table_a_sphere_is_grasped_from_above_and_never_from_below():
    # a ball resting on the table: from the side the opposing finger would go under the table;
    # from above (palm down, closing across a horizontal diameter) it is reachable
    ball = ObjectSpec("sphere", {"radius": 0.027}, (0.21, 0.02, -0.023))
    on_table = table_synthesis(ball, -0.05)
    best = on_table.candidates()
    assert best and best[0].label.endswith("from above")
    assert np.allclose(best[0].approach, [0.0, 0.0, -1.0], atol=1e-9)  # straight down
    assert abs(float(best[0].closing[2])) < 1e-9  # closing across a horizontal diameter
    assert best[0].about_centre
    # the same ball floating: the paper's candidates, none from above
    floating = table_synthesis(ball, None).candidates()
    assert floating and not any("from above" in c.label for c in floating)


def test_on_a_table_no_candidate_closes_vertically_or_climbs_from_under_it():
    from eos_svc.grasp.frames import RISING, STEEP, candidate_frames
    from eos_svc.grasp.postulate import make_object

    obj = make_object(ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.21, 0.02, -0.02), (0.3, 0.2, 0.5)))
    frames = list(candidate_frames(obj, on_table=True))
    assert frames and any(label.endswith("from above") for label, _ in frames)
    for _, R in frames:
        assert abs(R[2, 2]) <= STEEP and R[2, 0] <= RISING + 1e-12
    assert any(abs(R[2, 2]) > STEEP for _, R in candidate_frames(obj))  # without a table: it does


def test_a_short_object_on_a_table_is_located_by_the_rolled_hand():
    # 25 mm tall: upright, the hand's palm reaches 75 mm below its grasp centre, which then
    # stays more than the envelope (50 mm) above the object's top; rolled, it comes down to it
    flat = ObjectSpec("box", {"size": (0.06, 0.05, 0.025)}, (0.21, 0.02, -0.0375))
    result = plan(PlanRequest(obj=flat, seed=2, table=Table(-0.05)))
    assert "information" in result.cycles_per_stage  # located: the search stage ended
    first = next(r for r in result.trace if r.stage == "search" and r.chosen is not None)
    assert first.detail.startswith("rolled the hand a quarter turn over the table")
    hand, table = default_hand(), table_shape(-0.05)
    assert min(hand_table_gap(hand.state(q), table) for q in hand_poses(result)) >= -1e-9
