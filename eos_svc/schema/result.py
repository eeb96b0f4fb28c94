"""The plan result: how the plan ended and what it found. ``success`` only when the end agent
judged the grasp good; all stages completed with a grip that is not good is ``completed`` (the
paper's graceful exit, §6); otherwise the run's own status.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from eos_svc.records import CycleRecord, RunResult, RunStatus, to_jsonable
from eos_svc.schema import keys

if TYPE_CHECKING:
    from eos_svc.schema.request import PlanRequest

#: core run status -> plan status (a completed run is ``success`` only with a good grasp)
PLAN_STATUS: dict[RunStatus, str] = {status: status.value for status in RunStatus}


@dataclass(frozen=True)
class PlanResult:
    """Everything a caller wants to know about one plan.

    Attributes:
        status: success (the end agent judged the grasp good), completed (every stage done,
            the grip not good), failed, stalled, cycle_limit, deadline, cancelled or error.
        reason: why, in words.
        cycles: cycles in total; ``cycles_per_stage`` per stage entered.
        stages_completed: stages exited gracefully, in order.
        shape: post_shape's postulate (:class:`~eos_svc.schema.board_entries.ShapeEntry`) or None.
        curvature: EP1's last curvature estimate (principal curvatures, σ, radii).
        ground_truth: the real object (shape, size, pose, diameter, d/h).
        contacts: per finger: touching, distance (m), contact point and normal (world).
        good_grasp: the end agent's verdict (paper Fig. 2 and force closure; False unjudged).
        force_closure, epsilon, quality: the contacts' force closure at μ = ``friction``, their
            Ferrari–Canny ε (:mod:`eos_svc.grasp.quality`) and the full quality record.
        q_final: the hand configuration judged (None when never judged).
        d_over_h: estimated diameter over hand height (None if never estimated).
        touches: the contacts the postulate rests on; ``probes``: EP2's probes plus EP1's runs.
        seed: the request's seed. ``wall_time_s``: seconds for the whole call.
        trace: every cycle record (when kept).
        validation: the Drake validation of the final grasp, None unless asked for.
        world: the Drake world's figures (object moved, lift test, times); None when kinematic.
    """

    status: str
    reason: str
    cycles: int
    cycles_per_stage: dict[str, int]
    stages_completed: tuple[str, ...]
    final_stage: str
    shape: dict | None
    curvature: dict | None
    ground_truth: dict
    contacts: dict
    good_grasp: bool
    diameter_angle_deg: float | None
    d_over_h: float | None
    hand_height: float
    ep1_runs: int
    seed: int
    weights: dict[str, float]
    wall_time_s: float
    request: dict = field(repr=False)
    trace: tuple[CycleRecord, ...] = field(default=(), repr=False)
    force_closure: bool = False
    epsilon: float = 0.0
    friction: float = 0.5
    quality: dict | None = None
    q_final: tuple[float, ...] | None = field(default=None, repr=False)
    validation: dict | None = None
    world: dict | None = None
    touches: int = 0
    probes: int = 0

    @property
    def success(self) -> bool:
        """The end agent judged the grasp good (status ``success``)."""
        return self.status == "success"

    @property
    def precision_grip(self) -> bool:
        """Every fingertip touches the object (the paper's Fig. 3 criterion; good or not)."""
        return bool(self.contacts) and all(c.get("touching") for c in self.contacts.values())

    def with_validation(self, validation: Any) -> PlanResult:
        """A copy carrying ``validation`` (a GraspValidation or its dict form)."""
        data = validation.to_dict() if hasattr(validation, "to_dict") else dict(validation)
        return dataclasses.replace(self, validation=data)

    def agents_run(self) -> list[str]:
        """The chosen agent of every cycle, in order."""
        return [r.chosen for r in self.trace if r.chosen is not None]

    @classmethod
    def from_run(cls, run: RunResult, *, request: PlanRequest, **fields: Any) -> PlanResult:
        """Combine the controller's result with what the agents found (the end agent's verdict as
        given): a completed run is ``success`` only when ``good_grasp``; ``q_final`` unless given
        from the verdict in the trace."""
        if "q_final" not in fields:
            fields["q_final"] = _q_final(run.trace)
        fields.setdefault("friction", request.friction)
        status = PLAN_STATUS[run.status]
        if run.status is RunStatus.COMPLETED and fields.get("good_grasp"):
            status = "success"
        return cls(
            status=status,
            reason=run.reason,
            cycles=run.cycles,
            cycles_per_stage=dict(run.cycles_per_stage),
            stages_completed=run.stages_completed,
            final_stage=run.final_stage,
            seed=request.seed,
            weights=request.weights.to_dict(),
            request=request.to_dict(),
            trace=run.trace,
            **fields,
        )

    def to_dict(self, include_trace: bool = False, *, jsonable: bool = True) -> dict[str, Any]:
        """JSON-friendly form; the trace only when asked. ``jsonable=False``: the members as held
        (not copied: do not modify), for an encoder that writes tuples and non-finite floats
        itself (the service's msgspec)."""
        out = {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if f.name not in ("trace", "world")
        }
        if self.world is not None:
            out["world"] = self.world
        if include_trace:
            out["trace"] = [r.to_dict() for r in self.trace]
        if not jsonable:
            return out
        result: dict[str, Any] = to_jsonable(out)
        return result

    def to_json(self, include_trace: bool = False) -> str:
        """Strict JSON text."""
        return json.dumps(self.to_dict(include_trace), allow_nan=False)


def _q_final(trace: tuple[CycleRecord, ...]) -> tuple[float, ...] | None:
    """The hand configuration of the last end-agent verdict written in ``trace``."""
    for record in reversed(trace):
        for change in record.changes:
            if change.key == keys.OUTCOME and isinstance(change.new, dict) and "q_final" in change.new:
                return tuple(float(v) for v in change.new["q_final"])
    return None
