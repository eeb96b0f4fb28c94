"""Python client of the EOS planning service (``docs/service.md``): each plan goes to one live
instance (:mod:`~eos_svc.service.instances`), is watched (:mod:`~eos_svc.service.plan_attempt`)
and is retried on another instance when the one asked is lost or busy.
"""

from __future__ import annotations

import contextlib
import secrets
import time
from collections.abc import Callable, Mapping
from typing import Any

import zenoh

from eos_svc.schema.request import PlanRequest
from eos_svc.service import protocol as proto
from eos_svc.service.instances import LiveInstances, ServiceUnavailableError
from eos_svc.service.plan_attempt import (
    NO_CONSOLIDATION,
    Attempt,
    CycleHandler,
    InstanceLostError,
    NoReplyInTimeError,
    PlanOutcome,
)
from eos_svc.service.session import direct_callback
from eos_svc.service.wire_json import loads_message

#: tries with a fresh goal id when the service refuses the one drawn as a duplicate
_DUPLICATE_RETRIES = 3


def new_goal_id() -> str:
    """A fresh goal id: ``g-`` and 96 random bits from the OS's CSPRNG (24 hex digits), so no one
    who has seen this client's other goal ids can guess it (ids are public, see ``P/goal/*``)."""
    return f"g-{secrets.token_hex(12)}"


