"""The service instances a client knows: alive (their liveliness tokens), and its plans in flight on each."""

from __future__ import annotations

import itertools
import queue
import threading
import time
from typing import Any

import zenoh

from eos_svc.errors import EosError
from eos_svc.service import protocol as proto
from eos_svc.service.session import direct_callback


class ServiceUnavailableError(EosError):
    """No service instance answered the plan (none found, or every attempt lost its instance)."""


class LiveInstances:
    """The live set of service instances under ``prefix``, kept from their liveliness tokens.

    An attempt registers its event queue (:meth:`track`) while its query is in flight: when that
    instance's token goes, ``("lost", iid)`` is put into it.
    """

    def __init__(self, session: zenoh.Session, prefix: str) -> None:
        self._session = session
        self._prefix = prefix
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)
        self._live: set[str] = set()
        self._waiters: dict[int, tuple[str, queue.SimpleQueue[Any]]] = {}
        self._waiter_ids = itertools.count()
        self._turn = itertools.count()
        self._token_sub = session.liveliness().declare_subscriber(
            proto.instance_key(prefix), direct_callback(self._on_token), history=True
        )

    def close(self) -> None:
        """Undeclare the liveliness subscriber."""
        self._token_sub.undeclare()

    def _on_token(self, sample: zenoh.Sample) -> None:
        iid = str(sample.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._live.add(iid)
            else:
                self._live.discard(iid)
                for inst, events in self._waiters.values():
                    if inst == iid:
                        events.put(("lost", iid))
            self._changed.notify_all()

    def alive(self) -> list[str]:
        """Instances whose liveliness token is alive now (sorted)."""
        with self._lock:
            return sorted(self._live)

    def discover(self, timeout: float = 1.0) -> list[str]:
        """The instances alive now (sorted): a liveliness query's answers and the subscriber's
        tokens (through a loaded router Zenoh 1.x may answer the query with nothing); with
        neither, waits for the subscriber up to ``timeout`` s."""
        end = time.monotonic() + timeout
        found = set()
        for reply in self._session.liveliness().get(proto.instance_key(self._prefix), timeout=timeout):
            if reply.ok is not None:
                found.add(str(reply.ok.key_expr).rsplit("/", 1)[-1])
        with self._changed:
            self._live |= found
            while not self._live and (left := end - time.monotonic()) > 0:
                self._changed.wait(left)
            return sorted(self._live)

    def wait_for(self, n: int = 1, timeout: float = 5.0) -> list[str]:
        """Block until at least ``n`` instances are alive; returns them (raises ServiceUnavailableError)."""
        end = time.monotonic() + timeout
        with self._changed:
            while len(self._live) < n:
                left = end - time.monotonic()
                if left <= 0:
                    raise ServiceUnavailableError(
                        f"{len(self._live)} instance(s) alive after {timeout} s, wanted {n}"
                    )
                self._changed.wait(left)
            return sorted(self._live)

    def choose(self, exclude: set[str]) -> str | None:
        """The live instance (not in ``exclude``) with the fewest of this client's plans in
        flight, ties in turn; ``None`` when there is none."""
        with self._lock:
            candidates = sorted(self._live - exclude)
            if not candidates:
                return None
            turn = next(self._turn) % len(candidates)
            rotated = candidates[turn:] + candidates[:turn]
            inflight = [iid for iid, _ in self._waiters.values()]  # one waiter per plan in flight
            return min(rotated, key=inflight.count)

    def track(self, iid: str, events: queue.SimpleQueue[Any]) -> int:
        """Count a plan in flight on ``iid`` and tell ``events`` if its token goes; returns a
        handle for :meth:`untrack`."""
        wid = next(self._waiter_ids)
        with self._lock:
            self._waiters[wid] = (iid, events)
        return wid

    def untrack(self, wid: int) -> None:
        """The plan tracked under ``wid`` is no longer in flight."""
        with self._lock:
            self._waiters.pop(wid)
