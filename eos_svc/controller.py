"""The EOS controller (paper §2.1, §3, §5): rate, choose, act, record — every cycle.

Each cycle it rates the agents allowed in the stage, chooses the highest total
P(A_j) = Σ_i P(A_j|B_i)·P(B_i) (ties: the agent listed first), runs its action on the board and
records the cycle. Its rules, explained in ``docs/planner.md``:

1. Opportunistic sub-ratings reset every cycle; the previous action's and each agent's own test
   apply (the larger counts).
2. An agent that acted in the stage is eligible again only while its opportunistic and learned
   part is positive (:class:`RepeatPolicy`).
3. ``CANNOT_ACT`` or nobody eligible stalls; ``STAGE_COMPLETE`` moves on; ``FINISHED`` ends; an
   exception ends the run with ``error``.
4. With ``check_access`` each agent sees only its declared entries.
5. An :class:`~eos_svc.errors.AgentUnavailableError` skips the agent for that cycle.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from enum import Enum
from typing import Any

from eos_svc.agent import ActionResult, Agent, CycleContext, Outcome
from eos_svc.board import Board
from eos_svc.board_access import EntryCheck, clients_for
from eos_svc.errors import AgentUnavailableError, ContractError, ValidationError
from eos_svc.ratings import Weights, check_probability
from eos_svc.records import REPEAT_SKIP, AgentRating, CycleRecord, RunResult, RunStatus

CycleCallback = Callable[[CycleRecord], None]


class RepeatPolicy(str, Enum):
    """Which agents may be chosen again within a stage (see module docstring, rule 2)."""

    ONCE_UNLESS_ASKED = "once_unless_asked"
    ALWAYS = "always"


class CancelToken:
    """A thread-safe flag to cancel a running plan from another thread."""

    __slots__ = ("_event", "reason")

    def __init__(self) -> None:
        self._event = threading.Event()
        self.reason = "cancelled"

    def cancel(self, reason: str = "cancelled") -> None:
        """Ask the run to stop before its next cycle."""
        self.reason = reason
        self._event.set()

    @property
    def cancelled(self) -> bool:
        """Whether :meth:`cancel` was called."""
        return self._event.is_set()


class Controller:
    """Runs agents over stages until the run ends.

    Args:
        agents, stages: the agents (their order breaks ties) and the stages, in order.
        weights: weights of the sub-ratings.
        max_cycles, deadline_s: the cycle limit (≥ 1) and a run's wall-clock budget (s) or ``None``.
        repeat_policy: see :class:`RepeatPolicy`.
        keep_trace, callbacks: keep every cycle record in :attr:`RunResult.trace`; call these with each.
        check_access: debug mode: each agent sees only its declared entries (rule 4).
        entry_check: with ``check_access``, ``entry_check(key, value)`` validates every write.

    Raises:
        ValidationError: naming the argument at fault (duplicate agents, unknown stages, …).
    """

    def __init__(
        self,
        agents: Sequence[Agent],
        stages: Sequence[str],
        weights: Weights | None = None,
        *,
        max_cycles: int = 1000,
        deadline_s: float | None = None,
        repeat_policy: RepeatPolicy = RepeatPolicy.ONCE_UNLESS_ASKED,
        keep_trace: bool = True,
        callbacks: Iterable[CycleCallback] = (),
        check_access: bool = False,
        entry_check: EntryCheck | None = None,
    ) -> None:
        self.stages: tuple[str, ...] = tuple(stages)
        if not self.stages:
            raise ValidationError("stages", "must name at least one stage")
        if len(set(self.stages)) != len(self.stages):
            raise ValidationError("stages", f"must be unique, got {list(self.stages)}")
        self.agents: tuple[Agent, ...] = tuple(agents)
        names = [a.name for a in self.agents]
        for name in names:
            if names.count(name) > 1:
                raise ValidationError("agents", f"agent name {name!r} is used twice")
        for agent in self.agents:
            unknown = agent.stages - set(self.stages)
            if unknown:
                raise ValidationError(f"agents.{agent.name}.stages", f"unknown stage(s) {sorted(unknown)}")
        self.weights = weights if weights is not None else Weights()
        if not isinstance(self.weights, Weights):
            raise ValidationError("weights", f"must be a Weights, got {type(self.weights).__name__}")
        if isinstance(max_cycles, bool) or not isinstance(max_cycles, int) or max_cycles < 1:
            raise ValidationError("max_cycles", f"must be an integer ≥ 1, got {max_cycles!r}")
        self.max_cycles = max_cycles
        if deadline_s is not None and (
            not isinstance(deadline_s, (int, float)) or not math.isfinite(deadline_s) or deadline_s <= 0
        ):
            raise ValidationError("deadline_s", f"must be a positive number of seconds, got {deadline_s!r}")
        self.deadline_s = deadline_s
        self.repeat_policy = RepeatPolicy(repeat_policy)
        self.keep_trace = keep_trace
        self.callbacks: list[CycleCallback] = list(callbacks)
        if not isinstance(check_access, bool):
            raise ValidationError("check_access", f"must be a bool, got {check_access!r}")
        if entry_check is not None and not check_access:
            raise ValidationError("entry_check", "checks entries only with check_access=True")
        self.check_access = check_access
        self.entry_check = entry_check

    def add_callback(self, callback: CycleCallback) -> None:
        """Register a per-cycle callback (like py_trees' post-tick handlers)."""
        self.callbacks.append(callback)

    def run(self, board: Board | None = None, *, cancel: CancelToken | None = None) -> RunResult:
        """Run cycles on ``board`` (default: a new one) until the run ends, or ``cancel`` stops it;
        never raises for a planning outcome."""
        board = board if board is not None else Board()
        weights = self.weights
        wo, wl = weights.opportunistic, weights.learned
        always = self.repeat_policy is RepeatPolicy.ALWAYS
        stages = self.stages
        max_cycles = self.max_cycles
        clock = time.monotonic
        tables = self._stage_tables(board)
        log = _CycleLog(self.callbacks, self.keep_trace, clock)
        emit = log.emit
        deadline_at = None if self.deadline_s is None else log.t0 + self.deadline_s
        # the run's state; rule 1: what a stage's cycles carry over (events, hints) starts empty
        stage_index, stage, seq = 0, stages[0], 0
        per_stage: dict[str, int] = {stage: 0}
        completed: list[str] = []
        table, stage_cycle, acted, events, hints, last_agent = self._stage_start(tables, stage)

        while True:
            if (
                (cancel is not None and cancel.cancelled)
                or seq >= max_cycles
                or (deadline_at is not None and clock() >= deadline_at)
            ):
                return log.result(*self._limit_end(cancel, seq, stage), seq, per_stage, completed, stage)
            seq += 1
            per_stage[stage] += 1
            ctx = CycleContext(seq, stage, stage_cycle, events, last_agent, acted)

            # --- rate ---------------------------------------------------------
            rows: list[AgentRating] = []
            started = clock()
            best: Agent | None = None
            best_view = board
            best_total = -1.0
            name = ""
            try:
                for (
                    agent,
                    name,
                    default,
                    weighted_default,
                    has_pre,
                    has_learned,
                    learned,
                    view,
                    where,
                ) in table:
                    opp = hints.get(name, 0.0) if hints else 0.0  # rule 1
                    try:
                        if has_pre:
                            own = agent.opportunistic(view, ctx)
                            if own is not None:
                                if own.__class__ is not float or not 0.0 <= own <= 1.0:
                                    own = check_probability(own, f"agents.{name}.opportunistic")
                                if own > opp:
                                    opp = own
                        if has_learned:
                            learned = check_probability(
                                agent.learned_rating(view, ctx), f"agents.{name}.learned"
                            )
                    except AgentUnavailableError as exc:  # rule 5: rated 0, skipped, the reason recorded
                        why = f"unavailable: {exc}"
                        log.unavailable(name, seq, why)
                        now = clock()
                        latency, started = now - started, now
                        rows.append(AgentRating(name, default, 0.0, 0.0, 0.0, False, where, latency, why))
                        continue
                    variable = opp * wo + learned * wl
                    total = weighted_default + variable
                    eligible = always or variable > 0.0 or name not in acted
                    now = clock()  # one clock read per agent: its end is the next one's start
                    latency, started = now - started, now
                    skipped = None if eligible else REPEAT_SKIP
                    rows.append(
                        AgentRating(name, default, opp, learned, total, eligible, where, latency, skipped)
                    )
                    if eligible and total > best_total:
                        best = agent
                        best_total = total
                        best_view = view
            except Exception as exc:
                reason = f"agent {name!r} failed its rating: {type(exc).__name__}: {exc}"
                emit((seq, stage, stage_cycle, tuple(rows), weights, None, None, reason, ()))
                return log.result(RunStatus.ERROR, reason, seq, per_stage, completed, stage)
            if best is None:
                status, reason = _nobody_end(stage, rows)
                broken = emit((seq, stage, stage_cycle, tuple(rows), weights, None, None, reason, ()))
                if broken:
                    status, reason = RunStatus.ERROR, broken
                return log.result(status, reason, seq, per_stage, completed, stage)

            # --- act ----------------------------------------------------------
            name = best.name
            board.begin_cycle()
            try:
                result = best.act(best_view, ctx)
                if not isinstance(result, ActionResult):
                    raise ContractError(
                        f"agents.{name}.act", f"must return an ActionResult, got {type(result).__name__}"
                    )
                new_hints = {  # the opportunistic sub-ratings the action set for others, checked
                    target: check_probability(value, f"agents.{name}.ratings.{target}")
                    for target, value in result.ratings.items()
                }
            except AgentUnavailableError as exc:  # rule 5: the action did not run; the plan carries on
                changes = board.end_cycle()
                detail = f"agent {name!r} unavailable: {exc}; its action did not run"
                log.unavailable(name, seq, f"unavailable: {exc}")
                broken = emit((seq, stage, stage_cycle, tuple(rows), weights, name, None, detail, changes))
                if broken:
                    return log.result(RunStatus.ERROR, broken, seq, per_stage, completed, stage)
                continue
            except Exception as exc:
                changes = board.end_cycle()
                reason = f"agent {name!r} raised {type(exc).__name__}: {exc}"
                emit((seq, stage, stage_cycle, tuple(rows), weights, name, None, reason, changes))
                return log.result(RunStatus.ERROR, reason, seq, per_stage, completed, stage)
            changes = board.end_cycle()
            acted[name] = acted.get(name, 0) + 1
            outcome = result.outcome
            broken = emit(
                (seq, stage, stage_cycle, tuple(rows), weights, name, outcome, result.detail, changes)
            )
            if broken:
                return log.result(RunStatus.ERROR, broken, seq, per_stage, completed, stage)

            # --- transition ---------------------------------------------------
            if outcome is Outcome.PROGRESS:
                stage_cycle += 1
                events = changes
                hints = new_hints
                last_agent = name
                continue
            if outcome is Outcome.STAGE_COMPLETE and stage_index + 1 < len(stages):
                completed.append(stage)
                stage_index += 1
                stage = stages[stage_index]
                per_stage[stage] = 0
                table, stage_cycle, acted, events, hints, last_agent = self._stage_start(tables, stage)
                continue
            status, reason = _action_end(name, stage, result, completed)
            return log.result(status, reason, seq, per_stage, completed, stage)

    # --- once per run or per stage ----------------------------------------------------
    def _stage_tables(self, board: Board) -> dict[str, tuple[tuple, ...]]:
        """Per stage, its allowed agents in list order, each with what does not change during a
        run: (agent, name, default, weighted default, overrides the precondition test, overrides
        the learned hook (a hook not overridden is not called), learned, the board as the agent
        sees it — the board itself, or its client in debug mode —, where it runs)."""
        wd = self.weights.default
        views: dict[str, Any] = {}
        if self.check_access:
            views = clients_for(board, self.agents, self.entry_check)
        return {
            stage: tuple(
                (
                    a,
                    a.name,
                    a._default,
                    a._default * wd,
                    type(a).opportunistic is not Agent.opportunistic,
                    type(a).learned_rating is not Agent.learned_rating,
                    a._learned,
                    views.get(a.name, board),
                    a.location,
                )
                for a in self.agents
                if stage in a.stages
            )
            for stage in self.stages
        }

    @staticmethod
    def _stage_start(tables: dict[str, tuple[tuple, ...]], stage: str) -> tuple:
        """A stage's first state: its agent table, stage_cycle 0, nobody acted, no events, no
        ratings set by a previous action, no last agent."""
        return tables[stage], 0, {}, (), {}, None

    def _limit_end(self, cancel: CancelToken | None, seq: int, stage: str) -> tuple[RunStatus, str]:
        """Why the run stops before a cycle: cancelled, the cycle limit, or the deadline."""
        if cancel is not None and cancel.cancelled:
            return RunStatus.CANCELLED, cancel.reason
        if seq >= self.max_cycles:
            return RunStatus.CYCLE_LIMIT, f"cycle limit of {self.max_cycles} reached in stage {stage!r}"
        return RunStatus.DEADLINE, f"deadline of {self.deadline_s} s passed in stage {stage!r}"


def _nobody_end(stage: str, rows: list[AgentRating]) -> tuple[RunStatus, str]:
    """The run stalls: no agent is eligible in this cycle (rule 2), or none is allowed."""
    if rows:
        return RunStatus.STALLED, (
            f"no agent may act in stage {stage!r}: every allowed agent has acted and "
            "none is asked for again by its opportunistic or learned sub-rating"
        )
    return RunStatus.STALLED, f"no agent is allowed in stage {stage!r}"


def _action_end(name: str, stage: str, result: ActionResult, completed: list[str]) -> tuple[RunStatus, str]:
    """How the run ends after an action that is neither progress nor a stage change (rule 3);
    appends the stage to ``completed`` when the run leaves it gracefully."""
    outcome = result.outcome
    if outcome is Outcome.CANNOT_ACT:
        detail = f": {result.detail}" if result.detail else ""
        return RunStatus.STALLED, f"agent {name!r} cannot act in stage {stage!r}{detail}"
    if outcome is Outcome.STAGE_COMPLETE:  # the last stage
        completed.append(stage)
        return RunStatus.COMPLETED, f"all stages completed ({', '.join(completed)})"
    if outcome is Outcome.FINISHED:
        completed.append(stage)  # the run exits gracefully from this stage
        status = RunStatus.COMPLETED if result.succeeded else RunStatus.FAILED
        return status, result.detail or f"finished by agent {name!r}"
    return RunStatus.ERROR, f"agent {name!r} returned unknown outcome {outcome!r}"  # pragma: no cover


class _CycleLog:
    """A run's records: builds each cycle's record, keeps the trace, calls the callbacks, and
    makes the final :class:`RunResult`."""

    __slots__ = ("callbacks", "clock", "keep", "missing", "t0", "trace")

    def __init__(self, callbacks: list[CycleCallback], keep: bool, clock: Callable[[], float]) -> None:
        self.callbacks = callbacks
        self.keep = keep
        self.clock = clock
        self.trace: list[CycleRecord] = []
        self.t0 = clock()
        #: per agent that was unavailable: [first cycle, cycles, first reason] (rule 5)
        self.missing: dict[str, list] = {}

    def unavailable(self, name: str, seq: int, why: str) -> None:
        """Note that agent ``name`` was unavailable in cycle ``seq`` (the run's reason says so)."""
        seen = self.missing.get(name)
        if seen is None:
            self.missing[name] = [seq, 1, why]
        else:
            seen[1] += 1

    def emit(self, fields: tuple) -> str | None:
        """Record a cycle; returns an error text if a callback raised."""
        record = CycleRecord._make((*fields, self.clock() - self.t0))
        if self.keep:
            self.trace.append(record)
        for callback in self.callbacks:
            try:
                callback(record)
            except Exception as exc:  # a broken observer must not kill the plan silently
                return f"cycle callback {callback!r} raised {type(exc).__name__}: {exc}"
        return None

    def result(
        self,
        status: RunStatus,
        reason: str,
        cycles: int,
        per_stage: dict[str, int],
        completed: list[str],
        stage: str,
    ) -> RunResult:
        """The run's result (its reason followed by the agents that were unavailable, if any)."""
        for name, (first, count, why) in self.missing.items():
            reason += f"; agent {name!r} was unavailable in {count} cycle(s) from cycle {first} ({why})"
        return RunResult(
            status=status,
            reason=reason,
            cycles=cycles,
            cycles_per_stage=per_stage,
            stages_completed=tuple(completed),
            final_stage=stage,
            trace=tuple(self.trace),
            wall_time_s=self.clock() - self.t0,
        )
