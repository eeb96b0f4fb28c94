"""The grasp planner of the paper: eight agents, three stages (search, information, grasping).

``plan(request)`` runs one plan; :class:`PlanRequest` says what to grasp; the
result is a :class:`PlanResult`. Importing this package loads Pinocchio and coal.
"""

from eos_svc.agents.planner import DEFAULT_RATINGS, build_agents, build_world, default_hand, plan
from eos_svc.agents.request import ObjectSpec, PlanRequest
from eos_svc.agents.result import PlanResult

__all__ = [
    "DEFAULT_RATINGS",
    "ObjectSpec",
    "PlanRequest",
    "PlanResult",
    "build_agents",
    "build_world",
    "default_hand",
    "plan",
]
