"""The grasp tests' scene: the default position and a synthesis on hand3x3's default world."""

from __future__ import annotations

from eos_svc.agents import ObjectSpec, PlanRequest
from eos_svc.agents.planner import build_world, default_hand
from eos_svc.grasp.postulate import make_object
from eos_svc.grasp.synthesis import GraspSynthesis
from eos_svc.world.hand_context import context_for

#: the default scene's object position (m)
HERE = (0.21, 0.02, -0.015)


def synthesis(spec: ObjectSpec, friction: float = 0.5) -> GraspSynthesis:
    """Grasp synthesis of ``spec`` (known exactly) for hand3x3 at Coulomb ``friction``."""
    hand = default_hand()
    world = build_world(PlanRequest(), hand)
    return GraspSynthesis(hand, world.sweeps, context_for(hand).params, make_object(spec), friction)
