"""The goals one service instance holds: each admitted plan, the bounded table of them, the counters."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field, fields

import zenoh

from eos_svc.controller import CancelToken
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto


@dataclass
class Goal:
    """An admitted plan request, queued or running.

    Attributes:
        query: the plan query, answered exactly once when the goal ends.
        goal_id: the request's goal id.
        request: the decoded, validated request.
        cancel_token: the owner's secret: a cancel must carry it (``None``: nobody can cancel).
        cancel: set by a cancel (or by ``stop()``); read by the planner before every cycle.
        watch: the requester's hint: it subscribed to the goal (see :class:`~.protocol.Envelope`).
    """

    query: zenoh.Query
    goal_id: str
    request: PlanRequest
    cancel_token: str | None = None
    cancel: CancelToken = field(default_factory=CancelToken)
    watch: bool | None = None


@dataclass
class ServiceStats:
    """Counters of one instance (all since start).

    Every query it receives (plan or cancel) is counted in ``received`` and ends in exactly one
    of ``replied_ok``, ``replied_err`` or ``left_to_peers``: once no query is in flight,
    ``received == replied_ok + replied_err + left_to_peers`` (:meth:`consistent`).
    """

    #: queries received: plan and cancel (a watcher's sync is a cancel query)
    received: int = 0
    #: of those, cancel queries
    cancels: int = 0
    #: answered with a reply: a plan's result, a cancel's ``found`` answer
    replied_ok: int = 0
    #: answered with an error reply
    replied_err: int = 0
    #: plan queries on a key naming several instances, answered by another one (dropped here)
    left_to_peers: int = 0
    #: of the error replies, ``busy``
    busy: int = 0
    #: plans that ended ``cancelled``
    cancelled: int = 0
    #: cycles numbered for publication (sent or, with nobody watching, skipped)
    cycles_published: int = 0
    #: cycles actually put on the wire (someone was watching)
    cycles_sent: int = 0

    def __post_init__(self) -> None:
        self._lock = threading.Lock()

    def add(self, **counts: int) -> None:
        """Add to the named counters at once (thread-safe)."""
        with self._lock:
            for name, n in counts.items():
                setattr(self, name, getattr(self, name) + n)

    def consistent(self) -> bool:
        """Whether every query received has ended in exactly one way (when none is in flight)."""
        with self._lock:
            return self.received == self.replied_ok + self.replied_err + self.left_to_peers

    def to_dict(self) -> dict[str, int]:
        """JSON form."""
        with self._lock:
            return {f.name: getattr(self, f.name) for f in fields(self)}


class GoalTable:
    """The goals an instance holds, queued or running: at most ``capacity``, each goal id once.

    Args:
        capacity: goals held at once (the service's ``workers + queue_size``).
        instance: the instance's id (named in a ``busy`` refusal).
    """

    def __init__(self, capacity: int, instance: str) -> None:
        self.capacity = capacity
        self.instance = instance
        self._goals: dict[str, Goal] = {}
        self._lock = threading.Lock()

    def admit(self, goal: Goal) -> proto.RequestError | None:
        """Hold ``goal``, or return why not (``duplicate_goal``, ``busy``)."""
        with self._lock:
            if goal.goal_id in self._goals:
                return proto.RequestError(
                    proto.E_DUPLICATE,
                    "goal_id",
                    f"goal {goal.goal_id!r} is already queued or running",
                    goal.goal_id,
                )
            if len(self._goals) >= self.capacity:
                return proto.RequestError(
                    proto.E_BUSY,
                    "request",
                    f"instance {self.instance} busy: {self.capacity} goals queued or running; "
                    "retry later or on another instance",
                    goal.goal_id,
                )
            self._goals[goal.goal_id] = goal
            return None

    def get(self, goal_id: str) -> Goal | None:
        """The goal held under ``goal_id``, if any."""
        with self._lock:
            return self._goals.get(goal_id)

    def release(self, goal_id: str) -> None:
        """Forget a goal that has ended (its id may be used again)."""
        with self._lock:
            self._goals.pop(goal_id, None)

    def cancel_all(self, reason: str) -> None:
        """Cancel every goal held."""
        with self._lock:
            for goal in self._goals.values():
                goal.cancel.cancel(reason)
