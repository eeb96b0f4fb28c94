"""The guarded wrist move without forward kinematics far from the object is the plain one.

``GraspWorld._deferred_wrist_move`` computes the grasp centre of a pose it has not moved the
hand model to from the wrist's x, y, z (``palm_origin_is_wrist_xyz``); it must give the plain
loop's result bit for bit: the same length moved, blocked flag and final configuration.
"""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world, default_hand
from eos_svc.kinematics import allegro_hand
from eos_svc.world.world import palm_origin_is_wrist_xyz

OBJECTS = [
    ObjectSpec("sphere", {"radius": 0.03}, (0.12, 0.0, 0.0)),
    ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.12, 0.01, -0.01), (0.2, 0.3, 0.1)),
    ObjectSpec("cylinder", {"radius": 0.025, "length": 0.08}, (0.13, 0.0, 0.01), (1.2, 0.1, 0.0)),
    ObjectSpec("ellipsoid", {"radii": (0.035, 0.03, 0.025)}, (0.12, -0.01, 0.0), (0.3, 0.2, 0.5)),
]


@pytest.mark.parametrize("hand_name", ["hand3x3", "allegro"])
def test_the_palm_origin_is_the_wrist_xyz_bit_for_bit(hand_name):
    hand = allegro_hand() if hand_name == "allegro" else default_hand()
    assert palm_origin_is_wrist_xyz(hand)
    rng = np.random.default_rng(7)
    state = hand.state(hand.neutral())
    wrist = hand.wrist_q_index
    for _ in range(300):
        q = rng.uniform(hand.lower, hand.upper)
        q[wrist[:3]] = rng.uniform(-0.3, 0.3, 3)
        state.update(q)
        palm = state.data.oMf[hand.palm_frame_id].translation
        assert palm.tolist() == q[wrist[:3]].tolist()


def _move(world, q0, target, stop, deferred):
    world.set_q(q0)
    world._palm_at_wrist_xyz = deferred
    length, blocked = world.guarded_wrist_move(target, stop_when_located=stop)
    return length, blocked, world.state.q.tolist(), world.object_gap_to_grasp_centre()


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
@pytest.mark.parametrize("hand_name", ["hand3x3", "allegro"])
def test_deferred_move_is_the_plain_move(spec, hand_name):
    hand = allegro_hand() if hand_name == "allegro" else None
    world = build_world(PlanRequest(obj=spec), hand, check=False)
    h = world.hand
    wrist = h.wrist_q_index
    rng = np.random.default_rng(11)
    start = world.state.q
    outcomes = set()
    for i in range(40):
        q0 = start.copy()
        q0[wrist[:3]] += rng.uniform([-0.15, -0.05, -0.05], [0.0, 0.05, 0.05])
        if i % 2:  # a turned wrist as well
            q0[wrist[3:6]] = rng.uniform(h.lower[wrist[3:6]], h.upper[wrist[3:6]]) * 0.3
        target = q0[wrist[:3]] + rng.uniform([0.0, -0.06, -0.06], [0.25, 0.06, 0.06])
        for stop in (True, False):
            plain = _move(world, q0, target, stop, False)
            deferred = _move(world, q0, target, stop, True)
            assert deferred == plain
            outcomes.add((plain[1], plain[3] <= world.params.envelope_radius))
    # blocked and unblocked moves, located or not, were compared
    assert {blocked for blocked, _ in outcomes} == {True, False}
    assert {located for _, located in outcomes} == {True, False}


def _step(world, q0, target, step, deferred):
    world.set_q(q0)
    world._palm_at_wrist_xyz = deferred
    left, blocked = world.step_wrist_toward(target, step)
    return left, blocked, world.state.q.tolist()


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
@pytest.mark.parametrize("hand_name", ["hand3x3", "allegro"])
def test_deferred_step_toward_is_the_plain_step(spec, hand_name):
    hand = allegro_hand() if hand_name == "allegro" else None
    world = build_world(PlanRequest(obj=spec), hand, check=False)
    h = world.hand
    wrist = h.wrist_q_index
    rng = np.random.default_rng(5)
    start = world.state.q
    blocked_seen = set()
    for i in range(60):
        q0 = start.copy()
        q0[wrist[:3]] += rng.uniform([-0.06, -0.04, -0.04], [0.04, 0.04, 0.04])
        if i % 2:
            q0[wrist[3:6]] = rng.uniform(h.lower[wrist[3:6]], h.upper[wrist[3:6]]) * 0.3
        world.set_q(q0)
        if not world.hand_clear(0.5 * world.params.contact_tolerance):
            continue  # the stage starts each step from a clear pose
        target = q0[wrist[:3]] + rng.uniform([0.0, -0.05, -0.05], [0.12, 0.05, 0.05])
        step = float(rng.choice([0.005, 0.02, 0.08]))
        plain = _step(world, q0, target, step, False)
        assert _step(world, q0, target, step, True) == plain
        blocked_seen.add(plain[1])
    assert blocked_seen == {True, False}


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
def test_clear_after_translation_agrees_with_hand_clear(spec):
    world = build_world(PlanRequest(obj=spec), None, check=False)
    wrist = world.hand.wrist_q_index
    rng = np.random.default_rng(9)
    start = world.state.q
    decided = 0
    for _ in range(200):
        q0 = start.copy()
        q0[wrist[:3]] += rng.uniform([-0.05, -0.03, -0.03], [0.06, 0.03, 0.03])
        q1 = q0.copy()
        q1[wrist[:3]] += rng.uniform(-0.02, 0.02, 3)
        threshold = float(rng.choice([0.0, 5e-4, 2e-3]))
        world.set_q(q0)
        verdict = world._clear_after_translation(q1[wrist[:3]], threshold)
        world.set_q(q1)
        if verdict is not None:
            decided += 1
            assert verdict == world.hand_clear(threshold) == (world.hand_clearance() >= threshold)
    assert decided > 50
