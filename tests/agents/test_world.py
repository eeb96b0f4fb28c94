"""The grasp world's guarded motions: they never push into the object."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world
from eos_svc.world import finger_closing, wrist_motion


def world_with_sphere(position=(0.12, 0.0, 0.0), radius=0.03, seed=1):
    return build_world(PlanRequest(obj=ObjectSpec("sphere", {"radius": radius}, position), seed=seed))


@pytest.mark.parametrize("finger", ["finger1", "finger2", "finger3"])
def test_closing_stops_at_first_touch(finger):
    world = world_with_sphere()
    tol = world.params.contact_tolerance
    events = []
    for _ in range(100):
        event, _angle = finger_closing.close_finger_step(world, finger, 0.05)
        events.append(event)
        assert world.tip_distance(finger) >= 0.0  # never penetrates
        if event != "moved":
            break
    assert events[-1] == "touched"
    assert 0.0 <= world.tip_distance(finger) <= tol


def test_closing_on_nothing_reaches_the_limit():
    world = world_with_sphere(position=(0.35, 0.1, 0.1), radius=0.01)
    event = "moved"
    for _ in range(200):
        event, angle = finger_closing.close_finger_step(world, "finger1", 0.1)
        if event != "moved":
            break
    assert event == "limit"
    assert angle == pytest.approx(world.hand.upper[world.hand.finger_q_index("finger1")[0]])


def test_wrist_step_stops_short_of_contact():
    world = world_with_sphere(position=(0.30, 0.0, 0.0))
    target = world.wrist_position() + np.array([0.3, 0.0, 0.0])  # straight through the object
    blocked = False
    for _ in range(200):
        left, blocked = wrist_motion.step_wrist_toward(world, target, 0.01)
        assert world.hand_clearance() >= 0.0
        if blocked or left == 0.0:
            break
    assert blocked
    assert world.hand_clearance() <= 1e-4


def test_search_steps_stay_in_the_box_and_follow_the_seed():
    paths = []
    for _ in range(2):
        world = world_with_sphere(position=(0.35, 0.1, 0.1), radius=0.02, seed=7)
        path = []
        for _ in range(50):
            wrist_motion.search_step(world)
            p = world.wrist_position()
            assert np.all(p >= np.array(world.params.search_box_lo) - 1e-12)
            assert np.all(p <= np.array(world.params.search_box_hi) + 1e-12)
            assert world.hand_clearance() >= world.params.clearance
            path.append(p)
        paths.append(np.array(path))
    np.testing.assert_array_equal(paths[0], paths[1])


def test_hand_bound_contains_the_hand():
    # The collision-query shortcut assumes every hand part lies within hand_bound of the grasp centre.
    world = world_with_sphere()
    centre = np.array(world.params.grasp_centre)
    for finger, sweep in world.sweeps.items():
        reach = np.linalg.norm(sweep.points - centre, axis=1).max() + world.hand.tip_radius(finger)
        assert reach < world.params.hand_bound


def test_direct_motion_forgets_the_old_pose_even_on_an_error():
    world = world_with_sphere()
    before = world.hand_clearance()  # memoised for this pose
    q = world.state.q.copy()
    q[world.hand.wrist_q_index[0]] += 0.01  # 1 cm toward the object
    with pytest.raises(RuntimeError), world.direct_motion() as state:
        state.update(q)
        raise RuntimeError("the roll failed half way")
    fresh = world_with_sphere()
    fresh.set_q(q)
    assert world.hand_clearance() == fresh.hand_clearance() != before  # re-measured at the new pose
