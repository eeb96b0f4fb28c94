"""A plan's state and scene lent and taken back (eos_svc.agents.world_parts): reuse, bounds, and
the same plans as with new ones."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import coal
import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.agents.planner import build_world, default_hand
from eos_svc.agents.world_parts import WorldParts, history_free, object_key, world_parts
from eos_svc.kinematics import allegro_hand

SPHERE = ObjectSpec()
BOX = ObjectSpec("box", {"size": (0.04, 0.05, 0.06)}, (0.2, 0.0, -0.01), (0.0, 0.0, 0.4))
ELLIPSOID = ObjectSpec("ellipsoid", {"radii": (0.025, 0.03, 0.035)}, (0.21, 0.01, -0.015))
CYLINDER = ObjectSpec("cylinder", {"radius": 0.022, "length": 0.07}, (0.2, 0.02, -0.01), (0.3, 0.0, 0.0))
CAPSULE = ObjectSpec("capsule", {"radius": 0.02, "length": 0.05}, (0.21, -0.01, -0.02))


@pytest.fixture
def hand():
    return default_hand()


def _without_spares(parts: WorldParts, monkeypatch: pytest.MonkeyPatch) -> WorldParts:
    """``parts`` with no spares and none kept while the test runs (every plan builds its own)."""
    monkeypatch.setattr(parts, "keep", 0)
    monkeypatch.setattr(parts, "_states", [])
    monkeypatch.setattr(parts, "_scenes", type(parts._scenes)())
    monkeypatch.setattr(parts, "_scene_count", 0)
    return parts


@pytest.fixture
def fresh_parts(hand, monkeypatch):
    """The hand's parts with no spares kept while the test runs (every plan builds its own)."""
    return _without_spares(world_parts(hand), monkeypatch)


def _result(request: PlanRequest) -> dict:
    out = plan(request, keep_trace=True).to_dict()
    out.pop("wall_time_s")
    return out


def test_a_plan_gives_its_parts_back_and_the_next_one_reuses_them(hand):
    parts = WorldParts(hand)
    state, scene = parts.lend(SPHERE)
    parts.give_back(SPHERE, state, scene)
    assert parts.spares() == (1, 1)
    again_state, again_scene = parts.lend(ObjectSpec())  # an equal spec, another object
    assert again_state is state and again_scene is scene
    assert parts.spares() == (0, 0)


def test_a_lent_state_is_at_the_neutral_q_whatever_the_last_plan_left(hand):
    parts = WorldParts(hand)
    state, scene = parts.lend(SPHERE)
    q = hand.neutral()
    q[hand.wrist_q_index[0]] += 0.05
    q[hand.finger_q_index(hand.finger_names[0])[0]] += 0.3
    state.update(q)
    state.joint_jacobians()
    _ = state.geometry_data
    parts.give_back(SPHERE, state, scene)
    lent, _ = parts.lend(SPHERE)
    fresh = hand.state(hand.neutral())
    assert lent is state
    np.testing.assert_array_equal(lent.q, fresh.q)
    for name in hand.finger_names:
        np.testing.assert_array_equal(lent.tip_position(name), fresh.tip_position(name))
    lent.joint_jacobians()
    fresh.joint_jacobians()
    np.testing.assert_array_equal(lent.data.J, fresh.data.J)
    for a, b in zip(lent.geometry_data.oMg, fresh.geometry_data.oMg, strict=True):
        np.testing.assert_array_equal(a.homogeneous, b.homogeneous)


def test_a_scene_is_lent_only_for_the_same_object(hand):
    parts = WorldParts(hand)
    state, scene = parts.lend(SPHERE)
    parts.give_back(SPHERE, state, scene)
    moved = ObjectSpec(position=(0.21, 0.02, -0.0150001))
    _, other = parts.lend(moved)
    assert other is not scene
    assert other.object.placement.translation[2] == -0.0150001
    assert object_key(ObjectSpec(position=(0.21, 0.0, -0.015))) != object_key(
        ObjectSpec(position=(0.21, -0.0, -0.015))
    )
    turned = ObjectSpec(BOX.shape, BOX.size, BOX.position, (0.0, 0.0, 0.41))  # the pose's rpy alone
    state, scene = parts.lend(BOX)
    parts.give_back(BOX, state, scene)
    assert parts.lend(turned)[1] is not scene


def test_spares_are_bounded_and_the_least_recently_given_back_go_first(hand):
    parts = WorldParts(hand, keep=2)
    specs = [ObjectSpec(size={"radius": 0.02 + 0.001 * i}) for i in range(3)]
    lent = [parts.lend(s) for s in specs]
    for spec, (state, scene) in zip(specs, lent, strict=True):
        parts.give_back(spec, state, scene)
    assert parts.spares() == (2, 2)
    assert parts.lend(specs[0])[1] is not lent[0][1]  # dropped: a new scene
    assert parts.lend(specs[2])[1] is lent[2][1]


