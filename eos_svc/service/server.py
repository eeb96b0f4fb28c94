"""The EOS planning service on Zenoh.

One :class:`PlanService` is one service instance. It declares, under its
prefix ``P`` (see :mod:`eos_svc.service.protocol`):

- a liveliness token ``P/instance/<iid>`` (discovery);
- a queryable ``P/plan/<iid>`` — a plan request in, exactly one reply out
  (the result, or an error reply with a code, the field and the reason); a query
  whose key is not exactly this one (``P/plan/*``) reaches every instance it
  matches: of those, only the first by id answers, with an error naming the keys
  to use (each instance follows the others' liveliness tokens);
- a queryable ``P/cancel/*`` — cancel a queued or running goal by id, with the
  goal's secret ``cancel_token``;

and publishes every cycle of a plan on ``P/goal/<goal_id>/cycle`` and its
status on ``P/goal/<goal_id>/status``, reliably (``CongestionControl.BLOCK``).
A message is built and put only while some subscriber matches ``P/goal/*/*``
(:class:`_GoalWatchers`): Zenoh would drop it unsent otherwise, so a plan
nobody watches costs no encoding and no put; its cycles are numbered all the
same (``cycles_published`` counts them), so a watcher that comes in the middle
of a plan gets the rest of the cycles, numbered from where the plan is.

Threads: the queryables' callbacks run in Zenoh's own thread and never block
nor call Zenoh (see :func:`~eos_svc.service.session.direct_callback`): the plan
callback decodes and validates the request and either queues it for the
``workers`` worker threads that run the planner (at most ``workers +
queue_size`` goals admitted; past that a ``busy`` error) or hands the refusal
to a dispatcher thread, which sends the error reply (it also serves cancel).
Every query on this instance's key ends in exactly one ``reply`` or ``reply_err`` and is
dropped (a wildcard one another instance answers is only dropped).
"""

from __future__ import annotations

import functools
import inspect
import logging
import os
import queue
import secrets
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import zenoh

from eos_svc.controller import CancelToken
from eos_svc.errors import ContractError, ValidationError
from eos_svc.records import CycleRecord
from eos_svc.schema.request import PlanRequest
from eos_svc.schema.result import PlanResult
from eos_svc.service import protocol as proto
from eos_svc.service.session import direct_callback
from eos_svc.shape import kernels

log = logging.getLogger(__name__)

_JSON = zenoh.Encoding.APPLICATION_JSON
_BLOCK = zenoh.CongestionControl.BLOCK

#: the dispatcher's work items: (kind, query, refusal); None stops it
_Item = tuple[str, zenoh.Query | None, proto.RequestError | None]
#: the item that asks the dispatcher to refresh the goal watchers' flag (_GoalWatchers.refresh)
_REFRESH: _Item = ("refresh", None, None)

#: a planner as the service calls it (the signature of ``eos_svc.agents.planner.plan``)
Planner = Callable[..., Any]
#: admission check of a decoded request: raises ValidationError(field, reason) to refuse it
Admission = Callable[[PlanRequest], None]


def default_planner() -> Planner:
    """The grasp planner, imported only when first needed."""
    from eos_svc.agents.planner import plan  # lazy: Pinocchio and coal load here

    return plan


def default_admission() -> Admission:
    """The grasp planner's admission check (:func:`eos_svc.agents.admission.check_plannable` on
    the default hand, resolved once: :func:`~eos_svc.agents.admission.default_check`)."""
    from eos_svc.world.admission import default_check  # lazy: Pinocchio and coal load here

    return default_check()


def _is_grasp_planner(planner: Planner | None) -> bool:
    return planner is None or (
        getattr(planner, "__module__", None) == "eos_svc.agents.planner"
        and getattr(planner, "__name__", "") == "plan"
    )


def _encode(obj: Any) -> bytes:
    """Strict JSON bytes of a result (see :func:`~eos_svc.service.protocol.encode_result`)."""
    return proto.encode_result(obj)


