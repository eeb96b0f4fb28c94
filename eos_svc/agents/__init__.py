"""The grasp planner of the paper: eight agents, three stages (search, information, grasping).

``plan(request)`` runs one plan; :class:`PlanRequest` says what to grasp; the result is a
:class:`PlanResult`. Importing this package loads Pinocchio and coal; the request, the result
and the board's keys live in :mod:`eos_svc.schema`, the world the agents act in in
:mod:`eos_svc.world`.
"""

from __future__ import annotations

from eos_svc.agents.planner import DEFAULT_RATINGS, build_agents, build_world, default_hand, plan
from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.schema.result import PlanResult

__all__ = [
    "DEFAULT_RATINGS",
    "ObjectSpec",
    "PlanRequest",
    "PlanResult",
    "build_agents",
    "build_world",
    "default_hand",
    "keys",
    "plan",
]
