"""Python callbacks in Zenoh's threads keep their thread state (eos_svc.service.zenoh_threads)."""

from __future__ import annotations

import functools
import json
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import zenoh

from eos_svc.service import free_port, loopback, make_config
from eos_svc.service.session import direct_callback
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


def _compare_in_this_process() -> dict[str, Any]:
    """Plain callbacks first (no Zenoh thread's state kept yet), then ``direct_callback``'s."""
    plain = _run(lambda f: zenoh.handlers.Callback(f, indirect=False))
    kept = _run(direct_callback)
    return {
        "plain": [[p.decode() for p in plain[0]], list(plain[1].values()), plain[2]],
        "kept": [[p.decode() for p in kept[0]], list(kept[1].values()), kept[2]],
    }


def test_a_python_callback_keeps_its_zenoh_thread_state_and_gets_the_same_samples():
    # in a fresh interpreter: Zenoh's threads are shared by every session of a process, and an
    # earlier test's callbacks would already have kept their states
    script = "import json; from tests.service.test_zenoh_threads import _compare_in_this_process as c; "
    script += "print(json.dumps(c()))"
    out = subprocess.run(
        [sys.executable, "-c", script],
        cwd=Path(__file__).resolve().parents[2],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    result = json.loads(out.stdout.strip().splitlines()[-1])
    (plain_payloads, plain_counts, plain_faults), (kept_payloads, kept_counts, kept_faults) = (
        result["plain"],
        result["kept"],
    )
    # the same samples, in the same order, either way
    assert kept_payloads == plain_payloads == [str(i) for i in range(N)]
    # plain: every call starts from a fresh thread state (its threading.local is empty again)...
    assert all(seen == [1] * len(seen) for seen in plain_counts)
    # ...kept: each Zenoh thread's state, and its threading.local, lives from call to call
    assert all(seen == list(range(1, len(seen) + 1)) for seen in kept_counts)
    assert sum(len(seen) for seen in kept_counts) == N
    # and no fresh frame stack is mapped (and faulted in) per call
    assert plain_faults >= N // 2
    assert kept_faults < plain_faults // 4


def test_only_callables_that_run_python_are_wrapped():
    q: queue.SimpleQueue[Any] = queue.SimpleQueue()
    put = q.put
    end = functools.partial(q.put, None)
    handler = direct_callback(put, end)
    assert handler.callback is put and handler.drop is end  # built-ins run no Python frame: as they are

    def f(x: Any) -> None:
        q.put(x)

    class Recorder:
        def __call__(self, x: Any) -> None:
            q.put(("instance", x))

    handler = direct_callback(f, lambda: q.put("dropped"))
    assert handler.callback is not f and handler.callback.__wrapped__ is f
    handler.callback(3)
    handler.drop()
    assert [q.get_nowait(), q.get_nowait()] == [3, "dropped"]
    for runs_python in (functools.partial(f), Recorder()):  # Python code behind other callables
        handler = direct_callback(runs_python)
        assert handler.callback is not runs_python and handler.callback.__wrapped__ is runs_python
        handler.callback(4)
    assert [q.get_nowait(), q.get_nowait()] == [4, ("instance", 4)]
    assert kept_thread_state(lambda: 7)() == 7
