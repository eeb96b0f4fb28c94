"""Where a finger lands on an object when it closes from a candidate's open hand (``grasp.landing``):
closed forms, the hand's landings in one query against each finger's own, and the bounds that
skip exact gaps."""

from __future__ import annotations

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec
from eos_svc.grasp.frames import rotation_from_rpy
from eos_svc.grasp.landing import SweepLandings, sweep_landings
from tests.grasp.scenes import HERE, synthesis


def test_sphere_landing_matches_the_closed_form():
    # unrotated palm, sphere centre on the palm's x axis: the opposing tip touches where its
    # centre is R + r_f from the sphere's centre, the contact R from it along the same line
    s = synthesis(ObjectSpec("sphere", {"radius": 0.03}, HERE))
    hand = s.hand
    finger = hand.description.opposing_finger
    wrist = np.asarray(HERE) - np.array([0.125, 0.0, 0.0])
    hit = sweep_landings(s.obj, s.sweeps, {finger: hand.tip_radius(finger)}, np.eye(3), wrist)[
        finger
    ].landing(0)
    assert hit is not None
    q = hand.neutral()
    q[hand.wrist_q_index[:3]] = wrist
    q[hand.finger_q_index(finger)] = hit.angle
    tip = hand.state(q).tip_position(finger)
    assert np.linalg.norm(tip - np.asarray(HERE)) == pytest.approx(0.03 + hand.tip_radius(finger), abs=2e-5)
    assert np.linalg.norm(hit.point - np.asarray(HERE)) == pytest.approx(0.03, abs=1e-9)
    assert np.allclose(hit.normal, (hit.point - np.asarray(HERE)) / 0.03, atol=1e-3)


def test_wrist_angles_outside_the_joint_limits_are_refused():
    s = synthesis(ObjectSpec("sphere", {"radius": 0.03}, HERE))
    assert s.wrist_rpy(rotation_from_rpy(0.3, 0.2, 1.0)) == pytest.approx((0.3, 0.2, 1.0), abs=1e-12)
    assert s.wrist_rpy(rotation_from_rpy(0.3, 0.2, 2.0)) is None  # yaw beyond π/2


@pytest.mark.parametrize(
    "spec",
    [
        ObjectSpec("ellipsoid", {"radii": (0.04, 0.025, 0.03)}, HERE, (0.4, -0.3, 0.9)),
        ObjectSpec("box", {"size": (0.07, 0.035, 0.045)}, HERE, (0.3, 0.6, -1.1)),
    ],
    ids=lambda spec: spec.shape,
)
def test_the_hands_landings_in_one_query_are_each_fingers_landing(spec):
    # sweep_landings stacks the three sweeps into one distance query: the same landings as
    # finger by finger (the ellipsoid's Newton batch may iterate once more: 1e-12 m)
    s = synthesis(spec)
    R = rotation_from_rpy(0.2, -0.1, 0.3)
    wrist = np.asarray(HERE) - R[:, 0] * 0.12
    together = {
        f: found.landing(0) for f, found in sweep_landings(s.obj, s.sweeps, s.tip_radii, R, wrist).items()
    }
    assert tuple(together) == tuple(s.hand.finger_names)
    for f, hit in together.items():
        alone = sweep_landings(s.obj, s.sweeps, {f: s.tip_radii[f]}, R, wrist)[f].landing(0)
        assert (hit is None) == (alone is None)
        if hit is not None:
            assert hit.index == alone.index
            assert np.allclose(hit.point, alone.point, atol=1e-12) and hit.angle == pytest.approx(
                alone.angle, abs=1e-12
            )
    assert sum(hit is not None for hit in together.values()) >= 2


def test_a_finger_lands_from_any_start_before_its_touch_and_not_after():
    # unrotated palm, sphere on the palm's x axis: every start up to the touching sample lands
    # on the same contact; a finger starting inside the object (touching already) lands nowhere
    s = synthesis(ObjectSpec("sphere", {"radius": 0.03}, HERE))
    finger = s.opposing
    sweep, r = s.sweeps[finger], s.hand.tip_radius(finger)
    wrist = np.asarray(HERE) - np.array([0.125, 0.0, 0.0])
    landings = sweep_landings(s.obj, s.sweeps, {finger: r}, np.eye(3), wrist)[finger]
    pts, gaps = landings.pts, landings.gaps
    first = landings.landing(0)
    assert first is not None and gaps[first.index] <= 0.0 < gaps[first.index - 1]
    for start in range(first.index + 1):
        hit = landings.landing(start)
        assert hit is not None and hit.index == first.index and np.array_equal(hit.point, first.point)
    assert landings.landing(first.index + 1) is None  # starts where it already touches
    assert landings.first_touch(first.index + 1) is None
    far = SweepLandings(s.obj, sweep, pts + np.array([0.0, 0.3, 0.0]), np.full(len(gaps), 0.01))
    assert far.landing(0) is None


@pytest.mark.parametrize(
    "spec",
    [
        ObjectSpec("sphere", {"radius": 0.03}, HERE),
        ObjectSpec("box", {"size": (0.07, 0.035, 0.045)}, HERE, (0.3, 0.6, -1.1)),
    ],
)
def test_clearance_check_with_bounds_equals_every_exact_gap(spec):
    # clear() skips the exact query of a geometry whose lower bound reaches the threshold: the
    # answer must be the one from every geometry's exact gap, near and far from the object
    s = synthesis(spec)
    hand = s.hand
    rng = np.random.default_rng(7)
    widx = hand.wrist_q_index
    tips = {hand.tip_geometry_id(f) for f in hand.finger_names}
    answers = set()
    for _ in range(80):
        q = hand.neutral()
        q[widx[:3]] = np.asarray(HERE) - np.array([0.12, 0.0, 0.0]) + rng.uniform(-0.05, 0.05, 3)
        q[widx[3:6]] = rng.uniform(-0.6, 0.6, 3)
        for f in hand.finger_names:
            q[hand.finger_q_index(f)] = rng.uniform(0.0, 1.2)
        q = np.clip(q, hand.lower, hand.upper)
        for threshold in (0.0, 0.0025, 0.01):
            for skip_tips in (False, True):
                fast = s.clearance.clear(q, threshold, skip_tips)
                state = hand.state(q)
                exact = all(
                    s.clearance.scene.gap(state, g) >= threshold
                    for g in range(hand.collision_model.ngeoms)
                    if not (skip_tips and g in tips)
                )
                assert fast == exact
                answers.add(fast)
    assert answers == {True, False}
