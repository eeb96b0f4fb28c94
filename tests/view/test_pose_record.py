"""The hand's configuration in the cycle records (board entries hand_q, hand_path) for viewers."""

from __future__ import annotations

import re

import numpy as np
import pytest

from eos_svc.agents import PlanRequest, keys, plan
from eos_svc.agents.base import STAGES
from eos_svc.agents.planner import build_agents, build_world
from eos_svc.board import Board
from eos_svc.controller import Controller
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.schema.request import ObjectSpec
from eos_svc.world.pose_board import PoseBoard


def _written(record, key):
    return next((c.new for c in record.changes if c.key == key), None)


@pytest.fixture(scope="module")
def result():
    return plan(PlanRequest(seed=2))


def test_every_move_is_recorded_and_the_last_is_the_final_configuration(result):
    qs = [_written(r, keys.HAND_Q) for r in result.trace]
    moved = [q for q in qs if q is not None]
    assert len(moved) >= result.cycles_per_stage["grasping"] - 1  # every wrist/finger step moves it
    assert np.allclose(moved[-1], result.q_final, atol=1e-7)
    # a search move changes the wrist only; a finger step changes that finger's joints only
    hand_q = np.array(moved[0])
    assert np.allclose(hand_q[3:], 0.0) and np.linalg.norm(hand_q[:3]) > 0.005
    # cycles that do not move the hand (post_shape) write nothing
    for r in result.trace:
        if r.chosen == "post_shape":
            assert _written(r, keys.HAND_Q) is None


def test_ep1_path_is_the_roll_with_the_tip_on_the_object(result):
    world = build_world(PlanRequest(seed=2))
    ep1 = [r for r in result.trace if r.chosen == "ep1"]
    assert ep1
    for record in ep1:
        path = np.array(_written(record, keys.HAND_PATH))
        assert path.shape[0] >= 8 and path.shape[1] == len(result.q_final)
        assert np.ptp(path[:, 3:], axis=0).max() > 0.01  # the joints turn while rolling
        finger = re.search(r"rolled (\w+) on", record.detail).group(1)
        for q in path[:: max(1, len(path) // 5)]:
            state = world.hand.state(q)
            assert abs(world.scene.contact(state, finger).distance) < 5e-4  # rolling, not lifted


def test_the_records_do_not_change_the_plan():
    """The same agents on a plain Board and on the PoseBoard choose the same cycles."""
    cylinder = ObjectSpec("cylinder", {"radius": 0.025, "length": 0.08}, (0.2, 0.0, 0.0))
    request = PlanRequest(obj=cylinder, seed=4)
    runs = []
    for make in (
        lambda w: Board({keys.FRICTION: 0.5}),
        lambda w: PoseBoard(KinematicDriver(w), {keys.FRICTION: 0.5}),
    ):
        world = build_world(request)
        run = Controller(build_agents(world), STAGES, request.weights, max_cycles=2000).run(make(world))
        runs.append(
            [
                (r.chosen, r.outcome, r.detail, [(c.key, c.new) for c in r.changes if c.key != keys.HAND_Q])
                for r in run.trace
            ]
        )
        runs[-1].append(world.q_list())
    assert runs[0] == runs[1]