class _CycleSink:
    """Where a goal's cycles go: the first cycle is a plain ``put``; a publisher is declared only
    when a second comes (declaring one costs more than a put, and a 1-cycle plan needs none).
    Same key, encoding and congestion control either way, so the cycles stay in order."""

    __slots__ = ("_goal_id", "_key", "_prefix", "_publisher", "_sent", "_session")

    def __init__(self, session: zenoh.Session, prefix: str, goal_id: str) -> None:
        self._session = session
        self._prefix = prefix
        self._goal_id = goal_id
        self._key = ""  # the goal's cycle key, written when the first cycle is put
        self._publisher: Any = None
        self._sent = False

    def put(self, body: bytes) -> None:
        """Publish one cycle message."""
        if self._publisher is not None:
            self._publisher.put(body)
        elif not self._sent:
            self._key = proto.cycle_key(self._prefix, self._goal_id)
            self._session.put(self._key, body, encoding=_JSON, congestion_control=_BLOCK)
            self._sent = True
        else:
            self._publisher = self._session.declare_publisher(
                self._key, encoding=_JSON, congestion_control=_BLOCK
            )
            self._publisher.put(body)

    def undeclare(self) -> None:
        """Undeclare the publisher, if one was declared."""
        if self._publisher is not None:
            self._publisher.undeclare()


class _GoalWatchers:
    """Whether any subscriber matches ``P/goal/*/*`` (the cycles and status of any goal).

    A publisher declared on that key and never used to put. Two answers:

    - :meth:`now`: its matching status read from Zenoh's routing tables at this moment (the
      tables that would route a put), exact: a client's subscriber declared before it sends
      the plan query reaches the service before the query (in order on the same link), so a
      goal watched from the start gets every message. A few µs warm, tens of µs in a process
      that has been idle (cold caches): asked once per plan whose request does not say
      whether its sender watches, and only when ``any`` is false.
    - :attr:`any`: a Python bool, free to read before every cycle. A matching listener's
      notice that says "matching" sets it at once (a put too many costs little; nothing is
      woken on the request's path); one that says "nobody" asks for :meth:`refresh`
      (``on_notice``: the service's dispatcher thread runs it), which sets it to the routing
      tables' answer. The service also refreshes it after every plan that ends with it set or
      with Zenoh's last notice saying "matching" (after the reply), and before answering every
      cancel query. Readings are taken one at a time (a lock), so an older one never overwrites
      a newer one, and a "matching" notice that comes during a reading makes it read again. So
      the flag turns false only from an exact reading, never from a notice Zenoh delivered late
      or out of order (it delivers them from tasks it spawns); a stale "matching" lasts until
      the first plan that ends after it (plans running meanwhile publish to nobody). It lags a
      new subscriber by the notice's delay (well under a millisecond to a few): enough for a
      watcher that comes in the middle of a plan; a watcher that syncs with the instance
      (:meth:`~eos_svc.service.EosClient.watch`: a cancel query) is counted from then on.
    - :meth:`watched`: the choice at a plan's start, from the request's ``watch`` hint.
    """

    __slots__ = (
        "_listener",
        "_matching_notices",
        "_on_notice",
        "_publisher",
        "_reading",
        "any",
        "zenoh_says_matching",
    )

    def __init__(self, session: zenoh.Session, prefix: str, on_notice: Callable[[], None]) -> None:
        self._publisher = session.declare_publisher(proto.goal_keys(prefix))
        self.any = False
        #: what Zenoh's last notice said: Zenoh notifies only when its own state changes, which
        #: a reading of ours may have left behind; the worker reads the tables while it is true
        self.zenoh_says_matching = False
        self._matching_notices = 0  # changes with every "matching" notice (see refresh)
        self._reading = threading.Lock()  # one reading at a time (see refresh)
        self._on_notice = on_notice
        self._listener = self._publisher.declare_matching_listener(direct_callback(self._on_status))
        self.refresh()  # the watchers already there, exactly, without waiting for a notice

    def _on_status(self, status: Any) -> None:
        # in Zenoh's thread: an attribute store or a queue put; never blocks, never calls Zenoh
        if status.matching:
            self.zenoh_says_matching = True
            self._matching_notices += 1  # the counter first, then the flag (see refresh)
            self.any = True  # believed at once (a put too many costs little), nothing woken
        else:
            self.zenoh_says_matching = False
            self._on_notice()  # "nobody": believed only from the tables, read in another thread

    def watched(self, hint: bool | None) -> bool:
        """Whether to publish a goal's messages from its start: the requester's ``watch`` hint
        (it subscribed, or not: then the watchers known, :attr:`any`), or without one :meth:`now`."""
        if hint is None:
            return self.now()
        return hint or self.any

    def now(self) -> bool:
        """True when at least one subscriber matches some goal's messages now (exact)."""
        return self.any or self._tables_say_matching()

    def _tables_say_matching(self) -> bool:
        """The publisher's matching status, read from Zenoh's routing tables now."""
        status = self._publisher.matching_status  # a MatchingStatus (the 1.x stubs say bool)
        return bool(getattr(status, "matching", status))

    def refresh(self) -> None:
        """Set :attr:`any` to the routing tables' answer now (from our threads, never from
        Zenoh's). One reading at a time: Zenoh releases the GIL while it reads, so without the
        lock a worker's "nobody" could be stored after the dispatcher's newer "matching" (a
        watcher's sync). A "matching" notice that comes while the tables are read makes it read
        them again, so a "nobody" read before that notice never overwrites it."""
        with self._reading:  # never taken in Zenoh's threads: waiting on it cannot block them
            while True:
                mark = self._matching_notices
                matching = self._tables_say_matching()
                self.any = matching
                # stored first, checked after: a notice before the store is seen here, one
                # after it set the flag itself
                if matching or self._matching_notices == mark:
                    return

    def undeclare(self) -> None:
        """Undeclare the listener and the publisher (each tried, whatever the other did)."""
        try:
            self._listener.undeclare()
        finally:
            with self._reading:  # not while a reading uses the publisher
                self._publisher.undeclare()


