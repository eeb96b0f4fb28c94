"""guarded_probe's shortcut gives the plain conservative advancement's outcome.

The probe skips the exact queries of the hand's other geometries while a lower bound of their
gap (the hand's clearance at the start, then the last exact value less the distance moved,
``_probe_floor_after``) already fixes the step. Checked against the plain loop (every other
geometry queried at every sub-step, kept here as the reference) within 1e-9 m, and the bound
against coal, for every object shape.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world
from eos_svc.world.probe_motion import _probe_floor_after, guarded_probe
from eos_svc.world.probing import ProbeOutcome, densify

OBJECTS = [
    ObjectSpec("sphere", {"radius": 0.03}, (0.21, 0.0, 0.0)),
    ObjectSpec("box", {"size": (0.05, 0.04, 0.06)}, (0.21, 0.0, 0.0), (0.2, 0.3, 0.1)),
    ObjectSpec("cylinder", {"radius": 0.025, "length": 0.08}, (0.21, 0.0, 0.0), (1.2, 0.1, 0.0)),
    ObjectSpec("ellipsoid", {"radii": (0.035, 0.03, 0.025)}, (0.21, 0.0, 0.0), (0.3, 0.2, 0.5)),
    ObjectSpec("capsule", {"radius": 0.02, "length": 0.06}, (0.21, 0.0, 0.0), (1.5708, 0.0, 0.0)),
]


def plain_guarded_probe(world, finger, start, direction, travel, angle, queries=None) -> ProbeOutcome:
    """The probe without the shortcut: tip gap and every other geometry's exact gap at every
    sub-step (the algorithm as first written)."""
    p = world.params
    hand = world.hand
    wq = hand.wrist_q_index
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    q = world.state.q
    q[wq[3:6]] = 0.0
    for f in hand.finger_names:
        idx = hand.finger_q_index(f)
        q[idx] = angle if f == finger else hand.lower[idx]
    world.set_q(q)
    offset = world.state.tip_position(finger) - world.wrist_position()
    lo, hi = hand.lower[wq[:3]], hand.upper[wq[:3]]
    start = np.asarray(start, dtype=float)
    for back in (0.0, 0.02, 0.04, 0.06):
        wrist = start - back * d - offset
        if np.any(wrist < lo) or np.any(wrist > hi):
            return ProbeOutcome("blocked", finger, why="outside the wrist's workspace")
        q[wq[:3]] = wrist
        world.set_q(q)
        if world.exact_clearance() >= p.clearance:
            travel += back
            break
    else:
        return ProbeOutcome("blocked", finger, why="no clear start")
    tip_gid = hand.tip_geometry_id(finger)
    others = [g for g in range(hand.collision_model.ngeoms) if g != tip_gid]
    tol = p.contact_tolerance
    wrist0 = world.wrist_position().copy()
    travelled = 0.0
    free = [world.state.tip_position(finger)]
    for _ in range(300):
        tip_gap = world.tip_distance(finger)
        if tip_gap <= tol:
            contact = world.scene.contact(world.state, finger)
            reading = world.sensor.read(world.state, contact)
            M = world.state.data.oMf[hand.tip_frame_id(finger)]
            normal = -(M.rotation @ reading.normal_tip)
            centre = M.translation.copy()
            return ProbeOutcome("touched", finger, centre=centre, normal=normal, travelled=travelled)
        other = min(world.scene.gap(world.state, g) for g in others) - 0.5 * tol
        if queries is not None:
            queries.append(1)
        if other < 1e-5:
            return ProbeOutcome(
                "blocked",
                finger,
                free=densify(np.array(free)),
                travelled=travelled,
                why="another part of the hand would touch first",
            )
        step = min(travel - travelled, tip_gap - 0.5 * tol, other)
        travelled += step
        q[wq[:3]] = wrist0 + d * travelled
        world.set_q(q)
        free.append(world.state.tip_position(finger))
        if travelled >= travel - 1e-12:
            break
    return ProbeOutcome("missed", finger, free=densify(np.array(free)), travelled=travelled)


#: how far the shortcut's outcome may lie from the plain loop's (m; unit normals: 1e-9)
TOLERANCE = 1e-9


def assert_same_outcome(fast: ProbeOutcome, plain: ProbeOutcome) -> None:
    """The same event and reason; centre, normal, free path and travel within :data:`TOLERANCE`."""
    assert (fast.event, fast.why) == (plain.event, plain.why)
    for name in ("centre", "normal", "free"):
        a, b = getattr(fast, name), getattr(plain, name)
        assert (a is None) == (b is None), name
        if a is not None:
            np.testing.assert_allclose(a, b, rtol=0.0, atol=TOLERANCE, err_msg=name)
    assert fast.travelled == pytest.approx(plain.travelled, rel=0.0, abs=TOLERANCE)


def random_probes(world, rng, n):
    """Probes toward (and past) the object from around it: down onto the top, up under it,
    sideways, slanted; short and long travels; both exploring fingers."""
    centre = np.asarray(world.obj.placement.translation)
    for k in range(n):
        finger = world.probe.finger("top" if k % 3 else "bottom")
        direction = rng.normal(size=3)
        direction[2] += -2.0 if finger == world.probe.finger("top") else 2.0
        direction /= np.linalg.norm(direction)
        # every fourth from far away: exact_clearance's plain bound (gap − hand_bound) there
        reach = rng.uniform(0.25, 0.3) if k % 4 == 3 else rng.uniform(0.03, 0.08)
        start = centre - direction * reach + rng.uniform(-0.03, 0.03, size=3)
        yield finger, start, direction, float(rng.uniform(0.005, 0.12)), world.probe.angles[finger]


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
def test_guarded_probe_is_the_plain_advancement(spec):
    fast_world = build_world(PlanRequest(obj=spec, seed=3))
    plain_world = build_world(PlanRequest(obj=spec, seed=3))
    events = set()
    fast_queries: list[int] = []
    plain_queries: list[int] = []
    min_gap = fast_world.min_gap

    def counted(ids, best):
        fast_queries.append(1)
        return min_gap(ids, best)

    plain_min_gap = plain_world.min_gap
    plain_exact_clearance = plain_world.exact_clearance
    far = []

    def plain_clearance():
        value = plain_exact_clearance()
        far.append(value == plain_world.object_gap_to_grasp_centre() - plain_world.params.hand_bound)
        return value

    plain_world.exact_clearance = plain_clearance

    def plain_counted(ids, best):
        plain_queries.append(1)
        return plain_min_gap(ids, best)

    # the probes' queries of the other geometries, and the clearance's (exact_clearance)
    fast_world.min_gap = counted
    plain_world.min_gap = plain_counted
    for probe in random_probes(fast_world, np.random.default_rng(7), 40):
        fast = guarded_probe(fast_world, *probe)
        plain = plain_guarded_probe(plain_world, *probe, queries=plain_queries)
        assert_same_outcome(fast, plain)
        np.testing.assert_allclose(fast_world.state.q, plain_world.state.q, rtol=0.0, atol=TOLERANCE)
        events.add(fast.event)
    assert {"touched", "missed"} <= events  # the probes exercise the paths that matter
    assert any(far) and not all(far)  # starts where exact_clearance is exact, and where it is the plain bound
    # the shortcut was taken: fewer queries of the other geometries than the plain loop's
    assert len(fast_queries) < len(plain_queries)


@pytest.mark.parametrize("spec", OBJECTS, ids=lambda s: s.shape)
def test_probe_floor_is_a_lower_bound_of_every_gap_after_a_translation(spec):
    """min gap after a wrist translation by s ≥ _probe_floor_after(min gap before, s), for
    random poses and translations (coal's gaps, every hand geometry)."""
    world = build_world(PlanRequest(obj=spec, seed=1))
    hand = world.hand
    rng = np.random.default_rng(5)
    xyz = hand.wrist_q_index[:3]
    centre = np.asarray(world.obj.placement.translation)
    ids = range(hand.collision_model.ngeoms)
    tightest = math.inf
    for _ in range(60):
        q = world.state.q
        for finger in hand.finger_names:
            idx = hand.finger_q_index(finger)
            q[idx] = rng.uniform(hand.lower[idx], hand.upper[idx])
        q[xyz] = centre - np.array([0.12, 0.0, 0.0]) + rng.uniform(-0.04, 0.04, size=3)
        world.set_q(q)
        before = min(world.scene.gap(world.state, g) for g in ids)
        if before <= 0.0:
            continue
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        step = float(rng.uniform(0.0, before))
        q[xyz] = q[xyz] + d * step
        world.set_q(q)
        after = min(world.scene.gap(world.state, g) for g in ids)
        assert after >= _probe_floor_after(before, step)
        tightest = min(tightest, after - _probe_floor_after(before, step))
    assert tightest < 1e-3  # some translations head straight at the object: the bound is tight
