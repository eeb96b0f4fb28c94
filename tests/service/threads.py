"""Running one test function in several threads at once."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from typing import Any


def run_in_threads(
    target: Callable[[Any], object], args: Iterable[Any], timeout: float, stagger: float = 0.0
) -> None:
    """Call ``target(arg)`` for every ``arg``, each in a thread of its own, started ``stagger``
    seconds apart; then wait up to ``timeout`` seconds for each thread in turn."""
    threads = [threading.Thread(target=target, args=(arg,)) for arg in args]
    for t in threads:
        t.start()
        if stagger:
            time.sleep(stagger)
    for t in threads:
        t.join(timeout)