class _GoalCancel(CancelToken):
    """A goal's :class:`~eos_svc.controller.CancelToken` without its ``threading.Event``: a flag
    set once (an attribute store, atomic under the GIL), read by the controller before every
    cycle. Nothing waits on it, so no Event is needed; building one costs ≈ 9 µs back to back and
    ≈ 0.1 ms in a process that has idled, on every request's path."""

    __slots__ = ("_set",)

    def __init__(self) -> None:  # no super().__init__(): no Event
        self._set = False
        self.reason = "cancelled"

    def cancel(self, reason: str = "cancelled") -> None:
        """Ask the run to stop before its next cycle."""
        self.reason = reason
        self._set = True

    @property
    def cancelled(self) -> bool:
        """Whether :meth:`cancel` was called."""
        return self._set


@dataclass
class _Job:
    query: zenoh.Query
    goal_id: str
    request: PlanRequest
    cancel_token: str | None = None  # the owner's secret: a cancel must carry it
    cancel: CancelToken = field(default_factory=_GoalCancel)
    watch: bool | None = None  # the requester's hint: it subscribed to the goal (see proto.Envelope)


@dataclass
class ServiceStats:
    """Counters of one instance (all since start)."""

    received: int = 0
    replied_ok: int = 0
    replied_err: int = 0
    busy: int = 0
    cancelled: int = 0
    #: cycles numbered for publication (sent or, with nobody watching, skipped)
    cycles_published: int = 0
    #: cycles actually put on the wire (someone was watching)
    cycles_sent: int = 0

    def to_dict(self) -> dict[str, int]:
        """JSON form."""
        return dict(self.__dict__)


