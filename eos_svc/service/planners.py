"""The planner a service instance runs, and the admission check it makes before queueing a goal."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

from eos_svc.schema.request import PlanRequest

#: a planner as the service calls it (the signature of ``eos_svc.agents.planner.plan``)
Planner = Callable[..., Any]
#: admission check of a decoded request: raises ValidationError(field, reason) to refuse it
Admission = Callable[[PlanRequest], None]


def default_planner() -> Planner:
    """The grasp planner, imported only when first needed."""
    from eos_svc.agents.planner import plan  # lazy: Pinocchio and coal load here

    return plan


def default_admission() -> Admission:
    """The grasp planner's admission check (:func:`eos_svc.world.admission.check_plannable` on
    the default hand, resolved once: :func:`~eos_svc.world.admission.default_check`)."""
    from eos_svc.world.admission import default_check  # lazy: Pinocchio and coal load here

    return default_check()


def is_grasp_planner(planner: Planner | None) -> bool:
    """Whether ``planner`` is the grasp planner (``None``: the default, which is)."""
    return planner is None or (
        getattr(planner, "__module__", None) == "eos_svc.agents.planner"
        and getattr(planner, "__name__", "") == "plan"
    )


def planner_options(
    planner: Planner, admission: Admission | None, offered: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The keyword arguments the service passes its planner: the grasp planner keeps no trace
    (the service streams every cycle instead), skips its own admission check when the service
    has just run the same one, and takes a request's plug-in names from ``offered`` (this
    instance's plug-ins) only."""
    try:
        accepted = set(inspect.signature(planner).parameters)
    except (TypeError, ValueError):
        accepted = set()
    options: dict[str, Any] = {"keep_trace": False} if "keep_trace" in accepted else {}
    if "check" in accepted and admission is not None and admission is default_admission():
        options["check"] = False
    if "offered" in accepted:
        options["offered"] = dict(offered or {})
    return options
