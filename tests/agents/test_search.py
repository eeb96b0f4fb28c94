"""The search covers its workspace without revisiting: every findable object is located."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from eos_svc.agents import ObjectSpec, PlanRequest, keys
from eos_svc.agents.planner import build_world, default_hand, make_object
from eos_svc.agents.search import search_move
from eos_svc.board import Board
from eos_svc.drivers.kinematic import KinematicDriver
from eos_svc.world.coverage import (
    column_counts,
    coverage_spacing,
    findable,
    space_filling_order,
    wrist_columns,
)
from eos_svc.world.hand_context import context_for


def search_length(spec: ObjectSpec, seed: int, limit: int = 200) -> int:
    world = build_world(PlanRequest(obj=spec, seed=seed))
    driver = KinematicDriver(world)
    board = Board()
    for n in range(1, limit + 1):
        search_move(driver, board, "wrist")
        if board.get(keys.LOCATED):
            assert world.object_gap_to_grasp_centre() <= world.params.envelope_radius
            assert world.hand_clearance() >= world.params.clearance - 1e-9  # never touched it
            return n
    return limit + 1


def test_columns_cover_the_box():
    params = context_for().params
    cols = wrist_columns(params).reshape(-1, 2)
    rng = np.random.default_rng(0)
    pts = rng.uniform(params.search_box_lo[1:], params.search_box_hi[1:], size=(2000, 2))
    nearest = np.min(np.linalg.norm(pts[:, None, :] - cols[None, :, :], axis=2), axis=1)
    assert nearest.max() <= params.envelope_radius  # every line of the box within the envelope
    assert coverage_spacing(params) == pytest.approx(math.sqrt(2) * params.envelope_radius)


def vectorised_space_filling_order(counts, rng):
    """The maximin order written with numpy arrays (space_filling_order's scalar loop must agree)."""
    ny, nz = counts
    points = np.array([(i, j) for i in range(ny) for j in range(nz)], dtype=float)
    jitter = rng.uniform(0.0, 1e-3, len(points))
    first = int(rng.integers(len(points)))
    order = [first]
    nearest = np.linalg.norm(points - points[first], axis=1)
    nearest[first] = -1.0
    for _ in range(len(points) - 1):
        k = int(np.argmax(np.where(nearest >= 0.0, nearest + jitter, -1.0)))
        order.append(k)
        to_k = np.linalg.norm(points - points[k], axis=1)
        nearest = np.where(nearest >= 0.0, np.minimum(nearest, to_k), -1.0)
        nearest[k] = -1.0
    return [(int(points[k][0]), int(points[k][1])) for k in order]


@pytest.mark.parametrize("counts", [(6, 6), (1, 1), (1, 5), (4, 1), (3, 7), (9, 8)])
def test_scalar_order_equals_the_vectorised_one(counts):
    for seed in range(25):
        fast = space_filling_order(counts, np.random.default_rng(seed))
        plain = vectorised_space_filling_order(counts, np.random.default_rng(seed))
        assert fast == plain
        assert all(type(i) is int and type(j) is int for i, j in fast)


def test_order_visits_every_column_once_and_follows_the_seed():
    counts = (6, 6)
    a = space_filling_order(counts, np.random.default_rng(3))
    b = space_filling_order(counts, np.random.default_rng(3))
    c = space_filling_order(counts, np.random.default_rng(4))
    assert a == b and a != c
    assert sorted(a) == [(i, j) for i in range(6) for j in range(6)]
    # maximin: each column is the farthest from those before it, so that distance never grows
    pts = np.array(a, dtype=float)
    gaps = [float(np.min(np.linalg.norm(pts[:k] - pts[k], axis=1))) for k in range(1, len(pts))]
    assert all(later <= earlier + 1e-9 for earlier, later in itertools.pairwise(gaps))
    for k in range(1, len(pts)):  # and it is the farthest of the columns left
        rest = pts[k:]
        far = max(float(np.min(np.linalg.norm(pts[:k] - p, axis=1))) for p in rest)
        assert gaps[k - 1] >= far - 1e-9


@pytest.mark.parametrize(
    "position", [(0.21, 0.02, -0.015), (0.40, 0.14, 0.14), (0.30, -0.12, 0.0), (0.15, 0.10, -0.12)]
)
def test_findable_objects_are_found_within_one_pass(position):
    spec = ObjectSpec("sphere", {"radius": 0.025}, position)
    params = context_for().params
    assert findable(make_object(spec), params)
    ny, nz = column_counts(params)
    lengths = [search_length(spec, seed) for seed in range(1, 11)]
    assert max(lengths) <= ny * nz, lengths


def test_object_within_the_fingers_reach_from_the_rear_is_not_findable():
    params = context_for().params
    rear = ObjectSpec("sphere", {"radius": 0.03}, (0.05, -0.1, 0.1))  # the fingers reach it at the rear
    assert not findable(make_object(rear), params)
    ahead = ObjectSpec("sphere", {"radius": 0.03}, (0.09, -0.1, 0.1))
    assert findable(make_object(ahead), params)
    ny, nz = column_counts(params)
    assert max(search_length(ahead, seed) for seed in range(1, 6)) <= ny * nz


def test_object_beyond_every_sweep_is_not_findable():
    params = context_for().params
    far = ObjectSpec("sphere", {"radius": 0.02}, (0.30, 0.0, 0.25))  # 8 cm above the box's top
    assert not findable(make_object(far), params)


def test_forward_reach_of_hand3x3_is_the_default_of_the_rule():
    from eos_svc.grasp.sweeps import forward_reach
    from eos_svc.world.coverage import HAND3X3_FORWARD_REACH
    from eos_svc.world.hand_context import context_for

    hand = default_hand()
    assert forward_reach(hand, context_for(hand).sweeps) == pytest.approx(HAND3X3_FORWARD_REACH, abs=1e-3)
