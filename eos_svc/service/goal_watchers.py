"""Whether anyone watches the goals (a subscriber matching ``P/goal/*/*``, read from a publisher
never used to put): the service builds no message nobody would receive.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import zenoh

from eos_svc.service import protocol as proto
from eos_svc.service.session import direct_callback


class GoalWatchers:
    """Whether any subscriber matches ``P/goal/*/*``, from a publisher declared there and never
    used to put (the reasoning: ``docs/service.md``, "Key expressions and messages").

    - :meth:`now`: the publisher's matching status read from Zenoh's routing tables (exact).
    - :attr:`any`: a bool free to read before every cycle. A "matching" notice sets it at once;
      a "nobody" notice calls ``on_notice`` (the service's dispatcher then runs :meth:`refresh`,
      which sets it from the tables). So it turns false only from an exact reading, never from a
      notice Zenoh delivered late or out of order.
    - :meth:`watched`: the choice at a plan's start, from the request's ``watch`` hint.
    """

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
        """Set :attr:`any` to the routing tables' answer now (from our threads, never Zenoh's).
        One reading at a time (a lock: an older "nobody" never overwrites a newer "matching"); a
        "matching" notice during the reading makes it read again."""
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
