"""Tiny timing harness shared by the benchmarks: medians over repeated runs, a long-lived
child interpreter on another tree, a git revision exported to a folder."""

from __future__ import annotations

import gc
import statistics
import subprocess
import sys
import tarfile
import time
from collections.abc import Callable
from pathlib import Path

#: the repository (the benchmarks' parent folder)
ROOT = Path(__file__).resolve().parents[1]


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


class ScriptChild:
    """A fresh interpreter running ``script`` with ``eos_svc`` imported from ``tree`` and
    ``argument`` as its ``sys.argv[1]``; the script prints ``ready`` once set up, then one line
    for each line it reads (:meth:`ask`)."""

    def __init__(self, tree: str, script: str, argument: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-c", script, argument],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=tree,
            env={"PYTHONPATH": tree, "PATH": "/usr/bin:/bin"},
        )
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.stdin, self.stdout = self.proc.stdin, self.proc.stdout
        if self.stdout.readline().strip() != "ready":
            raise RuntimeError(f"the child on {tree} failed to start")

    def ask(self, line: str) -> str:
        """Send ``line``, return the child's answer."""
        self.stdin.write(f"{line}\n")
        self.stdin.flush()
        answer = self.stdout.readline()
        if not answer:
            raise RuntimeError("a child died")
        return answer

    def close(self) -> None:
        """End the child."""
        self.stdin.close()
        self.proc.wait()


def export_revision(rev: str, folder: str) -> bool:
    """``eos_svc`` and ``urdf`` of git revision ``rev`` into ``folder`` (False when git cannot)."""
    archive = Path(folder) / "rev.tar"
    done = subprocess.run(
        ["git", "-C", str(ROOT), "archive", "-o", str(archive), rev, "eos_svc", "urdf"], capture_output=True
    )
    if done.returncode != 0:
        return False
    with tarfile.open(archive) as tar:
        tar.extractall(folder, filter="data")
    return True
