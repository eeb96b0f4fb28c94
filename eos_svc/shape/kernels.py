"""Whether the fit's compiled kernels (:mod:`eos_svc.shape.compiled`) are ready in this process,
and getting them ready without making a fit wait.

Compiling the kernels takes ≈ 11 s the first time (numba, then cached on disk), importing numba
and loading them from the cache ≈ 1 s — more than a plan's deadline allows, or far more than
they save a single plan (its fits: 15–45 ms in numpy, a third of that compiled). So the fit
asks :func:`ready` at every evaluation and, until the kernels are ready, evaluates with its
numpy reference, which gives the same bits (``tests/shape/test_compiled.py``): the switch
changes how fast a fit runs, never what it finds. A process that keeps fitting — past
:data:`LOAD_AFTER` evaluations, a few plans — loads the kernels in a background thread; a
one-shot ``eos plan`` never imports numba. A service starts loading them at start
(:func:`load_in_background`), so that its requests run compiled within a second or two (the
first compilation on a new install: ≈ 11 s) without delaying its start; ``eos experiment`` and
the benchmarks load them before their first plan (:func:`load`).
"""

from __future__ import annotations

import threading

#: evaluations in numpy after which the kernels are loaded in the background (a few plans)
LOAD_AFTER = 500

_ready = threading.Event()
_lock = threading.Lock()
_loader: threading.Thread | None = None
_asked = 0
#: what stopped the background load, if anything did (the fit then stays on numpy)
error: BaseException | None = None


def ready() -> bool:
    """Whether the compiled kernels are ready; the :data:`LOAD_AFTER`-th call starts loading
    them in the background (a thread that the interpreter waits for at exit, so that a
    compilation is never cut short while numba writes its cache)."""
    if _ready.is_set():
        return True
    global _asked, _loader
    _asked += 1
    if _asked >= LOAD_AFTER and _loader is None:
        load_in_background()
    return False


def load_in_background() -> None:
    """Start loading (or compiling) the kernels in a background thread, once per process; the
    fit switches to them when they are ready. The interpreter waits for the thread at exit, so
    that a compilation is never cut short while numba writes its cache."""
    global _loader
    with _lock:
        if _loader is None and not _ready.is_set():
            _loader = threading.Thread(target=_load_quietly, name="eos-shape-kernels")
            _loader.start()


def load() -> None:
    """Load (or compile) the kernels now, in the calling thread; then :func:`ready` is true."""
    from eos_svc.shape import compiled  # numba: imported here, not with the package

    compiled.warm_up()  # sets the ready flag (mark_ready)


def mark_ready() -> None:
    """Called by :func:`eos_svc.shape.compiled.warm_up` once every kernel is loaded."""
    _ready.set()


def _load_quietly() -> None:
    global error
    try:
        load()
    except Exception as exc:  # the fit goes on with its numpy reference
        error = exc
