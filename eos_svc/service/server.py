"""The EOS planning service on Zenoh.

One :class:`PlanService` is one service instance. It declares, under its
prefix ``P`` (see :mod:`eos_svc.service.protocol`):

- a liveliness token ``P/instance/<iid>`` (discovery);
- a queryable ``P/plan/<iid>`` — a plan request in, exactly one reply out
  (the result, or an error reply with a code, the field and the reason);
- a queryable ``P/cancel/*`` — cancel a queued or running goal by id;

and publishes every cycle of a plan on ``P/goal/<goal_id>/cycle`` and its
status on ``P/goal/<goal_id>/status``, reliably (``CongestionControl.BLOCK``).

Threads: the queryables' callbacks run in Zenoh's own thread and never block
nor call Zenoh (see :func:`~eos_svc.service.session.direct_callback`): the plan
callback decodes and validates the request and either queues it for the
``workers`` worker threads that run the planner (at most ``workers +
queue_size`` goals admitted; past that a ``busy`` error) or hands the refusal
to a dispatcher thread, which sends the error reply (it also serves cancel).
Every query ends in exactly one ``reply`` or ``reply_err`` and is dropped.
"""

from __future__ import annotations

import inspect
import logging
import os
import queue
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import zenoh

from eos_svc.agents.request import PlanRequest
from eos_svc.controller import CancelToken
from eos_svc.records import CycleRecord, to_jsonable
from eos_svc.service import protocol as proto
from eos_svc.service.session import direct_callback

log = logging.getLogger(__name__)

_JSON = zenoh.Encoding.APPLICATION_JSON
_BLOCK = zenoh.CongestionControl.BLOCK

#: a planner as the service calls it (the signature of ``eos_svc.agents.planner.plan``)
Planner = Callable[..., Any]


def default_planner() -> Planner:
    """The grasp planner, imported only when first needed."""
    from eos_svc.agents.planner import plan  # lazy: Pinocchio and coal load here

    return plan


def _encode(obj: Any) -> bytes:
    """Strict JSON bytes; values JSON does not take (arrays, NaN, ...) go through ``to_jsonable``."""
    try:
        return proto.dumps(obj)
    except (TypeError, ValueError):
        return proto.dumps(to_jsonable(obj))


@dataclass
class _Job:
    query: zenoh.Query
    goal_id: str
    request: PlanRequest
    cancel: CancelToken = field(default_factory=CancelToken)
    received: float = field(default_factory=time.monotonic)


