"""Cycle records and run results (paper §2.1): a :class:`CycleRecord` per cycle, a
:class:`RunResult` whose status says how the run ended; JSON-friendly through :func:`to_jsonable`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, is_dataclass
from enum import Enum
from typing import Any, NamedTuple

from eos_svc.agent import Outcome
from eos_svc.board import BoardChange
from eos_svc.errors import NotFoundError
from eos_svc.ratings import Weights


class RunStatus(str, Enum):
    """How a run ended."""

    COMPLETED = "completed"  #: all stages done, or an agent finished the run successfully
    ERROR = "error"  #: an agent raised an exception or broke the contract (a bug, reported)
    FAILED = "failed"  #: an agent finished the run and reported the goal was not met
    STALLED = "stalled"  #: the chosen agent could not act, or no agent was eligible
    CYCLE_LIMIT = "cycle_limit"  #: the cycle limit was reached
    DEADLINE = "deadline"  #: the wall-clock deadline passed
    CANCELLED = "cancelled"  #: cancelled from outside


class AgentRating(NamedTuple):
    """One agent's ratings in one cycle. ``skipped`` says why it is not ``eligible``: the repeat
    rule (:data:`REPEAT_SKIP`) or ``"unavailable: ..."``; ``where`` is its
    :attr:`~eos_svc.agent.Agent.location`, ``latency_s`` the seconds its rating took."""

    name: str
    default: float
    opportunistic: float
    learned: float
    total: float
    eligible: bool = True
    where: str = "local"
    latency_s: float = 0.0
    skipped: str | None = None


#: the JSON keys of an :class:`AgentRating` (its fields, ``name`` written ``agent``)
_RATING_KEYS = ("agent", *AgentRating._fields[1:])
#: why an agent is not eligible under the repeat rule (``AgentRating.skipped``)
REPEAT_SKIP = "acted in this stage and not asked again (repeat rule)"


class CycleRecord(NamedTuple):
    """What happened in one cycle: its ``seq`` (1-based) and ``stage_cycle`` (0-based), every
    agent's ``ratings`` in list order, the ``chosen`` agent and its ``outcome`` (``None`` when
    nothing ran), its words (``detail``), the board ``changes`` it made and ``elapsed_s``, the
    seconds since the run started."""

    seq: int
    stage: str
    stage_cycle: int
    ratings: tuple[AgentRating, ...]
    weights: Weights
    chosen: str | None
    outcome: Outcome | None
    detail: str
    changes: tuple[BoardChange, ...]
    elapsed_s: float

    def rating_of(self, name: str) -> AgentRating:
        """The rating row of agent ``name`` (:class:`~eos_svc.errors.NotFoundError`, a KeyError,
        when it was not rated)."""
        for row in self.ratings:
            if row.name == name:
                return row
        raise NotFoundError("agent", f"{name!r} was not rated in cycle {self.seq}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form."""
        return {
            "seq": self.seq,
            "stage": self.stage,
            "stage_cycle": self.stage_cycle,
            "weights": self.weights.to_dict(),
            "ratings": [dict(zip(_RATING_KEYS, r, strict=True)) for r in self.ratings],
            "chosen": self.chosen,
            "outcome": None if self.outcome is None else self.outcome.value,
            "detail": self.detail,
            "changes": [
                {"key": c.key, "old": to_jsonable(c.old), "new": to_jsonable(c.new)} for c in self.changes
            ],
            "elapsed_s": self.elapsed_s,
        }


# name the module of the named tuple's generated __new__, so that pdoc resolves its annotations
CycleRecord.__new__.__module__ = __name__


@dataclass(frozen=True)
class RunResult:
    """How a controller run ended: its :class:`RunStatus` and ``reason``, the cycles run (in all
    and per stage entered), the stages completed in order, the final stage, every cycle record
    (``trace``, empty without ``keep_trace``) and the seconds it took."""

    status: RunStatus
    reason: str
    cycles: int
    cycles_per_stage: dict[str, int]
    stages_completed: tuple[str, ...]
    final_stage: str
    trace: tuple[CycleRecord, ...] = field(default=(), repr=False)
    wall_time_s: float = 0.0

    @property
    def ok(self) -> bool:
        """True when the run completed (all stages, or finished successfully)."""
        return self.status is RunStatus.COMPLETED

    def agents_run(self) -> list[str]:
        """Names of the chosen agents, cycle by cycle."""
        return [r.chosen for r in self.trace if r.chosen is not None]

    def to_dict(self, include_trace: bool = False) -> dict[str, Any]:
        """JSON-friendly form (the trace only when asked)."""
        out: dict[str, Any] = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "trace"}
        out["status"] = self.status.value
        out["cycles_per_stage"] = dict(self.cycles_per_stage)
        out["stages_completed"] = list(self.stages_completed)
        if include_trace:
            out["trace"] = [r.to_dict() for r in self.trace]
        return out


def to_jsonable(value: Any) -> Any:
    """A board value as strict JSON accepts it (dataclasses, enums, mappings, sequences, anything
    with ``tolist()``; non-finite floats become ``None``), without importing NumPy."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Enum):
        return to_jsonable(value.value)
    if hasattr(value, "to_dict"):
        return to_jsonable(value.to_dict())
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_jsonable(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if hasattr(value, "tolist"):
        return to_jsonable(value.tolist())
    if isinstance(value, (list, tuple, set, frozenset)):
        return [to_jsonable(v) for v in value]
    return repr(value)
