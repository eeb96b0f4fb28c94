"""The EOS planning service on Zenoh: :class:`PlanService`, one service instance (its keys and
threads: ``docs/service.md``). Zenoh's callbacks never block nor call Zenoh: they admit a plan
for the workers or hand a refusal or cancel to the dispatcher thread; every query gets one reply.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import os
import queue
import secrets
import threading
import time
from collections.abc import Mapping
from typing import Any

import zenoh

from eos_svc.errors import ContractError, ValidationError
from eos_svc.schema.request import MAX_DEADLINE_S, PlanRequest
from eos_svc.schema.result import PlanResult
from eos_svc.service import protocol as proto
from eos_svc.service.goal_stream import GoalStream
from eos_svc.service.goal_watchers import GoalWatchers
from eos_svc.service.goals import Goal, GoalTable, ServiceStats
from eos_svc.service.peers import PeerInstances
from eos_svc.service.planners import (
    Admission,
    Planner,
    default_admission,
    default_planner,
    is_grasp_planner,
    planner_options,
)
from eos_svc.service.session import direct_callback
from eos_svc.service.wire_json import dumps
from eos_svc.shape import kernels

log = logging.getLogger(__name__)

_JSON = zenoh.Encoding.APPLICATION_JSON

#: the dispatcher's work items: (kind, query, refusal); None stops it
_Item = tuple[str, zenoh.Query | None, proto.RequestError | None]
#: the item that asks the dispatcher to refresh the goal watchers' flag (GoalWatchers.refresh)
_REFRESH: _Item = ("refresh", None, None)

#: the deadline of a goal whose request gives none (s): every goal ends
DEFAULT_MAX_DEADLINE_S = 600.0


class PlanService:
    """A service instance on an open Zenoh session.

    Args:
        session: the Zenoh session (closed by :meth:`stop` only if :meth:`open` opened it).
        namespace: optional namespace under the versioned prefix.
        instance: this instance's id (default: ``<pid>-<random hex>``).
        planner: ``plan(request, *, on_cycle, cancel) -> result``; default the grasp planner.
        workers: threads running plans concurrently (≥ 1).
        queue_size: accepted plans waiting for a worker before ``busy`` (≥ 0).
        max_request_bytes: largest request payload accepted (bytes).
        max_deadline_s: the deadline of a goal whose request gives none or a longer one (s).
        admission: checks every decoded request before it is queued (a ``ValidationError`` is an
            ``invalid_request`` naming the field); default: the grasp planner's
            :func:`~eos_svc.world.admission.check_plannable`, none for another planner.
        plugins: the plug-in agents requests may name (:mod:`eos_svc.service.plugins`); default none.
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
        max_deadline_s: float = DEFAULT_MAX_DEADLINE_S,
        admission: Admission | None = None,
        plugins: Mapping[str, Any] | None = None,
    ) -> None:
        if workers < 1:
            raise proto.RequestError(proto.E_INVALID, "workers", f"must be ≥ 1, got {workers}")
        if queue_size < 0:
            raise proto.RequestError(proto.E_INVALID, "queue_size", f"must be ≥ 0, got {queue_size}")
        if not 0 < max_deadline_s <= MAX_DEADLINE_S:
            raise proto.RequestError(
                proto.E_INVALID,
                "max_deadline_s",
                f"must be in (0, {MAX_DEADLINE_S:g}] s, got {max_deadline_s}",
            )
        self.session = session
        self.prefix = proto.prefix(namespace)
        self.instance = (
            proto.check_id(instance, "instance") if instance else f"{os.getpid()}-{secrets.token_hex(4)}"
        )
        self._planner = planner
        self._admission: Admission | None = admission
        self._default_admission = admission is None and is_grasp_planner(planner)
        self.workers = workers
        self.queue_size = queue_size
        self.max_request_bytes = max_request_bytes
        self.max_deadline_s = max_deadline_s
        self.stats = ServiceStats()
        self._inbox: queue.SimpleQueue[_Item | None] = queue.SimpleQueue()
        # bounded by admission: at most workers + queue_size goals active (running or waiting)
        self._jobs: queue.SimpleQueue[Goal | None] = queue.SimpleQueue()
        self._goals = GoalTable(workers + queue_size, self.instance)
        self._threads: list[threading.Thread] = []
        self._entities: list[Any] = []
        self._peers = PeerInstances(self.prefix, self.instance)
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
        if is_grasp_planner(self._planner):
            # the shape fit's compiled kernels, loaded in the background while the service
            # already answers (its fits run their numpy reference until then: the same results)
            kernels.load_in_background()
        self._planner_kwargs = planner_options(self._planner, self._admission, self.plugins)
        self._started = True
        # replies go out on the queryable's own key (the query's may be a wildcard), built once
        self._plan_key = zenoh.KeyExpr(proto.plan_key(self.prefix, self.instance))
        self._plan_key_text = str(self._plan_key)
        s = self.session
        # before the threads (they refresh it) and the plan queryable (_run asks it); its
        # "nobody" notices become refreshes in the dispatcher
        self._watched = GoalWatchers(s, self.prefix, functools.partial(self._inbox.put, _REFRESH))
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
        self._entities += [  # declared in this order
            # the other instances (their tokens): who answers a plan query that names no single instance
            s.liveliness().declare_subscriber(
                proto.instance_key(self.prefix), direct_callback(self._peers.on_token), history=True
            ),
            s.declare_queryable(self._plan_key, direct_callback(self._on_plan), complete=True),
            s.declare_queryable(proto.cancel_key(self.prefix), direct_callback(self._on_cancel)),
            # the token last: a client that sees it can use the queryables
            s.liveliness().declare_token(proto.instance_key(self.prefix, self.instance)),
        ]
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
        self._goals.cancel_all("service stopping")
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
        """In Zenoh's thread: decode and admit at once; a refusal goes to the dispatcher."""
        self.stats.add(received=1)
        try:
            if str(query.key_expr) != self._plan_key_text:  # a wildcard: it reached every instance it names
                self._inbox.put(("wildcard", query, self._peers.wildcard_refusal(query.key_expr)))
                return
            refusal = self._admit(query)
        except Exception as exc:  # a bug must not leave the query unanswered
            refusal = proto.RequestError(proto.E_INTERNAL, "request", repr(exc)[:300])
        if refusal is not None:
            self._inbox.put(("error", query, refusal))

    def _on_cancel(self, query: zenoh.Query) -> None:
        self.stats.add(received=1, cancels=1)
        self._inbox.put(("cancel", query, None))  # never blocks, never calls Zenoh

    # ------------------------------------------------------------------ admission
    def _admit(self, query: zenoh.Query) -> proto.RequestError | None:
        """Queue the plan for a worker, or return why not."""
        goal = self._decode(query)
        if isinstance(goal, proto.RequestError):
            return goal
        refusal = self._goals.admit(goal)
        if refusal is None:
            self._jobs.put(goal)
        return refusal

    def _decode(self, query: zenoh.Query) -> Goal | proto.RequestError:
        """The goal of a plan query (decoded, validated, admitted by the planner), or why not."""
        payload = query.payload
        if self._stopping:
            return proto.RequestError(proto.E_UNAVAILABLE, "request", "service stopping")
        size = 0 if payload is None else len(payload)
        if size > self.max_request_bytes:  # before any copy: the bytes stay in Zenoh until the reply
            return proto.RequestError(
                proto.E_TOO_LARGE, "request", f"{size} bytes > limit {self.max_request_bytes}"
            )
        try:
            env = proto.decode_envelope(
                b"" if payload is None else payload.to_bytes(), self.max_request_bytes
            )
        except proto.RequestError as err:
            return err.with_traceback(None)  # no frames (and their copy of the payload) kept alive
        if self._admission is not None:
            try:
                self._admission(env.request)
            except ValidationError as exc:  # the planner could not plan it: refused here, named
                return proto.RequestError(proto.E_INVALID, exc.field, exc.reason, env.goal_id)
        return Goal(query, env.goal_id, env.request, env.cancel_token, watch=env.watch)

    # ------------------------------------------------------------------ dispatcher: refusals, cancels
    def _reply_err(self, query: zenoh.Query, err: proto.RequestError) -> None:
        log.info("refused goal %s: %s", err.goal_id, err)  # one line per refusal, never a traceback
        self.stats.add(replied_err=1, busy=err.code == proto.E_BUSY)
        try:
            query.reply_err(dumps(err.to_dict()), encoding=_JSON)
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
                    self.stats.add(left_to_peers=1)
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
        """:meth:`GoalWatchers.refresh` (in our threads: it calls Zenoh); after stop() has
        undeclared the watchers' publisher, nothing."""
        try:
            self._watched.refresh()
        except Exception:
            if not self._stopping:
                log.warning("could not read whether anyone watches the goals", exc_info=True)

    def _cancel(self, query: zenoh.Query) -> None:
        """Cancel a goal of this instance if the query carries the goal's cancel token (else
        ``forbidden``: goal ids are public, the token is the owner's secret); ``found`` false
        when this instance does not have the goal."""
        # a watcher syncing with this instance (EosClient.watch) sends such a query after its
        # subscriber: counted from now on, before the answer lets it go on
        self._refresh_watchers()
        goal_id = str(query.key_expr).rsplit("/", 1)[-1]
        goal = self._goals.get(goal_id)
        if goal is not None:
            payload = query.payload
            given = proto.decode_cancel(
                None if payload is None or len(payload) > proto.MAX_CANCEL_BYTES else payload.to_bytes()
            )
            if not proto.token_matches(goal.cancel_token, given):
                reason = (
                    "this goal was sent without a cancel_token: it cannot be cancelled"
                    if goal.cancel_token is None
                    else "the cancel_token does not match the goal's (only its owner can cancel it)"
                )
                self._reply_err(query, proto.RequestError(proto.E_FORBIDDEN, "cancel_token", reason, goal_id))
                return
            goal.cancel.cancel("cancelled by client")
        answer = {"schema": proto.SCHEMA_VERSION, "goal_id": goal_id, "instance": self.instance}
        self.stats.add(replied_ok=1)
        try:
            query.reply(query.key_expr, dumps({**answer, "found": goal is not None}))
        finally:
            query.drop()

    # ------------------------------------------------------------------ workers
    def _work(self) -> None:
        while True:
            goal = self._jobs.get()
            if goal is None:
                break
            try:
                self._run(goal)
            except Exception:
                log.exception("worker error on goal %s", goal.goal_id)
            finally:
                self._goals.release(goal.goal_id)

    def _unavailable(self, goal_id: str) -> proto.RequestError:
        return proto.RequestError(
            proto.E_UNAVAILABLE, "request", f"instance {self.instance} stopping", goal_id
        )

    def _run(self, goal: Goal) -> None:
        """Run one plan: publish its messages (while watched), then answer its query exactly once."""
        goal_id, query = goal.goal_id, goal.query
        answered = False
        stream: GoalStream | None = None
        try:
            if self._stopping:  # never ran, or cut short by stop(): let the client go elsewhere
                raise self._unavailable(goal_id)
            try:
                watched = self._watched.watched(goal.watch)  # before the first message
            except Exception:
                if self._stopping:  # stop() undeclared the watchers' publisher meanwhile
                    raise self._unavailable(goal_id) from None
                raise
            stream = GoalStream(self.session, self.prefix, self.instance, goal_id, self._watched, watched)
            request = self._bounded(goal.request)
            stream.running(request.to_dict())  # on every path a worker takes: running, then done
            if goal.cancel.cancelled:  # cancelled while queued: no cycle ran
                result: dict[str, Any] = {
                    "status": "cancelled",
                    "reason": goal.cancel.reason,
                    "cycles": 0,
                    "seed": request.seed,
                }
            else:
                result = self._plan(goal, request, stream)
                if self._stopping:
                    raise self._unavailable(goal_id)
            result.setdefault("cycles_published", stream.seq)
            done = stream.done_message(
                status=result.get("status"), cycles=result.get("cycles"), result=result
            )
            stream.done(done)
            answered = True
            # counted first: the client may read the stats as soon as it has the reply
            self.stats.add(
                replied_ok=1,
                cancelled=result.get("status") == "cancelled",
                cycles_published=stream.seq,
                cycles_sent=stream.sent,
            )
            query.reply(self._plan_key, done, encoding=_JSON)  # the reply is the done status
            query.drop()
        except proto.RequestError as err:
            if not answered:
                self._reply_err(query, err)
        except ValidationError as exc:  # the planner refused the request (admission let it through)
            if not answered:
                self._done_anyway(stream, status="refused", cycles=0, result=None)
                self._reply_err(query, proto.RequestError(proto.E_INVALID, exc.field, exc.reason, goal_id))
        except Exception as exc:
            log.exception("plan %s failed", goal_id)
            if not answered:
                reason = repr(exc)[:300]
                self._done_anyway(
                    stream, status="error", cycles=None, result={"status": "error", "reason": reason}
                )
                self._reply_err(query, proto.RequestError(proto.E_INTERNAL, "request", reason, goal_id))
        finally:
            if stream is not None and not answered:
                self.stats.add(cycles_published=stream.seq, cycles_sent=stream.sent)
            watchers = self._watched
            if watchers.any or watchers.zenoh_says_matching:  # believed until the tables are read
                self._refresh_watchers()

    def _done_anyway(self, stream: GoalStream | None, **fields: Any) -> None:
        """Publish ``done`` with ``fields`` for a goal that ended without a result, watched or not."""
        if stream is None:
            return
        try:
            stream.done(stream.done_message(**fields), always=True)
        except Exception:
            log.debug("status publication failed", exc_info=True)

    def _bounded(self, request: PlanRequest) -> PlanRequest:
        """``request`` with a deadline of at most :attr:`max_deadline_s` (also when it gives none)."""
        if request.deadline_s is not None and request.deadline_s <= self.max_deadline_s:
            return request
        return dataclasses.replace(request, deadline_s=self.max_deadline_s)

    def _plan(self, goal: Goal, request: PlanRequest, stream: GoalStream) -> dict[str, Any]:
        """Run the planner, publishing every cycle while watched; the result's JSON form."""
        assert self._planner is not None
        outcome = self._planner(request, on_cycle=stream.cycle, cancel=goal.cancel, **self._planner_kwargs)
        if type(outcome) is PlanResult:  # its members as held: encoded once, by msgspec, as is
            result = outcome.to_dict(jsonable=False)
        else:
            result = outcome.to_dict() if hasattr(outcome, "to_dict") else dict(outcome)
        if not isinstance(result, dict):
            raise ContractError("planner", f"its result is a {type(result).__name__}, not a mapping")
        if result.get("cycles") is not None and result.get("cycles") != stream.seq:
            log.warning(
                "goal %s: planner reports %s cycles, %d published",
                goal.goal_id,
                result.get("cycles"),
                stream.seq,
            )
        return result
