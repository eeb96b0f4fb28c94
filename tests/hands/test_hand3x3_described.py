"""hand3x3 described by its TOML file is the hand the planner was built around: the same model,
the same description, the world parameters it was tuned with, and the same plans as the hand
loaded straight from its URDF with those parameters."""

from __future__ import annotations

import numpy as np

from eos_svc.agents import PlanRequest, plan
from eos_svc.hands import load_hand_named
from eos_svc.kinematics import HandDescription, load_hand
from eos_svc.world.hand_context import HandContext, default_context
from eos_svc.world.parameters import WorldParameters


def test_the_description_makes_the_urdf_hand():
    described, plain = load_hand_named("hand3x3"), load_hand()
    assert described.description == HandDescription.hand3x3() == plain.description
    assert described.nq == plain.nq and np.array_equal(described.neutral(), plain.neutral())
    assert np.array_equal(described.lower, plain.lower) and np.array_equal(described.upper, plain.upper)
    assert described.hand_height == plain.hand_height
    names = [g.name for g in described.collision_model.geometryObjects]
    assert names == [g.name for g in plain.collision_model.geometryObjects]
    assert default_context().hand.name == "hand3x3"
    assert default_context().params == WorldParameters()  # the description's [world] = the defaults


def test_plans_are_those_of_the_urdf_hand_with_the_default_parameters():
    old = HandContext.build(load_hand(), WorldParameters())
    for data in ({"seed": 2}, {"seed": 1, "object": {"shape": "box", "size": [0.05, 0.06, 0.04]}}):
        request = PlanRequest.from_dict({**data, "deadline_s": None})
        new, before = plan(request), plan(request, context=old)
        assert [(r.stage, r.chosen, r.detail) for r in new.trace] == [
            (r.stage, r.chosen, r.detail) for r in before.trace
        ]
        assert new.q_final == before.q_final and new.epsilon == before.epsilon
