"""Stand-in planners for the transport's tests: :func:`root_plan` (the core's root-finding demo,
no Pinocchio) and :func:`slowed` (every cycle at least a given time).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from eos_svc.board import Board
from eos_svc.controller import CancelToken, Controller
from eos_svc.demo import STAGES, Bisect, Done, Scan, Secant, Widen, default_problem
from eos_svc.records import CycleRecord
from eos_svc.schema.request import PlanRequest


def root_plan(
    request: PlanRequest,
    *,
    on_cycle: Callable[[CycleRecord], None] | None = None,
    cancel: CancelToken | None = None,
) -> dict[str, Any]:
    """Solve cos(x) = x with the EOS controller under the request's weights and limits."""
    problem = default_problem()
    f, tol = problem.f, problem.tolerance
    controller = Controller(
        [Scan(f), Widen(f), Bisect(f, tol), Secant(f, tol), Done(tol)],
        STAGES,
        request.weights,
        max_cycles=request.max_cycles,
        deadline_s=request.deadline_s,
        keep_trace=False,
        callbacks=[on_cycle] if on_cycle is not None else [],
    )
    result = controller.run(Board({"interval": problem.interval}), cancel=cancel)
    out = result.to_dict()
    out["seed"] = request.seed
    return out


def slowed(planner: Callable[..., Any], cycle_s: float) -> Callable[..., Any]:
    """``planner`` with every cycle lasting at least ``cycle_s`` seconds (sleeps in the cycle callback)."""

    def plan(
        request: PlanRequest,
        *,
        on_cycle: Callable[[CycleRecord], None] | None = None,
        cancel: CancelToken | None = None,
    ) -> Any:
        def slow_cycle(record: CycleRecord) -> None:
            time.sleep(cycle_s)
            if on_cycle is not None:
                on_cycle(record)

        return planner(request, on_cycle=slow_cycle, cancel=cancel)

    return plan
