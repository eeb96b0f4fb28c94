"""Python client of the EOS planning service.

::

    with EosClient.open(make_config(connect=["tcp/127.0.0.1:7447"])) as client:
        client.wait_for_instances(1)
        outcome = client.plan(PlanRequest(), on_cycle=lambda msg: print(msg["seq"]))
        print(outcome.result["status"])

The client keeps the live set of service instances from their liveliness
tokens, sends each plan to one instance by its own key (spreading plans over
instances: the one with the fewest plans in flight from this client, ties in
turn), watches the goal's cycle stream, and retries on another instance when
the one it asked disappears (its token goes, or the query ends without a
reply) or is busy. Zenoh callbacks only enqueue; the user's ``on_cycle`` runs
in the thread that called :meth:`EosClient.plan`.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import queue
import secrets
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import zenoh

from eos_svc.errors import EosError
from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.session import direct_callback

_JSON = zenoh.Encoding.APPLICATION_JSON
_NO_CONSOLIDATION = zenoh.ConsolidationMode.NONE

#: called with every cycle message ``{"schema", "goal_id", "instance", "seq", "record"}``
CycleHandler = Callable[[dict[str, Any]], None]


class ServiceUnavailableError(EosError):
    """No service instance answered the plan (none found, or every attempt lost its instance)."""


@dataclass
class PlanOutcome:
    """What a plan request returned.

    Attributes:
        goal_id: the request's goal id.
        instance: the instance that answered.
        result: the plan result (``status``, ``reason``, ``cycles``, ``seed``, ...).
        cycles: the cycle messages of the answering attempt, in order (empty when not watched).
        final_status: the goal's final ``done`` status message (``None`` when not watched or lost).
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


class _LostError(EosError):
    """The instance answering an attempt was lost (liveliness token gone); try another."""


def _zenoh_timeout(err: zenoh.ReplyError) -> bool:
    """Whether an error reply is Zenoh's own for a query that timed out (the payload
    ``Timeout``, not JSON: the service's error replies are JSON)."""
    return err.encoding != _JSON and err.payload.to_bytes() == b"Timeout"


class _TimedOutError(_LostError):
    """The instance asked gave no reply before the query's timeout: it may still be running or
    queueing the goal, so this call does not ask it again (it would refuse the goal id as a
    duplicate)."""


#: spare waiters a client keeps (about the threads that plan through it at once)
_SPARE_WAITERS = 8


class _Waiter:
    """What one attempt waits on: the queue Zenoh puts the query's replies and then ``_END``
    into (and this client its ``lost`` notices), the query's Zenoh handler, and its cancellation
    token. Once its query has ended (``_END`` taken from the queue) a waiter serves the client's
    next attempt as it is: building these per request costs ≈ 0.1 ms in a process that has idled
    (Zenoh objects, a queue, a partial), taking a spare one a few µs."""

    __slots__ = ("events", "handler", "token")

    def __init__(self) -> None:
        self.events: queue.SimpleQueue[Any] = queue.SimpleQueue()
        # the reply itself goes in the queue (no Python frame between Zenoh and the queue)
        self.handler = direct_callback(self.events.put, functools.partial(self.events.put, _END))
        self.token = zenoh.CancellationToken()

    def ended(self) -> bool:
        """Whether the query has ended (``_END`` was put): the queue is then emptied (stale
        items, e.g. a ``lost`` notice that came after the reply, dropped) and nothing more will
        come into it; if not, the items drained meanwhile were stale too."""
        events = self.events
        ended = False
        while events.qsize():
            ended = events.get_nowait() is _END or ended
        return ended


