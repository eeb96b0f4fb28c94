"""One attempt of a plan: its query to one instance, its goal's messages (subscribed before the
query), its outcome; replies, end and ``lost`` notices come into one queue the caller drains.
"""

from __future__ import annotations

import functools
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import zenoh

from eos_svc.errors import EosError
from eos_svc.service import protocol as proto
from eos_svc.service.instances import LiveInstances
from eos_svc.service.session import direct_callback
from eos_svc.service.wire_json import loads_message

_JSON = zenoh.Encoding.APPLICATION_JSON
NO_CONSOLIDATION = zenoh.ConsolidationMode.NONE

#: called with every cycle message ``{"schema", "goal_id", "instance", "seq", "record"}``
CycleHandler = Callable[[dict[str, Any]], None]


@dataclass
class PlanOutcome:
    """What a plan request returned.

    Attributes:
        goal_id: the request's goal id.
        instance: the instance that answered.
        result: the plan result (``status``, ``reason``, ``cycles``, ``seed``, ...).
        cycles: the cycle messages of the answering attempt, in order (empty when not watched).
        final_status: the goal's ``done`` status message: the reply, which is the message the
            goal's status key carries (``None`` when not watched).
        attempts: instances asked (1 when the first answered).
        gaps: sequence numbers found missing or out of order in the cycle stream (should be empty).
        round_trip_s: seconds from the first request to the answer.
    """

    goal_id: str
    instance: str
    result: dict[str, Any]
    cycles: list[dict[str, Any]] = field(default_factory=list)
    final_status: dict[str, Any] | None = None
    attempts: int = 1
    gaps: list[int] = field(default_factory=list)
    round_trip_s: float = 0.0

    @property
    def status(self) -> str:
        """The plan's status (``success``, ``cancelled``, ...)."""
        return str(self.result.get("status"))

    @property
    def complete(self) -> bool:
        """Whether the cycle stream was received whole: seq 1..n, no gap, n = cycles published."""
        n = self.result.get("cycles_published", self.result.get("cycles"))
        return (
            not self.gaps
            and self.final_status is not None
            and [c["seq"] for c in self.cycles] == list(range(1, (n or 0) + 1))
        )


#: put in an attempt's queue when its query ends (every reply came, or the timeout passed)
_END = object()


class InstanceLostError(EosError):
    """The instance answering an attempt was lost (liveliness token gone); try another."""


def _zenoh_timeout(err: zenoh.ReplyError) -> bool:
    """Whether an error reply is Zenoh's own for a query that timed out (the payload
    ``Timeout``, not JSON: the service's error replies are JSON)."""
    return err.encoding != _JSON and err.payload.to_bytes() == b"Timeout"


class NoReplyInTimeError(InstanceLostError):
    """The instance asked gave no reply before the query's timeout: it may still be running or
    queueing the goal, so this call does not ask it again (it would refuse the goal id as a
    duplicate)."""


class _Stream:
    """The cycle messages of one attempt, in arrival order, and the sequence numbers found missing."""

    __slots__ = ("cycles", "gaps", "iid", "lock")

    def __init__(self, iid: str) -> None:
        self.iid = iid
        self.cycles: list[dict[str, Any]] = []
        self.gaps: list[int] = []
        self.lock = threading.Lock()

    def accept(self, payload: bytes) -> dict[str, Any] | None:
        """Parse a cycle or status message of this attempt's instance; record a cycle. None: not ours."""
        try:
            msg = loads_message(payload)
        except (ValueError, RecursionError):
            return None
        if not isinstance(msg, dict) or msg.get("instance") != self.iid:
            return None  # an earlier attempt's instance: ignore
        if "seq" in msg:
            with self.lock:
                expected = len(self.cycles) + 1
                if msg["seq"] != expected:
                    self.gaps.append(expected)
                self.cycles.append(msg)
        return msg

    def on_sample(self, sample: zenoh.Sample) -> None:
        """Zenoh callback without ``on_cycle``: cycles kept in Zenoh's thread (never blocks)."""
        self.accept(sample.payload.to_bytes())


