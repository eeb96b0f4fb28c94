"""The plan result (DESIGN §6): how the plan ended and what it found."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from eos_svc.agents import keys
from eos_svc.agents.quality import DEFAULT_EDGES, contacts_quality
from eos_svc.records import CycleRecord, RunResult, RunStatus, to_jsonable

if TYPE_CHECKING:
    from eos_svc.agents.request import PlanRequest

#: core run status -> plan status
PLAN_STATUS: dict[RunStatus, str] = {
    RunStatus.COMPLETED: "success",
    RunStatus.FAILED: "failed",
    RunStatus.STALLED: "stalled",
    RunStatus.CYCLE_LIMIT: "cycle_limit",
    RunStatus.DEADLINE: "deadline",
    RunStatus.CANCELLED: "cancelled",
    RunStatus.ERROR: "error",
}


@dataclass(frozen=True)
class PlanResult:
    """Everything a caller wants to know about one plan.

    Attributes:
        status: success, failed, stalled, cycle_limit, deadline, cancelled or error.
        reason: why, in words.
        cycles: cycles in total; ``cycles_per_stage`` per stage entered.
        stages_completed: stages exited gracefully, in order.
        shape: post_shape's postulate or None: ``class``, ``confidence`` (P(class right and size
            within tolerance)), ``object`` (the postulated object in the request's JSON form, None
            for a plane or before the size is known), ``pose_known``, ``evidence`` (contacts,
            fit residual, competing classes), ``grasp_radius``, ``diameter``, ``centre``.
        curvature: EP1's last curvature estimate (principal curvatures, σ, radii).
        ground_truth: the real object (shape, size, pose, diameter, d/h).
        contacts: per finger: touching, distance (m), contact point and normal (world).
        good_grasp: all fingertips touch, about the diameter (paper Fig. 2), and the
            contacts are in force closure at the request's friction.
        force_closure: the touching contacts are in force closure (Coulomb, μ = ``friction``).
        epsilon: Ferrari–Canny ε of the touching contacts (0 without force closure); see
            :mod:`eos_svc.agents.quality` (torques about the object's centre / its half diameter).
        friction: the Coulomb coefficient μ used.
        quality: the full quality record (cone edges, torque scale, rank, …).
        q_final: the hand configuration the end agent judged (None when it never acted or
            the trace was not kept).
        d_over_h: estimated diameter over hand height (None if never estimated).
        seed: the request's seed. ``wall_time_s``: seconds for the whole call.
        trace: every cycle record (when kept).
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

    @property
    def success(self) -> bool:
        """All fingertips touch the object."""
        return self.status == "success"

    def agents_run(self) -> list[str]:
        """The chosen agent of every cycle, in order."""
        return [r.chosen for r in self.trace if r.chosen is not None]

    @classmethod
    def from_run(cls, run: RunResult, *, request: PlanRequest, **fields: Any) -> PlanResult:
        """Combine the controller's result with what the agents found.

        ``force_closure``, ``epsilon`` and ``quality`` are computed here from the final
        ``contacts`` (unless given) at the request's friction, with the object's centre and
        half diameter from ``ground_truth``; ``good_grasp`` is kept only with force closure.
        ``q_final`` (unless given) comes from the end agent's verdict in the trace.
        """
        if "quality" not in fields and "contacts" in fields and "ground_truth" in fields:
            truth = fields["ground_truth"]
            q = contacts_quality(
                fields["contacts"],
                truth["position"],
                0.5 * float(truth["diameter"]),
                request.friction,
                DEFAULT_EDGES,
            )
            fields["quality"] = q.to_dict()
            fields["force_closure"] = q.force_closure
            fields["epsilon"] = q.epsilon
            fields["good_grasp"] = bool(fields.get("good_grasp")) and q.force_closure
        if "q_final" not in fields:
            fields["q_final"] = _q_final(run.trace)
        fields.setdefault("friction", request.friction)
        return cls(
            status=PLAN_STATUS[run.status],
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

    def to_dict(self, include_trace: bool = False) -> dict[str, Any]:
        """JSON-friendly form (DESIGN §6); the trace only when asked."""
        out = {
            "status": self.status,
            "reason": self.reason,
            "cycles": self.cycles,
            "cycles_per_stage": self.cycles_per_stage,
            "stages_completed": list(self.stages_completed),
            "final_stage": self.final_stage,
            "shape": self.shape,
            "curvature": self.curvature,
            "ground_truth": self.ground_truth,
            "contacts": self.contacts,
            "good_grasp": self.good_grasp,
            "force_closure": self.force_closure,
            "epsilon": self.epsilon,
            "friction": self.friction,
            "quality": self.quality,
            "q_final": None if self.q_final is None else list(self.q_final),
            "diameter_angle_deg": self.diameter_angle_deg,
            "d_over_h": self.d_over_h,
            "hand_height": self.hand_height,
            "ep1_runs": self.ep1_runs,
            "seed": self.seed,
            "weights": self.weights,
            "wall_time_s": self.wall_time_s,
            "request": self.request,
        }
        if include_trace:
            out["trace"] = [r.to_dict() for r in self.trace]
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
