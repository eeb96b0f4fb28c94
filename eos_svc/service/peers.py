"""The other live instances of the service (their liveliness tokens): a plan query on ``P/plan/*``
reaches every instance it matches; only the first by id answers, naming the keys to use.
"""

from __future__ import annotations

import threading

import zenoh

from eos_svc.service import protocol as proto


class PeerInstances:
    """The instance ids whose liveliness token is alive (fed by :meth:`on_token`, a Zenoh callback)."""

    def __init__(self, prefix: str, instance: str) -> None:
        self.prefix = prefix
        self.instance = instance
        self._peers: set[str] = set()
        self._lock = threading.Lock()

    def on_token(self, sample: zenoh.Sample) -> None:
        """A token came or went (in Zenoh's thread: never blocks, never calls Zenoh)."""
        iid = str(sample.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._peers.add(iid)
            else:
                self._peers.discard(iid)

    def wildcard_refusal(self, key: zenoh.KeyExpr) -> proto.RequestError | None:
        """The one answer to a plan query on ``key`` (not exactly this instance's), or ``None``
        to stay silent (another instance it names answers)."""
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