@dataclass
class Attempt:
    """One plan query (``payload``, timeout in s) for goal ``goal_id`` to instance ``iid``; with
    ``watch``, its goal's messages subscribed to and ``on_cycle`` run in the calling thread."""

    session: zenoh.Session
    prefix: str
    iid: str
    goal_id: str
    payload: bytes
    on_cycle: CycleHandler | None
    watch: bool
    timeout: float

    def run(self, instances: LiveInstances) -> PlanOutcome:
        """Send the query and wait for its outcome.

        Raises:
            RequestError: the instance refused the request.
            InstanceLostError: the instance was lost (or gave no reply in time): try another.
        """
        events: queue.SimpleQueue[Any] = queue.SimpleQueue()
        handler = direct_callback(events.put, functools.partial(events.put, _END))
        cancellation = zenoh.CancellationToken()
        stream = _Stream(self.iid) if self.watch else None
        sub = None
        wid = -1
        try:
            if stream is not None:
                on_sample = stream.on_sample if self.on_cycle is None else lambda s: events.put(("sample", s))
                sub = self.session.declare_subscriber(
                    proto.goal_keys(self.prefix, self.goal_id), direct_callback(on_sample)
                )
            self.session.get(
                proto.plan_key(self.prefix, self.iid),
                handler,
                payload=self.payload,
                encoding=_JSON,
                consolidation=NO_CONSOLIDATION,
                timeout=self.timeout,
                cancellation_token=cancellation,
            )
            # tracked while the query travels (off its path): a token withdrawn before this
            # goes unseen here, but the query then ends without a reply — lost all the same
            wid = instances.track(self.iid, events)
            return self._collect(events, stream)
        except InstanceLostError:
            cancellation.cancel()
            raise
        finally:
            if sub is not None:
                sub.undeclare()
            if wid >= 0:
                instances.untrack(wid)

    def _collect(self, events: queue.SimpleQueue[Any], stream: _Stream | None) -> PlanOutcome:
        """Wait for the reply (the goal's ``done`` status) or an error reply, running ``on_cycle``
        for every cycle that comes before it (the cycles travel ahead of the reply on the link)."""
        end_at = time.monotonic() + self.timeout + 1.0
        while True:
            try:
                event = events.get(timeout=max(0.0, end_at - time.monotonic()))
            except queue.Empty:
                raise InstanceLostError("no reply before the timeout") from None
            if event is _END:
                raise InstanceLostError("query ended without a reply (instance gone or timed out)")
            kind, item = event if type(event) is tuple else ("reply", event)
            if kind == "lost":
                raise InstanceLostError("liveliness token withdrawn")
            if kind == "sample" and stream is not None:  # with on_cycle: parsed in the thread of plan()
                msg = stream.accept(item.payload.to_bytes())
                if msg is not None and "seq" in msg and self.on_cycle is not None:
                    self.on_cycle(msg)
            elif kind == "reply":
                ok = item.ok  # read once: every read makes a new Sample object in Zenoh's binding
                if ok is not None:
                    return self._outcome(loads_message(ok.payload.to_bytes()), stream)
                if _zenoh_timeout(item.err):  # Zenoh's, not the instance's: it never answered
                    raise NoReplyInTimeError(f"no reply within the query's timeout ({self.timeout:g} s)")
                raise proto.error_from_payload(item.err.payload.to_bytes())

    def _outcome(self, reply: dict[str, Any], stream: _Stream | None) -> PlanOutcome:
        cycles: list[dict[str, Any]] = []
        gaps: list[int] = []
        if stream is not None:
            with stream.lock:  # copies: Zenoh's thread may still append until the subscriber is undeclared
                cycles, gaps = list(stream.cycles), list(stream.gaps)
        return PlanOutcome(
            goal_id=self.goal_id,
            instance=str(reply.get("instance", self.iid)),
            result=reply.get("result", {}),
            cycles=cycles,
            final_status=reply if self.watch else None,
            gaps=gaps,
        )
