"""Python callbacks in Zenoh's threads keep their thread state (eos_svc.service.zenoh_threads)."""

from __future__ import annotations

import queue
import threading
import time
from typing import Any

import zenoh

from eos_svc.service import free_port, loopback, make_config
from eos_svc.service.session import _kept_if_python, direct_callback
from eos_svc.service.zenoh_threads import kept_thread_state

N = 200


def _minor_faults() -> int:
    with open("/proc/self/stat") as f:
        return int(f.read().rsplit(")", 1)[1].split()[7])


def _run(handler_of: Any) -> tuple[list[bytes], dict[int, list[int]], int]:
    """Publish N samples to a subscriber whose Python callback counts its calls in a
    ``threading.local``; returns the payloads received, the counts seen per Zenoh thread, and the
    minor page faults of this process meanwhile."""
    port = free_port()
    sub_session = zenoh.open(make_config(listen=[loopback(port)]))
    pub_session = zenoh.open(make_config(connect=[loopback(port)]))
    local = threading.local()
    payloads: list[bytes] = []
    counts: dict[int, list[int]] = {}
    done: queue.SimpleQueue[None] = queue.SimpleQueue()

    def on_sample(sample: zenoh.Sample) -> None:
        local.n = getattr(local, "n", 0) + 1
        counts.setdefault(threading.get_ident(), []).append(local.n)
        payloads.append(sample.payload.to_bytes())
        if len(payloads) == N:
            done.put(None)

    try:
        sub = sub_session.declare_subscriber("test/kept", handler_of(on_sample))
        time.sleep(0.3)
        faults = _minor_faults()
        for i in range(N):
            pub_session.put("test/kept", str(i).encode())
            time.sleep(0.0005)
        done.get(timeout=10)
        faults = _minor_faults() - faults
        sub.undeclare()
    finally:
        pub_session.close()
        sub_session.close()
    return payloads, counts, faults


def test_a_python_callback_keeps_its_zenoh_thread_state_and_gets_the_same_samples():
    plain_payloads, plain_counts, plain_faults = _run(lambda f: zenoh.handlers.Callback(f, indirect=False))
    kept_payloads, kept_counts, kept_faults = _run(direct_callback)
    # the same samples, in the same order, either way
    assert kept_payloads == plain_payloads == [str(i).encode() for i in range(N)]
    # plain: every call starts from a fresh thread state (its threading.local is empty again)...
    assert all(seen == [1] * len(seen) for seen in plain_counts.values())
    # ...kept: each Zenoh thread's state, and its threading.local, lives from call to call
    assert all(seen == list(range(1, len(seen) + 1)) for seen in kept_counts.values())
    assert sum(len(seen) for seen in kept_counts.values()) == N
    # and no fresh frame stack is mapped (and faulted in) per call
    assert plain_faults >= N // 2
    assert kept_faults < plain_faults // 4


def test_only_python_callables_are_wrapped():
    q: queue.SimpleQueue[Any] = queue.SimpleQueue()
    put = q.put
    assert _kept_if_python(put) is put  # a built-in runs no Python frame: left as it is

    def f(x: Any) -> None:
        q.put(x)

    wrapped = _kept_if_python(f)
    assert wrapped is not f and wrapped.__wrapped__ is f  # type: ignore[attr-defined]
    wrapped(3)
    assert q.get_nowait() == 3
    assert kept_thread_state(lambda: 7)() == 7  # a drop callback: no argument
