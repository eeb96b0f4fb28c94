"""What a batch tells its user: a progress bar while it runs and a summary at the end."""

from __future__ import annotations

import statistics
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import IO, Any


class ProgressBar:
    """A one-line progress bar on a terminal (redrawn at most every ``interval`` s); on anything
    else (a log file, CI) one plain line every ``log_interval`` s and at the end.

    Args:
        total: rows this run will plan.
        skipped: rows already done before this run (shown, not counted in the rate).
        stream: where to draw (stderr).
    """

    WIDTH = 30

    def __init__(
        self,
        total: int,
        skipped: int = 0,
        stream: IO[str] | None = None,
        interval: float = 0.2,
        log_interval: float = 30.0,
    ) -> None:
        self.total, self.skipped, self.done, self.good = total, skipped, 0, 0
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval = interval if self.tty else log_interval
        self.started = time.perf_counter()
        self._drawn = -float("inf")

    def update(self, rows: list[dict[str, Any]]) -> None:
        """Count finished rows and redraw when due."""
        self.done += len(rows)
        self.good += sum(1 for r in rows if r["good_grasp"])
        now = time.perf_counter()
        if now - self._drawn >= self.interval:
            self._draw(now)

    def close(self) -> None:
        """The final state, then a new line."""
        self._draw(time.perf_counter())
        if self.tty:
            self.stream.write("\n")
        self.stream.flush()

    def line(self, now: float) -> str:
        """The bar's text: done/total, good grasps, rate and time left."""
        elapsed = max(now - self.started, 1e-9)
        rate = self.done / elapsed
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        frac = self.done / self.total if self.total else 1.0
        filled = round(frac * self.WIDTH)
        eta = "?" if left == float("inf") else _duration(left)
        skipped = f" (+{self.skipped} done before)" if self.skipped else ""
        return (
            f"[{'#' * filled}{'.' * (self.WIDTH - filled)}] {self.done}/{self.total}{skipped} "
            f"good {self.good} · {rate:.1f} plans/s · left {eta}"
        )

    def _draw(self, now: float) -> None:
        self._drawn = now
        self.stream.write(("\r" if self.tty else "") + self.line(now) + ("" if self.tty else "\n"))
        self.stream.flush()


@dataclass
class BatchSummary:
    """What a batch run did (this run's rows only, and how many were done before)."""

    planned: int = 0  #: rows written by this run
    skipped: int = 0  #: keys done before this run
    lost: int = 0  #: keys whose task failed after every retry (a rerun plans them)
    files: int = 0  #: Parquet files written by this run
    wall_s: float = 0.0
    workers: float = 0.0  #: CPUs of the Ray cluster
    statuses: Counter[str] = field(default_factory=Counter)
    good: int = 0
    validated: int = 0
    held: int = 0
    plan_s: list[float] = field(default_factory=list, repr=False)
    validation_s: list[float] = field(default_factory=list, repr=False)

    def add(self, rows: list[dict[str, Any]]) -> None:
        """Count finished rows."""
        for r in rows:
            self.planned += 1
            self.statuses[r["status"]] += 1
            self.good += bool(r["good_grasp"])
            if r["plan_s"]:
                self.plan_s.append(r["plan_s"])
            if r["held"] is not None:
                self.validated += 1
                self.held += bool(r["held"])
                self.validation_s.append(r["validation_s"])

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (``eos batch --json``)."""
        return {
            "planned": self.planned,
            "skipped": self.skipped,
            "lost": self.lost,
            "files": self.files,
            "wall_s": self.wall_s,
            "workers": self.workers,
            "statuses": dict(self.statuses),
            "good_grasps": self.good,
            "validated": self.validated,
            "held": self.held,
            "median_plan_s": statistics.median(self.plan_s) if self.plan_s else None,
            "median_validation_s": statistics.median(self.validation_s) if self.validation_s else None,
            "plans_per_s": self.planned / self.wall_s if self.wall_s > 0 else None,
        }

    def format(self) -> str:
        """A few readable lines."""
        d = self.to_dict()
        lines = [
            f"planned {self.planned} (skipped {self.skipped} done before, lost {self.lost}) "
            f"in {_duration(self.wall_s)} on {self.workers:g} CPUs, {self.files} files",
            "statuses: " + (", ".join(f"{k} {v}" for k, v in sorted(self.statuses.items())) or "none"),
            f"good grasps: {self.good}/{self.planned}",
        ]
        if d["median_plan_s"] is not None:
            rate = d["plans_per_s"] or 0.0
            lines.append(f"median plan {d['median_plan_s'] * 1000:.1f} ms, {rate:.2f} plans/s")
        if self.validated:
            lines.append(
                f"validated {self.validated}: held {self.held}, median {d['median_validation_s']:.2f} s"
            )
        if self.lost:
            lines.append(
                f"{self.lost} plans lost to failed workers after every retry: run again to plan them"
            )
        return "\n".join(lines)


def _duration(seconds: float) -> str:
    """``1h02m``, ``3m07s`` or ``4.2s``."""
    if seconds >= 3600:
        return f"{int(seconds // 3600)}h{int(seconds % 3600 // 60):02d}m"
    if seconds >= 60:
        return f"{int(seconds // 60)}m{int(seconds % 60):02d}s"
    return f"{seconds:.1f}s"