class EosClient:
    """Client of the EOS planning service on an open Zenoh session.

    Args:
        session: an open Zenoh session (closed by :meth:`close` only if
            the client opened it, see :meth:`open`).
        namespace: the service's namespace, if any.
        timeout_margin_s: added to the request's deadline to time out a plan query (s).
    """

    def __init__(
        self,
        session: zenoh.Session,
        *,
        namespace: str | None = None,
        timeout_margin_s: float = 10.0,
    ) -> None:
        self.session = session
        self.prefix = proto.prefix(namespace)
        self.timeout_margin_s = timeout_margin_s
        self._owns_session = False
        self._tokens: dict[str, str] = {}  # goal id -> cancel token, while the plan is in flight
        #: whether watch() was called: this session may hold goal subscribers of its own, so its
        #: plans do not tell the service whether they are watched (it asks Zenoh; see plan())
        self._watching = False
        self._instances = LiveInstances(session, self.prefix)

    @classmethod
    def open(cls, config: zenoh.Config, **kwargs: Any) -> EosClient:
        """Open a session from ``config`` and a client that owns it."""
        client = cls(zenoh.open(config), **kwargs)
        client._owns_session = True
        return client

    def close(self) -> None:
        """Undeclare the liveliness subscriber (and close the session if owned)."""
        with contextlib.suppress(Exception):  # already gone with a closed session
            self._instances.close()
        if self._owns_session:
            self.session.close()

    def __enter__(self) -> EosClient:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ discovery
    def instances(self) -> list[str]:
        """Instances whose liveliness token is alive now (sorted)."""
        return self._instances.alive()

    def discover(self, timeout: float = 1.0) -> list[str]:
        """The instances alive now (sorted), see :meth:`LiveInstances.discover`."""
        return self._instances.discover(timeout)

    def wait_for_instances(self, n: int = 1, timeout: float = 5.0) -> list[str]:
        """Block until at least ``n`` instances are alive; returns them (raises ServiceUnavailableError)."""
        return self._instances.wait_for(n, timeout)

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
            goal_id: the goal id (default: :func:`new_goal_id`, drawn again on ``duplicate_goal``).
            on_cycle: called with every cycle message, in order, in this thread.
            instance: ask this instance only (no spreading, no retry elsewhere).
            watch: subscribe to the goal's cycles and status (needed for ``on_cycle``), and tell
                the instance so in the request (left out once :meth:`watch` was called: then
                the instance asks Zenoh whether anyone watches).
            timeout: seconds to wait for one instance's answer (default: the request's deadline
                + ``timeout_margin_s``); one that does not answer in time is not asked again.
            max_attempts: instances to try before giving up.
            cancel_token: the goal's secret for :meth:`cancel` (default: a fresh random one).

        Raises:
            RequestError: the service refused the request (code, field, reason).
            ServiceUnavailableError: no instance answered.
        """
        req = PlanRequest() if request is None else request
        chosen = goal_id is None
        if goal_id is not None:
            proto.check_id(goal_id, "goal_id")
        if instance is not None:
            proto.check_id(instance, "instance")  # one instance, never a wildcard
        if cancel_token is None:
            cancel_token = proto.new_cancel_token()
        elif not proto.is_token(cancel_token):
            raise proto.RequestError(
                proto.E_INVALID, "cancel_token", "must be 16-128 characters of A-Z a-z 0-9 _ -"
            )
        if timeout is None:
            deadline = req.deadline_s if isinstance(req, PlanRequest) else req.get("deadline_s", 10.0)
            timeout = (deadline if isinstance(deadline, (int, float)) else 60.0) + self.timeout_margin_s
        hint = None if self._watching else watch
        for _ in range(_DUPLICATE_RETRIES if chosen else 1):
            goal = new_goal_id() if chosen else str(goal_id)
            payload = proto.encode_request(goal, req, cancel_token, hint)
            self._tokens[goal] = cancel_token
            try:
                return self._plan(goal, payload, on_cycle, instance, watch, timeout, max_attempts)
            except proto.RequestError as err:
                if not (chosen and err.code == proto.E_DUPLICATE):
                    raise
                refusal = err  # someone holds the id this client drew: draw another
            finally:
                self._tokens.pop(goal, None)
        raise refusal

    def _plan(
        self,
        goal_id: str,
        payload: bytes,
        on_cycle: CycleHandler | None,
        instance: str | None,
        watch: bool,
        timeout: float,
        max_attempts: int,
    ) -> PlanOutcome:
        """Send the plan to one instance after another until one answers (see :meth:`plan`)."""
        t0 = time.monotonic()
        exclude: set[str] = set()  # tried in this round
        timed_out: set[str] = set()  # never asked again in this call (see NoReplyInTimeError)
        last_error: str = "no service instance found"
        for attempt in range(1, max_attempts + 1):
            iid = instance or self._instances.choose(exclude | timed_out)
            if iid is None:
                self.discover(timeout=0.5)
                iid = self._instances.choose(exclude | timed_out)
                if iid is None and exclude:  # every instance tried: start over after a pause
                    time.sleep(0.05 * attempt)
                    exclude.clear()
                    iid = self._instances.choose(timed_out)
            if iid is None:
                raise ServiceUnavailableError(last_error)
            try:
                one = Attempt(self.session, self.prefix, iid, goal_id, payload, on_cycle, watch, timeout)
                outcome = one.run(self._instances)
            except InstanceLostError as lost:
                last_error = f"instance {iid}: {lost}"
                (timed_out if isinstance(lost, NoReplyInTimeError) else exclude).add(iid)
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

    # ------------------------------------------------------------------ cancel / watch
    def cancel(self, goal_id: str, timeout: float = 2.0, *, cancel_token: str | None = None) -> bool:
        """Cancel a queued or running goal on whichever instance has it; True when one had it.
        The cancel carries ``cancel_token`` (default: the one this client sent with the plan).

        Raises:
            RequestError: ``forbidden`` — the instance running the goal refused the token.
        """
        proto.check_id(goal_id, "goal_id")
        if cancel_token is None:
            cancel_token = self._tokens.get(goal_id)
        found = False
        refusal: proto.RequestError | None = None
        for reply in self._cancel_query(goal_id, proto.encode_cancel(cancel_token), timeout):
            if reply.ok is not None:
                try:
                    found = found or bool(loads_message(reply.ok.payload.to_bytes()).get("found"))
                except (ValueError, AttributeError):
                    continue
            elif reply.err is not None:
                refusal = proto.error_from_payload(reply.err.payload.to_bytes())
        if refusal is not None and not found:
            raise refusal
        return found

    def _cancel_query(self, goal_id: str, payload: bytes | None, timeout: float) -> Any:
        """The replies of every live instance to a query on ``P/cancel/<goal_id>`` (``timeout`` in s)."""
        return self.session.get(
            proto.cancel_key(self.prefix, goal_id),
            payload=payload,
            target=zenoh.QueryTarget.ALL,
            consolidation=NO_CONSOLIDATION,
            timeout=timeout,
        )

    def watch(
        self,
        callback: Callable[[str, dict[str, Any]], None],
        goal_id: str = "*",
        *,
        sync_timeout: float | None = 2.0,
    ) -> Any:
        """Subscribe to cycle and status messages (of every goal by default); returns the subscriber.

        ``callback(kind, message)`` runs in a Zenoh thread, ``kind`` ``"cycle"`` or ``"status"``.
        Unless ``sync_timeout`` is ``None``, returns after :meth:`sync_with_instances` (at most
        ``sync_timeout`` s), so every goal the instances start from then on is seen from its start.
        """

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                msg = loads_message(sample.payload.to_bytes())
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
        """A round trip to every live instance (a cancel of a goal id nobody uses); the instances
        that answered (sorted), which have then received every subscriber declared before."""
        answered: set[str] = set()
        for reply in self._cancel_query(f"sync-{secrets.token_hex(8)}", None, timeout):
            if reply.ok is not None:
                try:
                    answered.add(str(loads_message(reply.ok.payload.to_bytes())["instance"]))
                except (ValueError, KeyError, TypeError):
                    continue
        return sorted(answered)