class PlanService:
    """A service instance on an open Zenoh session.

    Args:
        session: the Zenoh session to serve on (not closed by :meth:`stop`
            unless the service opened it, see :meth:`open`).
        namespace: optional namespace under the versioned prefix.
        instance: this instance's id (default: ``<pid>-<random hex>``).
        planner: ``plan(request, *, on_cycle, cancel) -> result`` with
            ``result.to_dict()``; default the grasp planner (imported lazily).
        workers: threads running plans concurrently (≥ 1).
        queue_size: accepted plans waiting for a worker before ``busy`` (≥ 0).
        max_request_bytes: largest request payload accepted (bytes).
        admission: called with every decoded request before it is queued; a
            ``ValidationError`` it raises is an ``invalid_request`` reply naming the field.
            Default: :func:`~eos_svc.agents.admission.check_plannable` when the planner is
            the grasp planner, none otherwise.
        plugins: the plug-in agents this instance offers, by the name requests give them
            (``PlanRequest.agents``; see :mod:`eos_svc.service.plugins`); a request naming another
            is refused. Default: none.
    """

    def __init__(
        self,
        session: zenoh.Session,
        *,
        namespace: str | None = None,
        instance: str | None = None,
        planner: Planner | None = None,
        workers: int = 2,
        queue_size: int = 16,
        max_request_bytes: int = proto.MAX_REQUEST_BYTES,
        admission: Admission | None = None,
        plugins: Mapping[str, Any] | None = None,
    ) -> None:
        if workers < 1:
            raise proto.RequestError(proto.E_INVALID, "workers", f"must be ≥ 1, got {workers}")
        if queue_size < 0:
            raise proto.RequestError(proto.E_INVALID, "queue_size", f"must be ≥ 0, got {queue_size}")
        self.session = session
        self.prefix = proto.prefix(namespace)
        self.instance = (
            proto.check_id(instance, "instance") if instance else f"{os.getpid()}-{secrets.token_hex(4)}"
        )
        self._planner = planner
        self._admission: Admission | None = admission
        self._default_admission = admission is None and _is_grasp_planner(planner)
        self.workers = workers
        self.queue_size = queue_size
        self.max_request_bytes = max_request_bytes
        self.stats = ServiceStats()
        self._inbox: queue.SimpleQueue[_Item | None] = queue.SimpleQueue()
        # bounded by admission: at most workers + queue_size goals active (running or waiting)
        self._jobs: queue.SimpleQueue[_Job | None] = queue.SimpleQueue()
        self._active: dict[str, _Job] = {}
        self._lock = threading.Lock()
        self._threads: list[threading.Thread] = []
        self._entities: list[Any] = []
        self._peers: set[str] = set()  # instance ids whose liveliness token is alive
        self._stopping = False
        self._owns_session = False
        self._started = False
        self._planner_kwargs: dict[str, Any] = {}
        self.plugins: dict[str, Any] = dict(plugins or {})  # requests name only these

    # ------------------------------------------------------------------ lifecycle
    @classmethod
    def open(cls, config: zenoh.Config, **kwargs: Any) -> PlanService:
        """Open a session from ``config`` and start a service that owns it."""
        session = zenoh.open(config)
        service = cls(session, **kwargs)
        service._owns_session = True
        return service.start()

    def start(self) -> PlanService:
        """Declare the Zenoh entities and start the threads; returns ``self``."""
        if self._started:
            return self
        if self._planner is None:
            self._planner = default_planner()
        if self._default_admission:
            self._admission = default_admission()
            self._admission(PlanRequest())  # loads the hand, measures its span: now, not on a request
        if _is_grasp_planner(self._planner):
            # the shape fit's compiled kernels, loaded in the background while the service
            # already answers (its fits run their numpy reference until then: the same results)
            kernels.load_in_background()
        try:
            accepted = set(inspect.signature(self._planner).parameters)
        except (TypeError, ValueError):
            accepted = set()
        # the grasp planner can skip keeping its trace (the service streams every cycle instead)
        # and its own admission check when the service has just run the same one
        self._planner_kwargs = {"keep_trace": False} if "keep_trace" in accepted else {}
        if "check" in accepted and self._admission is not None and self._admission is default_admission():
            self._planner_kwargs["check"] = False
        if "offered" in accepted:  # a request's plug-in names pick from this instance's only
            self._planner_kwargs["offered"] = self.plugins
        self._started = True
        # replies go out on the queryable's own key (the query's may be a wildcard), built once
        self._plan_key = zenoh.KeyExpr(proto.plan_key(self.prefix, self.instance))
        self._plan_key_text = str(self._plan_key)
        s = self.session
        # before the threads (they refresh it) and the plan queryable (_run asks it); its
        # "nobody" notices become refreshes in the dispatcher
        self._watched = _GoalWatchers(s, self.prefix, functools.partial(self._inbox.put, _REFRESH))
        self._entities.append(self._watched)
        self._threads.append(
            threading.Thread(target=self._dispatch, name=f"eos-dispatch-{self.instance}", daemon=True)
        )
        for i in range(self.workers):
            self._threads.append(
                threading.Thread(target=self._work, name=f"eos-worker{i}-{self.instance}", daemon=True)
            )
        for t in self._threads:
            t.start()
        # the other instances (their tokens): who answers a plan query that names no single instance
        self._entities.append(
            s.liveliness().declare_subscriber(
                proto.instance_key(self.prefix), direct_callback(self._on_token), history=True
            )
        )
        self._entities.append(
            s.declare_queryable(self._plan_key, direct_callback(self._on_plan), complete=True)
        )
        self._entities.append(
            s.declare_queryable(proto.cancel_key(self.prefix), direct_callback(self._on_cancel))
        )
        # the token last: a client that sees it can use the queryables
        self._entities.append(s.liveliness().declare_token(proto.instance_key(self.prefix, self.instance)))
        log.info("eos service %s serving under %s", self.instance, self.prefix)
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Withdraw the token and queryables, cancel running plans, answer queued ones, join threads."""
        if not self._started or self._stopping:
            return
        self._stopping = True
        for entity in reversed(self._entities):
            try:
                entity.undeclare()
            except Exception:  # already gone with a closed session
                log.debug("undeclare failed", exc_info=True)
        self._entities.clear()
        with self._lock:
            for job in self._active.values():
                job.cancel.cancel("service stopping")
        self._inbox.put(None)
        for _ in range(self.workers):
            self._jobs.put(None)
        deadline = time.monotonic() + timeout
        for t in self._threads:
            t.join(max(0.0, deadline - time.monotonic()))
        if self._owns_session:
            self.session.close()

    def __enter__(self) -> PlanService:
        return self.start()

    def __exit__(self, *_exc: object) -> None:
        self.stop()

    # ------------------------------------------------------------------ Zenoh callbacks
    def _on_token(self, sample: zenoh.Sample) -> None:
        iid = str(sample.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._peers.add(iid)
            else:
                self._peers.discard(iid)

    def _on_plan(self, query: zenoh.Query) -> None:
        """In Zenoh's thread: decode and admit at once (pure Python: never blocks, never calls Zenoh).

        An admitted plan goes straight to the workers' queue (one thread hop less);
        a refusal goes to the dispatcher thread, which sends the error reply.
        """
        if str(query.key_expr) != self._plan_key_text:  # a wildcard: it reached every instance it names
            with self._lock:
                self.stats.received += 1
            try:
                answer = self._wildcard_refusal(query)
            except Exception as exc:  # a bug must not leave the query unanswered
                answer = proto.RequestError(proto.E_INTERNAL, "request", repr(exc)[:300])
            self._inbox.put(("wildcard", query, answer))
            return
        try:
            refusal = self._admit(query)
        except Exception as exc:  # a bug must not leave the query unanswered
            refusal = proto.RequestError(proto.E_INTERNAL, "request", repr(exc)[:300])
        if refusal is not None:
            self._inbox.put(("error", query, refusal))

    def _on_cancel(self, query: zenoh.Query) -> None:
        self._inbox.put(("cancel", query, None))  # never blocks, never calls Zenoh

    # ------------------------------------------------------------------ threads
    def _reply_err(self, query: zenoh.Query, err: proto.RequestError) -> None:
        log.info("refused goal %s: %s", err.goal_id, err)  # one line per refusal, never a traceback
        with self._lock:
            self.stats.replied_err += 1
            if err.code == proto.E_BUSY:
                self.stats.busy += 1
        try:
            query.reply_err(proto.dumps(err.to_dict()), encoding=zenoh.Encoding.APPLICATION_JSON)
        except Exception:
            log.warning("reply_err failed for %s", err, exc_info=True)
        finally:
            query.drop()

    def _dispatch(self) -> None:
        while True:
            item = self._inbox.get()
            if item is None:
                break
            kind, query, refusal = item
            if query is None:  # _REFRESH: a "nobody" notice came
                self._refresh_watchers()
                continue
            try:
                if kind == "wildcard" and refusal is None:  # another instance answers it
                    query.drop()
                elif refusal is not None:
                    self._reply_err(query, refusal)
                else:
                    self._cancel(query)
            except Exception as exc:  # a bug must not kill the dispatcher, nor leave a query unanswered
                log.exception("dispatcher error")
                self._reply_err(query, proto.RequestError(proto.E_INTERNAL, "request", repr(exc)[:300]))
        # answer whatever is still waiting
        while True:
            try:
                item = self._inbox.get_nowait()
            except queue.Empty:
                break
            if item is not None and item[1] is not None:
                self._reply_err(
                    item[1], item[2] or proto.RequestError(proto.E_UNAVAILABLE, "request", "service stopping")
                )

    def _refresh_watchers(self) -> None:
        """:meth:`_GoalWatchers.refresh` (in our threads: it calls Zenoh); after stop() has
        undeclared the watchers' publisher, nothing."""
        try:
            self._watched.refresh()
        except Exception:
            if not self._stopping:
                log.warning("could not read whether anyone watches the goals", exc_info=True)

    def _wildcard_refusal(self, query: zenoh.Query) -> proto.RequestError | None:
        """The one answer to a plan query whose key names no single instance, or ``None`` to stay
        silent: of the live instances the key matches, only the first by id answers (with the
        keys to use), so the query gets one error, never one plan per instance."""
        key = query.key_expr
        with self._lock:
            named = sorted(
                {self.instance} | {i for i in self._peers if key.intersects(proto.plan_key(self.prefix, i))}
            )
        if named[0] != self.instance:
            return None
        keys = ", ".join(proto.plan_key(self.prefix, i) for i in named[:8]) + (
            " ..." if len(named) > 8 else ""
        )
        return proto.RequestError(
            proto.E_INVALID,
            "key_expr",
            f"{str(key)[:200]} names {len(named)} instance(s); send a plan to exactly one: {keys} "
            f"(find them with a liveliness query on {proto.instance_key(self.prefix)})",
        )

    def _admit(self, query: zenoh.Query) -> proto.RequestError | None:
        """Queue the plan for a worker, or return why not."""
        try:
            job = self._decode(query)
        except Exception:  # a bug: counted all the same, answered by _on_plan
            with self._lock:
                self.stats.received += 1
            raise
        if not isinstance(job, _Job):
            with self._lock:
                self.stats.received += 1
            return job
        goal_id = job.goal_id
        refusal: proto.RequestError
        with self._lock:  # one lock for the count and the admission
            self.stats.received += 1
            if goal_id in self._active:
                refusal = proto.RequestError(
                    proto.E_DUPLICATE, "goal_id", f"goal {goal_id!r} is already queued or running", goal_id
                )
            elif len(self._active) < self.workers + self.queue_size:
                self._active[goal_id] = job
                self._jobs.put(job)
                return None
            else:
                refusal = proto.RequestError(
                    proto.E_BUSY,
                    "request",
                    f"instance {self.instance} busy: {self.workers} running, {self.queue_size} queued; "
                    "retry later or on another instance",
                    goal_id,
                )
        return refusal

    def _decode(self, query: zenoh.Query) -> _Job | proto.RequestError:
        """The job of a plan query (decoded, validated, admitted by the planner), or why not."""
        payload = query.payload
        if self._stopping:
            return proto.RequestError(proto.E_UNAVAILABLE, "request", "service stopping")
        size = 0 if payload is None else len(payload)
        if size > self.max_request_bytes:  # before any copy: the bytes stay in Zenoh until the reply
            return proto.RequestError(
                proto.E_TOO_LARGE, "request", f"{size} bytes > limit {self.max_request_bytes}"
            )
        try:
            goal_id, request, token, watch = proto.decode_envelope(
                b"" if payload is None else payload.to_bytes(), self.max_request_bytes
            )
        except proto.RequestError as err:
            return err.with_traceback(None)  # no frames (and their copy of the payload) kept alive
        if self._admission is not None:
            try:
                self._admission(request)
            except ValidationError as exc:  # the planner could not plan it: refused here, named
                return proto.RequestError(proto.E_INVALID, exc.field, exc.reason, goal_id)
        return _Job(query, goal_id, request, token, _GoalCancel(), watch)

    def _cancel(self, query: zenoh.Query) -> None:
        """Cancel a goal of this instance if the query carries the goal's cancel token.

        Every instance answers: ``found`` false when it does not have the goal, a ``forbidden``
        error when it has it and the token is missing or wrong (goal ids are public: anyone
        subscribed to ``P/goal/*/status`` learns them; the token is the owner's secret).
        """
        # a watcher syncing with this instance (EosClient.watch) sends such a query after its
        # subscriber: counted from now on, before the answer lets it go on
        self._refresh_watchers()
        goal_id = str(query.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            job = self._active.get(goal_id)
        if job is not None:
            payload = query.payload
            given = proto.decode_cancel(
                None if payload is None or len(payload) > proto.MAX_CANCEL_BYTES else payload.to_bytes()
            )
            if not proto.token_matches(job.cancel_token, given):
                reason = (
                    "this goal was sent without a cancel_token: it cannot be cancelled"
                    if job.cancel_token is None
                    else "the cancel_token does not match the goal's (only its owner can cancel it)"
                )
                self._reply_err(query, proto.RequestError(proto.E_FORBIDDEN, "cancel_token", reason, goal_id))
                return
            job.cancel.cancel("cancelled by client")
        try:
            query.reply(
                query.key_expr,
                proto.dumps(
                    {
                        "schema": proto.SCHEMA_VERSION,
                        "goal_id": goal_id,
                        "instance": self.instance,
                        "found": job is not None,
                    }
                ),
            )
        finally:
            query.drop()

    def _work(self) -> None:
        while True:
            job = self._jobs.get()
            if job is None:
                break
            try:
                self._run(job)
            except Exception:
                log.exception("worker error on goal %s", job.goal_id)
            finally:
                with self._lock:
                    self._active.pop(job.goal_id, None)

    def _status(self, goal_id: str, state: str, **extra: Any) -> None:
        """Publish a status message on the goal: :meth:`_head`, then ``state`` and ``extra``."""
        body = self._head(goal_id).encode() + proto.dumps({"state": state, **extra})[1:]
        key = proto.status_key(self.prefix, goal_id)
        self.session.put(key, body, encoding=_JSON, congestion_control=_BLOCK)

    def _head(self, goal_id: str) -> str:
        """The fixed start of every message about a goal: ``{"schema":1,"goal_id":...,"instance":...,``."""
        return f'{{"schema":{proto.SCHEMA_VERSION},"goal_id":"{goal_id}","instance":"{self.instance}",'

    def _run(self, job: _Job) -> None:
        """Run one plan: publish its cycles and status, then answer its query exactly once.

        The critical path after the plan is: result to JSON (once), the ``done`` status, the
        reply; the cycle publisher (if any) is undeclared and the query dropped after the reply.
        """
        goal_id, query = job.goal_id, job.query
        answered = False
        publisher: _CycleSink | None = None
        try:
            if self._stopping:  # never ran, or cut short by stop(): let the client go elsewhere
                raise proto.RequestError(
                    proto.E_UNAVAILABLE, "request", f"instance {self.instance} stopping", goal_id
                )
            head = self._head(goal_id)
            watchers = self._watched
            try:
                watched = watchers.watched(job.watch)  # before the first message
            except Exception:
                if self._stopping:  # stop() undeclared the watcher publisher meanwhile
                    raise proto.RequestError(
                        proto.E_UNAVAILABLE, "request", f"instance {self.instance} stopping", goal_id
                    ) from None
                raise
            if job.cancel.cancelled:  # cancelled while queued: no cycle ran
                result: dict[str, Any] = {
                    "status": "cancelled",
                    "reason": job.cancel.reason,
                    "cycles": 0,
                    "seed": job.request.seed,
                }
            else:
                publisher = _CycleSink(self.session, self.prefix, goal_id)
                if watched:  # with the request: a watcher can draw the object
                    running = proto.dumps({"state": proto.STATE_RUNNING, "request": job.request.to_dict()})
                    self.session.put(
                        proto.status_key(self.prefix, goal_id),
                        head.encode() + running[1:],
                        encoding=_JSON,
                        congestion_control=_BLOCK,
                    )
                result = self._plan(job, publisher, head, watched)
                if self._stopping:
                    raise proto.RequestError(
                        proto.E_UNAVAILABLE, "request", f"instance {self.instance} stopping", goal_id
                    )
            encoded = _encode(result)  # once, spliced into the status message and the reply
            head_b = head.encode()
            if watched or watchers.any:
                status = proto.dumps({"status": result.get("status"), "cycles": result.get("cycles")})[1:-1]
                self.session.put(
                    proto.status_key(self.prefix, goal_id),
                    head_b + b'"state":"done",' + status + b',"result":' + encoded + b"}",
                    encoding=_JSON,
                    congestion_control=_BLOCK,
                )
            answered = True
            with self._lock:  # counted first: the client may read the stats as soon as it has the reply
                self.stats.replied_ok += 1
                if result.get("status") == "cancelled":
                    self.stats.cancelled += 1
            query.reply(self._plan_key, head_b + b'"result":' + encoded + b"}", encoding=_JSON)
            query.drop()
        except proto.RequestError as err:
            if not answered:
                self._reply_err(query, err)
        except ValidationError as exc:  # the planner refused the request (admission let it through)
            if not answered:
                self._done_refused(goal_id)
                self._reply_err(query, proto.RequestError(proto.E_INVALID, exc.field, exc.reason, goal_id))
        except Exception as exc:
            log.exception("plan %s failed", goal_id)
            if not answered:
                try:
                    self._status(
                        goal_id,
                        proto.STATE_DONE,
                        status="error",
                        cycles=None,
                        result={"status": "error", "reason": repr(exc)[:300]},
                    )
                except Exception:
                    log.debug("status publication failed", exc_info=True)
                self._reply_err(
                    query, proto.RequestError(proto.E_INTERNAL, "request", repr(exc)[:300], goal_id)
                )
        finally:
            if publisher is not None:  # after the reply: off the request's critical path
                try:
                    publisher.undeclare()
                except Exception:
                    log.debug("undeclare failed", exc_info=True)
            watchers = self._watched
            if watchers.any or watchers.zenoh_says_matching:  # believed until the tables are read
                self._refresh_watchers()

    def _done_refused(self, goal_id: str) -> None:
        """Close a goal the planner refused after admission: ``done`` with status ``refused``, no
        cycle (published whether or not anyone watches: a rare path, kept simple)."""
        try:
            self._status(goal_id, proto.STATE_DONE, status="refused", cycles=0, result=None)
        except Exception:
            log.debug("status publication failed", exc_info=True)

    def _plan(self, job: _Job, publisher: _CycleSink, head: str, watched: bool) -> dict[str, Any]:
        """Run the planner, publishing every cycle while watched (from the start, or since a
        watcher came: :attr:`_GoalWatchers.any`); the result's JSON form."""
        seq = 0
        sent = 0
        head += '"seq":'
        put = publisher.put
        record_json = proto.cycle_record_json
        watchers = self._watched

        def on_cycle(record: CycleRecord) -> None:
            nonlocal seq, sent
            seq += 1
            if not (watched or watchers.any):  # nobody would receive it: numbered, not built nor sent
                return
            if type(record) is CycleRecord:
                body = record_json(record)
            else:  # a planner of another kind: its records' own JSON form
                body = _encode(record.to_dict() if hasattr(record, "to_dict") else record).decode()
            put((head + str(seq) + ',"record":' + body + "}").encode())
            sent += 1

        try:
            assert self._planner is not None
            outcome = self._planner(job.request, on_cycle=on_cycle, cancel=job.cancel, **self._planner_kwargs)
            if type(outcome) is PlanResult:  # its members as held: encoded once, by msgspec, as is
                result = outcome.to_dict(jsonable=False)
            else:
                result = outcome.to_dict() if hasattr(outcome, "to_dict") else dict(outcome)
        finally:
            with self._lock:
                self.stats.cycles_published += seq
                self.stats.cycles_sent += sent
        if not isinstance(result, dict):
            raise ContractError("planner", f"its result is a {type(result).__name__}, not a mapping")
        if result.get("cycles") is not None and result.get("cycles") != seq:
            log.warning(
                "goal %s: planner reports %s cycles, %d published", job.goal_id, result.get("cycles"), seq
            )
        result.setdefault("cycles_published", seq)
        return result
