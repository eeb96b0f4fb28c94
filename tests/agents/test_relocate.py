"""The relocate agent: check touches against the postulate, a refit when they disagree.

Run in the kinematic world (exact touches, the object fixed) with a postulate that is off —
as if the object had moved since it was explored — so the agent's logic is tested without a
physics simulation; the Drake world's test pushes a real object (tests/drivers, slow)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from eos_svc.agent import CycleContext, Outcome
from eos_svc.agents import PlanRequest, build_world
from eos_svc.agents.probe_plan import Probe
from eos_svc.agents.relocate import RelocateAgent
from eos_svc.board import Board
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.grasp.postulate import make_object
from eos_svc.objects import SurfaceObject
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec
from eos_svc.shape.pose_refit import moved_spec

BOX = ObjectSpec("box", {"size": (0.05, 0.04, 0.05)}, (0.21, 0.02, -0.015), (0.0, 0.0, 0.2))
CTX = CycleContext(seq=40, stage="information", stage_cycle=30, events=(), last_agent="post_shape", acted={})


def postulate(spec: ObjectSpec) -> dict:
    """A confident postulate of ``spec`` (what post_shape writes when it trusts its fit)."""
    return {
        "class": spec.shape,
        "grasp_radius": 0.025,
        "diameter": 0.08,
        "centre": list(spec.position),
        "confidence": 0.9,
        "principal_curvatures": [0.0, 0.0],
        "curvature_radius": None,
        "needs": None,
        "object": spec.to_dict(),
        "pose_known": True,
    }


def check_until_located(agent: RelocateAgent, board: Board) -> list[str]:
    said = []
    while agent.opportunistic(board, CTX):
        result = agent.act(board, CTX)
        assert result.outcome == Outcome.PROGRESS
        said.append(result.detail)
    return said


def test_a_postulate_where_the_object_is_is_checked_and_kept() -> None:
    driver = KinematicDriver(build_world(PlanRequest(obj=BOX, seed=1)))
    board = Board({keys.SHAPE: postulate(BOX)})
    said = check_until_located(RelocateAgent(0.65, driver), board)
    assert len(said) == 1 and "where it was postulated" in said[0]
    assert board.get(keys.SHAPE)["located"]["moved"] is False
    assert board.get(keys.SHAPE)["object"] == BOX.to_dict()  # unchanged
    assert driver.probes == 4  # front, the side from −y (ended by a link on the turned box), from +y, top


def relocated(truth: ObjectSpec, believed: ObjectSpec) -> SurfaceObject:
    """The object relocate ends believing when the postulate says ``believed`` and the world holds
    ``truth``: its checks must first disagree, then agree after the refit."""
    driver = KinematicDriver(build_world(PlanRequest(obj=truth, seed=1)))
    board = Board({keys.SHAPE: postulate(believed)})
    said = check_until_located(RelocateAgent(0.65, driver), board)
    assert "re-located" in said[0] and "where it was postulated" in said[-1]
    shape = board.get(keys.SHAPE)
    assert shape["located"]["moved"] is False and shape["relocations"] >= 1
    return make_object(ObjectSpec.from_dict(shape["object"]))


def test_a_postulate_off_by_9_mm_and_10_degrees_is_relocated_onto_the_object() -> None:
    """The postulate believes the box 9 mm to −y and turned 10° from where it is: the check
    touches disagree, the refit moves the postulate onto the box (centre within 1 mm, its yaw
    within 2°), and the next check agrees."""
    believed = moved_spec(BOX, np.array([0.0, -0.009, 0.0]), pin.rpy.rpyToMatrix(0.0, 0.0, np.radians(10)))
    found = relocated(BOX, believed)
    assert np.linalg.norm(found.centre - np.asarray(BOX.position)) < 1e-3
    yaw = np.arctan2(found.rotation[1, 0], found.rotation[0, 0])
    assert abs(np.degrees(yaw) - 11.459) < 2.0  # BOX's 0.2 rad


def test_a_sphere_postulated_12_mm_sideways_is_relocated_onto_it() -> None:
    """A ball believed 12 mm to −y of where it is: the front and top check probes at the
    postulate's middle pass 12 mm beside the ball's and touch within 2 mm of the prediction
    (√(0.04² − 0.012²) ≈ 38.2 mm from its centre, not 40); the side check touch sees the move,
    the refit puts the postulate on the ball (centre within 1 mm), and the next check agrees."""
    ball = ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.02, -0.015))
    believed = moved_spec(ball, np.array([0.0, -0.012, 0.0]), np.eye(3))
    found = relocated(ball, believed)
    assert np.linalg.norm(found.centre - np.asarray(ball.position)) < 1e-3


def test_a_blocked_check_probe_is_no_miss_and_a_free_one_is() -> None:
    """A check probe the driver refuses (its start 10 m away: outside the wrist's workspace)
    says nothing of the object, so it gives no entry; one through free space beside the box
    touches nothing: a miss (None), which starts a re-location."""
    driver = KinematicDriver(build_world(PlanRequest(obj=BOX, seed=1)))
    agent = RelocateAgent(0.65, driver)
    down = np.array([0.0, 0.0, -1.0])
    far = Probe("top", "finger1", np.array([10.0, 0.0, 0.0]), down, 0.02, 0.0)
    beside = Probe("top", "finger1", np.array([0.21, 0.12, 0.06]), down, 0.01, 0.0)
    assert driver.guarded_probe("finger1", far.start, down, 0.02, 0.0).event == "blocked"
    assert agent._probe([far]) == []
    assert agent._probe([beside]) == [None]
    assert agent._probe([far, beside]) == [None]
