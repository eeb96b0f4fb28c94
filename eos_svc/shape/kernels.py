"""The one seam that chooses how the fit's residuals are computed: numpy (the default) or the
compiled loop of :mod:`eos_svc.shape.compiled` (numba, the ``fast`` extra) once :func:`load`
has run in this process (≈ 1 s from numba's cache: the service, ``eos experiment``, the
benchmarks load it; ``docs/objects.md``). Both agree to rounding (``tests/shape/test_compiled.py``).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

#: each kind's code in the compiled loop
KIND_CODES = {"sphere": 0, "ellipsoid": 1, "box": 2, "cylinder": 3, "capsule": 4}
#: the compiled residuals once loaded in this process (the state of numba's JIT, which is per
#: process anyway); None: the fit runs in numpy
_loaded: list[Callable[..., Any]] = []
_lock = threading.Lock()


def compiled_residuals() -> Callable[..., Any] | None:
    """:func:`eos_svc.shape.compiled.residuals` if :func:`load` has run in this process, else None."""
    return _loaded[0] if _loaded else None


def load() -> bool:
    """Load (compiling on first use) the compiled residuals now; False when numba is missing
    (the fit stays on numpy)."""
    with _lock:
        if _loaded:
            return True
        try:
            from eos_svc.shape import compiled  # numba: imported here, never with the package
        except ImportError:
            return False
        compiled.warm_up()
        _loaded.append(compiled.residuals)
        return True


def load_in_background() -> threading.Thread:
    """:func:`load` in a thread (the fit switches to the compiled residuals when it is done)."""
    thread = threading.Thread(target=load, name="eos-shape-kernels", daemon=False)
    thread.start()
    return thread


def unload() -> None:
    """Go back to the numpy residuals in this process (tests comparing the two)."""
    with _lock:
        _loaded.clear()