class _Stream:
    """The cycle messages of one attempt, in arrival order, and the sequence numbers found missing."""

    __slots__ = ("cycles", "events", "gaps", "iid", "lock")

    def __init__(self, iid: str, events: queue.SimpleQueue[Any]) -> None:
        self.iid = iid
        self.events = events
        self.cycles: list[dict[str, Any]] = []
        self.gaps: list[int] = []
        self.lock = threading.Lock()

    def accept(self, payload: bytes) -> dict[str, Any] | None:
        """Parse a cycle or status message of this attempt's instance; record a cycle. None: not ours."""
        try:
            msg = proto.loads_message(payload)
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
        """Zenoh callback when there is no ``on_cycle``: cycles are parsed and kept right here, in
        Zenoh's thread (pure Python, never blocks), so the waiting thread is woken only for the
        final status, not once per cycle."""
        msg = self.accept(sample.payload.to_bytes())
        if msg is not None and "seq" not in msg and msg.get("state") == proto.STATE_DONE:
            self.events.put(("final", msg))


class EosClient:
    """Client of the EOS planning service on an open Zenoh session.

    Args:
        session: an open Zenoh session (closed by :meth:`close` only if
            the client opened it, see :meth:`open`).
        namespace: the service's namespace, if any.
        timeout_margin_s: added to the request's deadline to time out a plan query (s).
        status_grace_s: how long to wait for the final status message after the reply (s).
    """

    def __init__(
        self,
        session: zenoh.Session,
        *,
        namespace: str | None = None,
        timeout_margin_s: float = 10.0,
        status_grace_s: float = 2.0,
    ) -> None:
        self.session = session
        self.prefix = proto.prefix(namespace)
        self.timeout_margin_s = timeout_margin_s
        self.status_grace_s = status_grace_s
        self._lock = threading.Lock()
        self._live: set[str] = set()
        self._inflight: dict[str, int] = {}
        self._waiters: dict[int, tuple[str, queue.SimpleQueue[Any]]] = {}
        self._waiter_ids = itertools.count()
        # default goal ids: a random prefix per client and a counter (no random bytes per plan)
        self._goal_prefix = f"g-{secrets.token_hex(6)}-"
        self._goal_numbers = itertools.count(1)
        self._turn = itertools.count()
        self._owns_session = False
        self._tokens: dict[str, str] = {}  # goal id -> cancel token, while the plan is in flight
        self._plan_keys: dict[str, zenoh.KeyExpr] = {}
        #: waiters of attempts without a stream, kept for later attempts (see _Waiter)
        self._spare_waiters: list[_Waiter] = []
        #: whether watch() was called: this session may hold goal subscribers of its own, so its
        #: plans do not tell the service whether they are watched (it asks Zenoh; see plan())
        self._watching = False
        self._live_changed = threading.Condition(self._lock)
        self._token_sub = session.liveliness().declare_subscriber(
            proto.instance_key(self.prefix), direct_callback(self._on_token), history=True
        )

    @classmethod
    def open(cls, config: zenoh.Config, **kwargs: Any) -> EosClient:
        """Open a session from ``config`` and a client that owns it."""
        client = cls(zenoh.open(config), **kwargs)
        client._owns_session = True
        return client

    def close(self) -> None:
        """Undeclare the liveliness subscriber (and close the session if owned)."""
        with contextlib.suppress(Exception):  # already gone with a closed session
            self._token_sub.undeclare()
        if self._owns_session:
            self.session.close()

    def __enter__(self) -> EosClient:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ discovery
    def _on_token(self, sample: zenoh.Sample) -> None:
        iid = str(sample.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._live.add(iid)
            else:
                self._live.discard(iid)
                for inst, q in self._waiters.values():
                    if inst == iid:
                        q.put(("lost", iid))
            self._live_changed.notify_all()

    def instances(self) -> list[str]:
        """Instances whose liveliness token is alive now (sorted)."""
        with self._lock:
            return sorted(self._live)

    def discover(self, timeout: float = 1.0) -> list[str]:
        """The instances alive now (sorted): the answers to a liveliness query on their tokens,
        together with the tokens this client's liveliness subscriber holds.

        Both, because through a router on a loaded machine Zenoh (1.x) now and then answers a
        liveliness query with nothing, once or for a while, while the tokens are alive and the
        subscriber has them (here, with a busy loop on one of two cores: the first query after
        connecting, 3 trials in 20). With neither holding any token, this waits for the
        subscriber up to ``timeout`` seconds.
        """
        end = time.monotonic() + timeout
        found = set()
        for reply in self.session.liveliness().get(proto.instance_key(self.prefix), timeout=timeout):
            if reply.ok is not None:
                found.add(str(reply.ok.key_expr).rsplit("/", 1)[-1])
        with self._live_changed:
            self._live |= found
            while not self._live and (left := end - time.monotonic()) > 0:
                self._live_changed.wait(left)
            return sorted(self._live)

    def wait_for_instances(self, n: int = 1, timeout: float = 5.0) -> list[str]:
        """Block until at least ``n`` instances are alive; returns them (raises ServiceUnavailableError)."""
        end = time.monotonic() + timeout
        with self._live_changed:
            while len(self._live) < n:
                left = end - time.monotonic()
                if left <= 0:
                    raise ServiceUnavailableError(
                        f"{len(self._live)} instance(s) alive after {timeout} s, wanted {n}"
                    )
                self._live_changed.wait(left)
            return sorted(self._live)

    def _plan_key(self, iid: str) -> zenoh.KeyExpr:
        """The plan key of an instance, parsed by Zenoh once (kept for the instances seen)."""
        key = self._plan_keys.get(iid)
        if key is None:
            key = zenoh.KeyExpr(proto.plan_key(self.prefix, iid))
            if len(self._plan_keys) < 1024:  # bounded: instance ids come from the network
                self._plan_keys[iid] = key
        return key

    def _choose(self, exclude: set[str]) -> str | None:
        with self._lock:
            if len(self._live) == 1 and not exclude:  # one instance: no choice to make
                return next(iter(self._live))
            candidates = sorted(self._live - exclude)
            if not candidates:
                return None
            turn = next(self._turn)
            rotated = candidates[turn % len(candidates) :] + candidates[: turn % len(candidates)]
            return min(rotated, key=lambda i: self._inflight.get(i, 0))

    # ------------------------------------------------------------------ plan
    def plan(
        self,
        request: PlanRequest | Mapping[str, Any] | None = None,
        *,
        goal_id: str | None = None,
        on_cycle: CycleHandler | None = None,
        instance: str | None = None,
        watch: bool = True,
        timeout: float | None = None,
        max_attempts: int = 3,
        cancel_token: str | None = None,
    ) -> PlanOutcome:
        """Request one plan and wait for its result.

        Args:
            request: the plan request (default: ``PlanRequest()``); a mapping is sent as is.
            goal_id: the goal id (default: ``g-<random hex of this client>-<n>``, n = 1, 2, ...).
            on_cycle: called with every cycle message, in order, in this thread.
            instance: ask this instance only (no spreading, no retry elsewhere).
            watch: subscribe to the goal's cycles and status (needed for ``on_cycle``). The
                request says so (its ``watch`` hint), so the instance need not ask Zenoh
                whether anyone watches: ``False`` tells it this session has no subscriber of
                the goal — one declared on :attr:`session` directly is counted only once
                Zenoh notifies the instance (a goal may start unseen by it). Once this client
                has called :meth:`watch` (for good: it does not know when that subscriber
                goes), its requests leave the hint out and the instance asks.
            timeout: seconds to wait for one instance's answer (default: the
                request's deadline + ``timeout_margin_s``). An instance that does not answer
                in time is not asked again by this call; the plan goes to another, so the
                whole call may wait up to ``max_attempts × timeout`` (and the instance given up
                may still be running the plan).
            max_attempts: instances to try before giving up.
            cancel_token: the goal's secret for :meth:`cancel` (default: a fresh random one,
                kept by this client while the plan runs; never published by the service).

        Raises:
            RequestError: the service refused the request (code, field, reason).
            ServiceUnavailableError: no instance answered.
        """
        req = PlanRequest() if request is None else request
        if goal_id is None:
            goal_id = f"{self._goal_prefix}{next(self._goal_numbers)}"
        else:
            proto.check_id(goal_id, "goal_id")
        if instance is not None:
            proto.check_id(instance, "instance")  # one instance, never a wildcard
        if cancel_token is None:
            cancel_token = proto.new_cancel_token()
        elif not proto.is_token(cancel_token):
            raise proto.RequestError(
                proto.E_INVALID, "cancel_token", "must be 16-128 characters of A-Z a-z 0-9 _ -"
            )
        payload = proto.encode_request(goal_id, req, cancel_token, None if self._watching else watch)
        self._tokens[goal_id] = cancel_token  # one dict store or pop: atomic, no lock needed
        try:
            return self._plan(goal_id, req, payload, on_cycle, instance, watch, timeout, max_attempts)
        finally:
            self._tokens.pop(goal_id, None)

    def _plan(
        self,
        goal_id: str,
        req: PlanRequest | Mapping[str, Any],
        payload: bytes,
        on_cycle: CycleHandler | None,
        instance: str | None,
        watch: bool,
        timeout: float | None,
        max_attempts: int,
    ) -> PlanOutcome:
        if timeout is None:
            deadline = req.deadline_s if isinstance(req, PlanRequest) else req.get("deadline_s", 10.0)
            timeout = (deadline if isinstance(deadline, (int, float)) else 60.0) + self.timeout_margin_s
        t0 = time.monotonic()
        exclude: set[str] = set()  # tried in this round
        timed_out: set[str] = set()  # never asked again in this call (see _TimedOutError)
        last_error: str = "no service instance found"
        for attempt in range(1, max_attempts + 1):
            iid = instance or self._choose(exclude | timed_out)
            if iid is None:
                self.discover(timeout=0.5)
                iid = self._choose(exclude | timed_out)
                if iid is None and exclude:  # every instance tried: start over after a pause
                    time.sleep(0.05 * attempt)
                    exclude.clear()
                    iid = self._choose(timed_out)
            if iid is None:
                raise ServiceUnavailableError(last_error)
            try:
                outcome = self._attempt(iid, goal_id, payload, on_cycle, watch, timeout)
            except _LostError as lost:
                last_error = f"instance {iid}: {lost}"
                (timed_out if isinstance(lost, _TimedOutError) else exclude).add(iid)
                if instance is not None:
                    break
                continue
            except proto.RequestError as err:
                if (
                    err.code in (proto.E_BUSY, proto.E_UNAVAILABLE)
                    and instance is None
                    and attempt < max_attempts
                ):
                    last_error = str(err)
                    exclude.add(iid)
                    continue
                raise
            outcome.attempts = attempt
            outcome.round_trip_s = time.monotonic() - t0
            return outcome
        raise ServiceUnavailableError(
            f"goal {goal_id}: no answer after {max_attempts} attempt(s); last: {last_error}"
        )

    def _attempt(
        self,
        iid: str,
        goal_id: str,
        payload: bytes,
        on_cycle: CycleHandler | None,
        watch: bool,
        timeout: float,
    ) -> PlanOutcome:
        waiter = self._waiter() if not watch else _Waiter()
        events = waiter.events
        wid = -1
        sub = None
        stream = _Stream(iid, events) if watch else None
        issued = lost = False
        try:
            if stream is not None:
                sub = self.session.declare_subscriber(
                    proto.goal_keys(self.prefix, goal_id),
                    direct_callback(
                        stream.on_sample if on_cycle is None else lambda s: events.put(("sample", s))
                    ),
                )
            self.session.get(
                self._plan_key(iid),
                waiter.handler,
                payload=payload,
                encoding=_JSON,
                consolidation=_NO_CONSOLIDATION,
                timeout=timeout,
                cancellation_token=waiter.token,
            )
            issued = True  # Zenoh has the handler: its _END will come
            # registered while the query travels (off its path): a token withdrawn before this
            # goes unseen here, but the query then ends without a reply — lost all the same
            wid = next(self._waiter_ids)
            with self._lock:
                self._waiters[wid] = (iid, events)
                self._inflight[iid] = self._inflight.get(iid, 0) + 1
            return self._collect(iid, goal_id, events, stream, on_cycle, watch, timeout)
        except _LostError:
            lost = True
            waiter.token.cancel()
            raise
        finally:
            if sub is not None:
                sub.undeclare()
            if wid >= 0:
                with self._lock:
                    self._waiters.pop(wid, None)
                    self._inflight[iid] -= 1
            # issued (its _END will come), no stream (no subscriber put into its queue) and not
            # cancelled: spare for later
            if issued and not watch and not lost and len(self._spare_waiters) < _SPARE_WAITERS:
                self._spare_waiters.append(waiter)

    def _waiter(self) -> _Waiter:
        """A spare waiter whose query has ended, or a new one (``list.pop``/``append`` are
        atomic: threads planning through this client at once never share one)."""
        spare = self._spare_waiters
        for _ in range(len(spare)):
            try:
                waiter = spare.pop(0)
            except IndexError:
                break
            if waiter.ended():
                return waiter
            spare.append(waiter)  # its query is still ending (its _END is yet to come)
        return _Waiter()

    def _collect(
        self,
        iid: str,
        goal_id: str,
        events: queue.SimpleQueue[Any],
        stream: _Stream | None,
        on_cycle: CycleHandler | None,
        watch: bool,
        timeout: float,
    ) -> PlanOutcome:
        final: dict[str, Any] | None = None
        reply: dict[str, Any] | None = None
        error: proto.RequestError | None = None
        ended = False
        end_at = time.monotonic() + timeout + 1.0
        grace_at: float | None = None
        while True:
            if (reply is not None or error is not None) and (
                not watch or final is not None or error is not None
            ):
                break
            now = time.monotonic()
            limit = grace_at if grace_at is not None else end_at
            if now >= limit:
                break
            try:
                event = events.get(timeout=limit - now)
            except queue.Empty:
                break
            if type(event) is tuple:
                kind, item = event
            elif event is _END:
                kind, item = "end", None
            else:  # a zenoh.Reply
                kind, item = "reply", event
            if kind == "sample" and stream is not None:  # with on_cycle: parsed in the thread of plan()
                msg = stream.accept(item.payload.to_bytes())
                if msg is None:
                    continue
                if "seq" in msg:
                    if on_cycle is not None:
                        on_cycle(msg)
                elif msg.get("state") == proto.STATE_DONE:
                    final = msg
            elif kind == "final":
                final = item
            elif kind == "reply":
                ok = item.ok  # read once: every read makes a new Sample object in Zenoh's binding
                if ok is not None:
                    reply = proto.loads_message(ok.payload.to_bytes())
                elif _zenoh_timeout(item.err):  # Zenoh's, not the instance's
                    if reply is None and error is None:  # it never answered: try another
                        raise _TimedOutError(f"no reply within the query's timeout ({timeout:g} s)")
                    continue  # the answer came; the query timed out waiting for its end
                else:
                    error = proto.error_from_payload(item.err.payload.to_bytes())
                grace_at = time.monotonic() + self.status_grace_s
            elif kind == "end":
                ended = True
                if reply is None and error is None:
                    raise _LostError("query ended without a reply (instance gone or timed out)")
            elif kind == "lost" and reply is None and error is None:
                raise _LostError("liveliness token withdrawn")
        if error is not None:
            raise error
        if reply is None:
            raise _LostError("no reply before the timeout" if not ended else "no reply")
        result = reply.get("result", {})
        cycles: list[dict[str, Any]] = []
        gaps: list[int] = []
        if stream is not None:
            with stream.lock:  # copies: Zenoh's thread may still append until the subscriber is undeclared
                cycles, gaps = list(stream.cycles), list(stream.gaps)
        return PlanOutcome(
            goal_id=goal_id,
            instance=str(reply.get("instance", iid)),
            result=result,
            cycles=cycles,
            final_status=final,
            gaps=gaps,
        )

    # ------------------------------------------------------------------ cancel / watch
    def cancel(self, goal_id: str, timeout: float = 2.0, *, cancel_token: str | None = None) -> bool:
        """Cancel a queued or running goal on whichever instance has it; True when one had it.

        Only the goal's owner can: the cancel carries the goal's ``cancel_token`` (default: the
        one this client sent with the plan, while it runs).

        Raises:
            RequestError: ``forbidden`` — the instance running the goal refused the token.
        """
        proto.check_id(goal_id, "goal_id")
        if cancel_token is None:
            with self._lock:
                cancel_token = self._tokens.get(goal_id)
        found = False
        refusal: proto.RequestError | None = None
        for reply in self._cancel_query(goal_id, proto.encode_cancel(cancel_token), timeout):
            if reply.ok is not None:
                try:
                    found = found or bool(proto.loads_message(reply.ok.payload.to_bytes()).get("found"))
                except (ValueError, AttributeError):
                    continue
            elif reply.err is not None:
                refusal = proto.error_from_payload(reply.err.payload.to_bytes())
        if refusal is not None and not found:
            raise refusal
        return found

    def _cancel_query(self, goal_id: str, payload: bytes | None, timeout: float) -> Any:
        """A query on ``P/cancel/<goal_id>`` that every live instance answers (target ``ALL``, no
        consolidation): its replies, as Zenoh hands them (``timeout`` in seconds)."""
        return self.session.get(
            proto.cancel_key(self.prefix, goal_id),
            payload=payload,
            target=zenoh.QueryTarget.ALL,
            consolidation=_NO_CONSOLIDATION,
            timeout=timeout,
        )

    def watch(
        self,
        callback: Callable[[str, dict[str, Any]], None],
        goal_id: str = "*",
        *,
        sync_timeout: float | None = 2.0,
    ) -> Any:
        """Subscribe to cycle and status messages (of every goal by default).

        ``callback(kind, message)`` runs in a Zenoh callback thread with ``kind``
        ``"cycle"`` or ``"status"``; keep it short. Returns the subscriber
        (``undeclare()`` it to stop).

        A subscriber's declaration travels to each instance on its own, unacknowledged: a
        plan another client sends right after could start on an instance that does not know
        the watcher yet, and that goal's first messages (its ``running`` status) would be
        missed. So unless ``sync_timeout`` is ``None`` this returns only after a round trip
        to every live instance (see :meth:`sync_with_instances`), at most ``sync_timeout``
        seconds: from then on every goal they start is seen from its first message.
        """

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                msg = proto.loads_message(sample.payload.to_bytes())
            except (ValueError, RecursionError):
                return
            kind = "cycle" if str(sample.key_expr).endswith("/cycle") else "status"
            callback(kind, msg)

        self._watching = True  # before the subscriber: from now on plan() leaves its hint out
        subscriber = self.session.declare_subscriber(
            proto.goal_keys(self.prefix, goal_id), direct_callback(on_sample)
        )
        if sync_timeout is not None:
            self.sync_with_instances(sync_timeout)
        return subscriber

    def sync_with_instances(self, timeout: float = 2.0) -> list[str]:
        """Make a round trip to every live instance; return the instances that answered (sorted).

        Zenoh delivers one session's messages to a peer in the order they were sent, so an
        instance that answers has already received everything this session declared before
        the call (subscribers above all). The round trip is a cancel query for a goal id no
        client uses: each instance answers ``found: false`` and nothing else happens.
        """
        answered: set[str] = set()
        for reply in self._cancel_query(f"sync-{secrets.token_hex(8)}", None, timeout):
            if reply.ok is not None:
                try:
                    answered.add(str(proto.loads_message(reply.ok.payload.to_bytes())["instance"]))
                except (ValueError, KeyError, TypeError):
                    continue
        return sorted(answered)