@dataclass
class ServiceStats:
    """Counters of one instance (all since start)."""

    received: int = 0
    replied_ok: int = 0
    replied_err: int = 0
    busy: int = 0
    cancelled: int = 0
    cycles_published: int = 0

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
        self.workers = workers
        self.queue_size = queue_size
        self.max_request_bytes = max_request_bytes
        self.stats = ServiceStats()
        self._inbox: queue.SimpleQueue[tuple[str, zenoh.Query, proto.RequestError | None] | None] = (
            queue.SimpleQueue()
        )
        # bounded by admission: at most workers + queue_size goals active (running or waiting)
        self._jobs: queue.SimpleQueue[_Job | None] = queue.SimpleQueue()
        self._active: dict[str, _Job] = {}
        self._lock = threading.Lock()
        self._threads: list[threading.Thread] = []
        self._entities: list[Any] = []
        self._stopping = False
        self._owns_session = False
        self._started = False
        self._planner_kwargs: dict[str, Any] = {}

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
        try:  # the grasp planner can skip keeping its trace: the service streams every cycle instead
            params = inspect.signature(self._planner).parameters
            self._planner_kwargs = {"keep_trace": False} if "keep_trace" in params else {}
        except (TypeError, ValueError):
            self._planner_kwargs = {}
        self._started = True
        # replies go out on the queryable's own key (the query's may be a wildcard), built once
        self._plan_key = zenoh.KeyExpr(proto.plan_key(self.prefix, self.instance))
        self._threads.append(
            threading.Thread(target=self._dispatch, name=f"eos-dispatch-{self.instance}", daemon=True)
        )
        for i in range(self.workers):
            self._threads.append(
                threading.Thread(target=self._work, name=f"eos-worker{i}-{self.instance}", daemon=True)
            )
        for t in self._threads:
            t.start()
        s = self.session
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
    def _on_plan(self, query: zenoh.Query) -> None:
        """In Zenoh's thread: decode and admit at once (pure Python: never blocks, never calls Zenoh).

        An admitted plan goes straight to the workers' queue (one thread hop less);
        a refusal goes to the dispatcher thread, which sends the error reply.
        """
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
            _kind, query, refusal = item
            try:
                if refusal is not None:
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
            if item is not None:
                self._reply_err(
                    item[1], item[2] or proto.RequestError(proto.E_UNAVAILABLE, "request", "service stopping")
                )

    def _admit(self, query: zenoh.Query) -> proto.RequestError | None:
        """Queue the plan for a worker, or return why not."""
        with self._lock:
            self.stats.received += 1
        payload = query.payload
        try:
            if self._stopping:
                raise proto.RequestError(proto.E_UNAVAILABLE, "request", "service stopping")
            goal_id, request = proto.decode_request(
                b"" if payload is None else payload.to_bytes(), self.max_request_bytes
            )
        except proto.RequestError as err:
            return err
        job = _Job(query, goal_id, request)
        refusal: proto.RequestError
        with self._lock:
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

    def _cancel(self, query: zenoh.Query) -> None:
        goal_id = str(query.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            job = self._active.get(goal_id)
        if job is not None:
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
        reply; the cycle publisher is undeclared and the query dropped after the reply.
        """
        goal_id, query = job.goal_id, job.query
        answered = False
        publisher: Any = None
        try:
            if self._stopping:  # never ran, or cut short by stop(): let the client go elsewhere
                raise proto.RequestError(
                    proto.E_UNAVAILABLE, "request", f"instance {self.instance} stopping", goal_id
                )
            head = self._head(goal_id)
            status_key = proto.status_key(self.prefix, goal_id)
            running = proto.dumps({"state": proto.STATE_RUNNING, "request": job.request.to_dict()})
            if job.cancel.cancelled:  # cancelled while queued: no cycle ran
                result: dict[str, Any] = {
                    "status": "cancelled",
                    "reason": job.cancel.reason,
                    "cycles": 0,
                    "seed": job.request.seed,
                }
            else:
                publisher = self.session.declare_publisher(
                    proto.cycle_key(self.prefix, goal_id), encoding=_JSON, congestion_control=_BLOCK
                )
                self.session.put(
                    status_key,
                    head.encode() + running[1:],  # with the request: a watcher can draw the object
                    encoding=_JSON,
                    congestion_control=_BLOCK,
                )
                result = self._plan(job, publisher, head)
                if self._stopping:
                    raise proto.RequestError(
                        proto.E_UNAVAILABLE, "request", f"instance {self.instance} stopping", goal_id
                    )
            encoded = _encode(result)  # once, spliced into the status message and the reply
            status = proto.dumps({"status": result.get("status"), "cycles": result.get("cycles")})[1:-1]
            head_b = head.encode()
            self.session.put(
                status_key,
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

    def _plan(self, job: _Job, publisher: Any, head: str) -> dict[str, Any]:
        seq = 0
        head += '"seq":'
        put = publisher.put
        record_json = proto.cycle_record_json

        def on_cycle(record: CycleRecord) -> None:
            nonlocal seq
            seq += 1
            if type(record) is CycleRecord:
                body = record_json(record)
            else:  # a planner of another kind: its records' own JSON form
                body = _encode(record.to_dict() if hasattr(record, "to_dict") else record).decode()
            put((head + str(seq) + ',"record":' + body + "}").encode())

        try:
            assert self._planner is not None
            outcome = self._planner(job.request, on_cycle=on_cycle, cancel=job.cancel, **self._planner_kwargs)
            result = outcome.to_dict() if hasattr(outcome, "to_dict") else dict(outcome)
        finally:
            with self._lock:
                self.stats.cycles_published += seq
        if not isinstance(result, dict):
            raise TypeError(f"planner result is a {type(result).__name__}, not a mapping")
        if result.get("cycles") is not None and result.get("cycles") != seq:
            log.warning(
                "goal %s: planner reports %s cycles, %d published", job.goal_id, result.get("cycles"), seq
            )
        result.setdefault("cycles_published", seq)
        return result
