"""Tiny timing harness shared by the benchmarks: medians over repeated runs."""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable


def median_time(fn: Callable[[], object], *, inner: int, repeats: int = 15, warmup: int = 2) -> float:
    """Median over ``repeats`` of the mean time of one call, each repeat timing ``inner`` calls (s)."""
    for _ in range(warmup):
        for _ in range(inner):
            fn()
    samples = []
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        for _ in range(repeats):
            t0 = time.perf_counter()
            for _ in range(inner):
                fn()
            samples.append((time.perf_counter() - t0) / inner)
    finally:
        if gc_was_enabled:
            gc.enable()
    return statistics.median(samples)


def median_of(samples: list[float]) -> float:
    """Median of a list of timings (s)."""
    return statistics.median(samples)


def fmt_us(seconds: float) -> str:
    """Seconds as a right-aligned microsecond string."""
    return f"{seconds * 1e6:9.2f} µs"


def table(rows: list[tuple[str, float, float | None]], baseline_name: str) -> str:
    """Rows (name, seconds, ratio to baseline) as an aligned text table."""
    width = max(len(name) for name, _, _ in rows)
    lines = [f"{'what':<{width}}  {'median':>12}  ratio vs {baseline_name}"]
    for name, seconds, ratio in rows:
        ratio_text = "" if ratio is None else f"{ratio:8.3f}x"
        lines.append(f"{name:<{width}}  {fmt_us(seconds)}  {ratio_text}")
    return "\n".join(lines)