def test_two_plans_at_once_never_share_a_part(hand):
    parts = WorldParts(hand)
    state, scene = parts.lend(SPHERE)
    parts.give_back(SPHERE, state, scene)
    got: list[tuple] = []
    barrier = threading.Barrier(4)

    def take() -> None:
        barrier.wait()
        got.append(parts.lend(SPHERE))

    threads = [threading.Thread(target=take) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len({id(s) for s, _ in got}) == 4 and len({id(c) for _, c in got}) == 4


def test_parts_of_another_hand_are_refused(hand):
    allegro = allegro_hand()
    state, scene = WorldParts(allegro).lend(SPHERE)
    with pytest.raises(ValueError, match="this hand"):
        WorldParts(hand).give_back(SPHERE, state, scene)
    with pytest.raises(ValueError, match="parts"):
        build_world(PlanRequest(), hand, parts=WorldParts(allegro))


def test_a_hand_with_a_convex_polytope_keeps_no_spares(hand):
    assert history_free(hand) and history_free(allegro_hand())
    points = coal.StdVec_Vec3s()
    for p in ([0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]):
        points.append(np.array(p, dtype=float))
    convex = coal.ConvexBase.convexHull(points, False, None)
    assert isinstance(convex, coal.ConvexBase)
    polytope_hand = SimpleNamespace(
        collision_model=SimpleNamespace(geometryObjects=[SimpleNamespace(geometry=convex)])
    )
    assert not history_free(polytope_hand)  # type: ignore[arg-type]
    assert WorldParts(polytope_hand).keep == 0  # type: ignore[arg-type]


@pytest.mark.parametrize("seed", [1, 4])
def test_plans_with_lent_parts_are_the_plans_with_new_ones(fresh_parts, seed):
    objects = [SPHERE, BOX, ELLIPSOID, CYLINDER, CAPSULE]
    requests = [PlanRequest(obj=o, seed=seed) for o in objects]
    with_new = [_result(r) for r in requests]  # keep = 0: every plan builds its own
    fresh_parts.keep = 4
    # each object planned after another object's plan, then again right after its own
    for i, request in enumerate(requests):
        assert _result(request) == with_new[i], request.obj.shape
        assert _result(request) == with_new[i], request.obj.shape
    assert fresh_parts.spares() == (1, 4)


def test_a_worlds_generators_are_the_seed_sequences_two_children(hand):
    search, sensor = np.random.SeedSequence(12345).spawn(2)
    world = build_world(PlanRequest(seed=12345, tactile_noise=2e-4), hand)
    assert np.array_equal(world.rng.random(8), np.random.default_rng(search).random(8))
    assert np.array_equal(world.sensor.rng.random(8), np.random.default_rng(sensor).random(8))


def test_a_plan_that_raises_keeps_its_parts(hand, monkeypatch):
    parts = world_parts(hand)
    plan(PlanRequest(seed=5, max_cycles=1))  # gives its parts back
    before = parts.spares()

    def broken(*_a, **_k):
        raise RuntimeError("a bug after the run")

    monkeypatch.setattr("eos_svc.agents.planner.PlanResult.from_run", broken)
    with pytest.raises(RuntimeError, match="a bug"):
        plan(PlanRequest(seed=5, max_cycles=1))
    assert parts.spares() == (before[0] - 1, before[1] - 1)  # lent, never given back


def test_plans_in_two_threads_are_the_plans_in_one(hand):
    requests = [PlanRequest(obj=o, seed=2) for o in (SPHERE, SPHERE, BOX, BOX)]
    alone = [_result(r) for r in requests]
    got: dict[int, dict] = {}
    barrier = threading.Barrier(2)

    def worker(indices: list[int]) -> None:
        barrier.wait()
        for i in indices:
            got[i] = _result(requests[i])

    threads = [threading.Thread(target=worker, args=(ix,)) for ix in ([0, 2], [1, 3])]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert [got[i] for i in range(4)] == alone


def test_another_hands_plans_with_lent_parts_are_the_plans_with_new_ones(monkeypatch):
    allegro = allegro_hand()
    parts = _without_spares(world_parts(allegro), monkeypatch)
    request = PlanRequest(obj=CYLINDER, seed=3)
    with_new = plan(request, hand=allegro).to_dict()
    with_new.pop("wall_time_s")
    parts.keep = 4
    for _ in range(2):
        lent = plan(request, hand=allegro).to_dict()
        lent.pop("wall_time_s")
        assert lent == with_new
    assert parts.spares() == (1, 1)

