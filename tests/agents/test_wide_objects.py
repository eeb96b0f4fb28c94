"""Objects as wide as the hand is high (d/h ≥ 1) but within the fingertips' span: the wrist
keeps a positive opportunistic sub-rating until the hand reaches its grasp position, so the
plan does not stall with every finger unable to land (random-draw stalls, seeded)."""

from __future__ import annotations

import pytest

from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.wrist import WRIST_FLOOR
from eos_svc.schema.request import ObjectSpec

#: objects of a random draw that stalled with the wrist rated 1 − d/h = 0 (d/h > 1)
WIDE = [
    ObjectSpec("box", {"size": (0.0662, 0.078, 0.0906)}, (0.2125, 0.096, -0.0032), (-0.667, -0.4915, 1.1969)),
    ObjectSpec("capsule", {"radius": 0.0471, "length": 0.1142}, (0.25, -0.05, 0.03), (1.2, 0.3, -0.4)),
    ObjectSpec("box", {"size": (0.114, 0.075, 0.085)}, (0.22, 0.0, -0.02), (0.3, -0.2, 0.9)),
]


@pytest.mark.parametrize("obj", WIDE, ids=lambda o: o.shape)
def test_wide_object_is_grasped_not_stalled(obj):
    result = plan(PlanRequest(obj=obj, seed=1335484845), keep_trace=True)
    assert result.status == "success", result.reason
    assert result.good_grasp
    grasping = [c for c in result.trace if c.stage == "grasping"]
    wrist_moves = [c for c in grasping if c.chosen == "wrist"]
    assert len(wrist_moves) >= 2  # the wrist acted again after its first approach step
    d_over_h = result.d_over_h
    if d_over_h is not None and d_over_h >= 1.0:
        rated = [r for c in wrist_moves[1:] for r in c.ratings if r.name == "wrist"]
        assert all(r.opportunistic == pytest.approx(WRIST_FLOOR) for r in rated)
