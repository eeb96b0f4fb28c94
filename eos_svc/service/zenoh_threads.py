"""Python callbacks in Zenoh's own threads, without a Python thread state made and freed per call.

Zenoh runs a callback in one of its Rust threads (zenoh-python, through pyo3). Such a thread has
no Python thread state of its own, so every call makes one (``PyGILState_Ensure``) and frees it
again on return (``PyGILState_Release``). When the callback is Python code, its first frame also
maps a fresh 16 KiB frame stack (``mmap``) that is unmapped when the state is freed (``munmap``,
which on a multi-CPU machine flushes the other CPUs' TLBs with an interrupt). On a 2-vCPU VM that
costs ≈ 55–80 µs a callback — a service's plan query, a client's cycle samples.

:func:`keep_thread_state`, called once in such a thread while it holds the GIL, takes one more
reference on the thread's state (``PyGILState_Ensure`` never released), so pyo3's release after
each callback only lets the GIL go and the state, its frame stack and its ``threading.local``
values stay for the next call. :func:`kept_thread_state` wraps a Python callback so that it does
this on its first call in each thread. The state of each Zenoh thread then lives as long as the
thread (a few kB each; Zenoh's runtime keeps a fixed pool of threads).

Interpreters without ``ctypes.pythonapi`` (not CPython) get the plain behaviour.
"""

from __future__ import annotations

import ctypes
import threading
from collections.abc import Callable
from typing import Any

#: ``kept`` is set in a thread once its state is kept: a thread-local value lives exactly as
#: long as the thread state it belongs to (unlike a set of thread idents, which the OS reuses)
_LOCAL = threading.local()
try:
    _ensure: Callable[[], int] | None = ctypes.pythonapi.PyGILState_Ensure
except AttributeError:  # pragma: no cover - not CPython
    _ensure = None


def keep_thread_state() -> None:
    """Keep the calling thread's Python thread state after the current callback returns (once
    per thread; the caller holds the GIL, as any Python code does). Harmless in a thread Python
    started: its state lives as long as the thread anyway."""
    if _ensure is None or getattr(_LOCAL, "kept", False):
        return
    _ensure()  # one more reference on this thread's state, never released
    _LOCAL.kept = True


def kept_thread_state(callback: Callable[..., Any]) -> Callable[..., Any]:
    """``callback`` (one argument, or none for a drop callback) that first keeps the thread
    state of the Zenoh thread running it (:func:`keep_thread_state`)."""
    local = _LOCAL

    def call(*args: Any) -> Any:
        if not getattr(local, "kept", False):
            keep_thread_state()
        return callback(*args)

    call.__wrapped__ = callback  # type: ignore[attr-defined]
    return call
