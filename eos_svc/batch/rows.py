"""One row of a batch's dataset: a plan, its grasp, its quality and its validation.

A row is a plain dict of the columns below (the Parquet schema is in
:mod:`eos_svc.batch.store`). Grasp columns are ``None`` when there is no grasp to describe (a
request admission refused, a plan that raised); validation columns are ``None`` when the plan
was not validated.
"""

from __future__ import annotations

import json
from typing import Any

from eos_svc.batch.expansion import PlanKey

#: status of a request admission refused (the planner's statuses are in PlanResult)
REFUSED = "refused"
#: status of a plan whose task raised (the reason carries the exception)
ERROR = "error"


def key_columns(key: PlanKey, worker: str) -> dict[str, Any]:
    """The columns every row has, from its key: what was planned and where."""
    return {
        "key": key.key,
        "label": key.label,
        "condition": key.condition,
        "hand": key.hand,
        "seed": key.seed,
        "world": key.world,
        "request": json.dumps(key.request, sort_keys=True, allow_nan=False),
        "worker": worker,
    }


def empty_columns(status: str, reason: str) -> dict[str, Any]:
    """The outcome columns of a row without a plan result."""
    return {
        "status": status,
        "reason": reason,
        "good_grasp": False,
        "force_closure": False,
        "epsilon": None,
        "friction": None,
        "wrist_pose": None,
        "q_final": None,
        "contacts": None,
        "cycles": 0,
        "cycles_per_stage": "{}",
        "final_stage": None,
        "plan_s": 0.0,
        **validation_columns(None, None),
    }


def result_columns(result: Any, wrist_index: list[int]) -> dict[str, Any]:
    """The outcome columns of a :class:`~eos_svc.agents.PlanResult`.

    ``wrist_pose`` is the wrist joints' values in ``q_final`` (``wrist_index``; for hand3x3 and
    the Allegro mount x, y, z in m, then roll, pitch, yaw in rad).
    """
    q = None if result.q_final is None else [float(v) for v in result.q_final]
    contacts = [
        {
            "finger": finger,
            "touching": bool(c.get("touching")),
            "distance_m": _float(c.get("distance")),
            "point": _vector(c.get("point")),
            "normal": _vector(c.get("normal")),
        }
        for finger, c in result.contacts.items()
    ]
    return {
        "status": result.status,
        "reason": result.reason,
        "good_grasp": bool(result.good_grasp),
        "force_closure": bool(result.force_closure),
        "epsilon": float(result.epsilon),
        "friction": float(result.friction),
        "wrist_pose": None if q is None else [q[i] for i in wrist_index],
        "q_final": q,
        "contacts": contacts,
        "cycles": int(result.cycles),
        "cycles_per_stage": json.dumps(result.cycles_per_stage, sort_keys=True),
        "final_stage": result.final_stage,
        "plan_s": float(result.wall_time_s),
    }


def validation_columns(report: Any, failure: str | None) -> dict[str, Any]:
    """The validation columns: from a :class:`~eos_svc.validation.GraspValidation`, or the
    reason it could not run (``failure``), or neither (not validated)."""
    if report is None:
        return {
            "validated": failure is not None,
            "held": None,
            "validation_reason": failure,
            "max_displacement_m": None,
            "validation": None,
            "validation_s": 0.0,
        }
    data = report.to_dict()
    displacements = [v for v in data["displacement_m"].values() if v is not None]
    return {
        "validated": True,
        "held": bool(report.held),
        "validation_reason": data.get("reason"),
        "max_displacement_m": max(displacements) if displacements else None,
        "validation": json.dumps(data, sort_keys=True, default=str),
        "validation_s": float(report.wall_time_s),
    }


def _float(value: object) -> float | None:
    return None if value is None else float(value)  # type: ignore[arg-type]


def _vector(value: object) -> list[float] | None:
    return None if value is None else [float(v) for v in value]  # type: ignore[attr-defined]
