"""What one goal publishes while it runs: its ``running`` status, every cycle, its ``done`` status,
built and put only while someone watches (cycles numbered all the same), with
``CongestionControl.DROP``: a slow subscriber loses messages alone (``docs/service.md``).
"""

from __future__ import annotations

from typing import Any

import zenoh

from eos_svc.records import CycleRecord
from eos_svc.service import protocol as proto
from eos_svc.service.goal_watchers import GoalWatchers
from eos_svc.service.wire_json import encode_result

_JSON = zenoh.Encoding.APPLICATION_JSON
#: a message a watcher's full queue cannot take is dropped for that watcher alone, never waited for
_DROP = zenoh.CongestionControl.DROP


class GoalStream:
    """The messages of goal ``goal_id`` on ``instance``, ``watched`` from its start or not
    (:meth:`GoalWatchers.watched`), later while ``watchers`` says anyone watches."""

    def __init__(
        self,
        session: zenoh.Session,
        prefix: str,
        instance: str,
        goal_id: str,
        watchers: GoalWatchers,
        watched: bool,
    ) -> None:
        self._session = session
        self._watchers = watchers
        self._watched = watched
        self._cycle_key = proto.cycle_key(prefix, goal_id)
        self._status_key = proto.status_key(prefix, goal_id)
        self.head = {"schema": proto.SCHEMA_VERSION, "goal_id": goal_id, "instance": instance}
        #: cycles numbered so far (published or, with nobody watching, skipped)
        self.seq = 0
        #: cycles put on the wire
        self.sent = 0

    @property
    def watched(self) -> bool:
        """Whether anyone watches this goal's messages now."""
        return self._watched or self._watchers.any

    def running(self, request: dict[str, Any]) -> None:
        """The ``running`` status, with the request (a watcher can draw the object); only when
        watched from the start."""
        if self._watched:
            self._put(self._status_key, {**self.head, "state": proto.STATE_RUNNING, "request": request})

    def cycle(self, record: CycleRecord | Any) -> None:
        """Number a cycle, and publish it while watched."""
        self.seq += 1
        if not self.watched:
            return
        body = record.to_dict() if hasattr(record, "to_dict") else record
        self._put(self._cycle_key, {**self.head, "seq": self.seq, "record": body})
        self.sent += 1

    def done(self, message: bytes, always: bool = False) -> None:
        """Publish the ``done`` status (``message``: its JSON) while watched, or ``always``."""
        if always or self.watched:
            self._session.put(self._status_key, message, encoding=_JSON, congestion_control=_DROP)

    def done_message(self, **fields: Any) -> bytes:
        """The JSON of the ``done`` status with ``fields`` (``status``, ``cycles``, ``result``)."""
        return encode_result({**self.head, "state": proto.STATE_DONE, **fields})

    def _put(self, key: str, message: dict[str, Any]) -> None:
        self._session.put(key, encode_result(message), encoding=_JSON, congestion_control=_DROP)
