"""The grasp planner of the paper: eight agents, three stages (search, information, grasping).

``plan(request)`` runs one plan; :class:`PlanRequest` says what to grasp; the result is a
:class:`PlanResult`. The planner's names load on first use (they bring Pinocchio and coal);
the request, the result and the board's keys live in :mod:`eos_svc.schema`, the world the
agents act in in :mod:`eos_svc.world`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from eos_svc.schema import keys
from eos_svc.schema.request import ObjectSpec, PlanRequest
from eos_svc.schema.result import PlanResult

if TYPE_CHECKING:
    from eos_svc.agents.planner import DEFAULT_RATINGS, build_agents, build_world, default_hand, plan

#: the planner's names, imported from :mod:`eos_svc.agents.planner` when first asked for
_PLANNER = ("DEFAULT_RATINGS", "build_agents", "build_world", "default_hand", "plan")

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


def __getattr__(name: str) -> Any:
    if name in _PLANNER:
        from eos_svc.agents import planner

        return getattr(planner, name)
    raise AttributeError(f"module 'eos_svc.agents' has no attribute {name!r}")
