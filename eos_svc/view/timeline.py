"""A plan's cycles as an animation timeline: where the hand is at which frame, what each cycle did.

Built from cycle records' JSON form (``hand_q`` after each move, ``hand_path`` of each EP1 roll);
each cycle gets at least :data:`CYCLE_FRAMES` frames, a move is split into keyframes of at most
:data:`MAX_STEP_RAD` per joint and :data:`MAX_STEP_M` of wrist travel.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from eos_svc.schema import keys

#: animation frames per second
FPS = 16
#: frames of a cycle (the least; a long move or a roll takes more)
CYCLE_FRAMES = 4
#: frames per EP1 roll sample
PATH_FRAMES = 2
#: largest joint change (rad) and wrist travel (m) between two keyframes
MAX_STEP_RAD = 0.15
MAX_STEP_M = 0.01


@dataclass(frozen=True)
class CycleSpan:
    """One cycle on the timeline: frames [start, end] and what happened."""

    seq: int
    stage: str
    chosen: str | None
    outcome: str | None
    detail: str
    start: int
    end: int

    def to_dict(self, fps: int) -> dict[str, Any]:
        """JSON form for the page (times ``t0``, ``t1`` in s)."""
        what = {k: v for k, v in asdict(self).items() if k not in ("start", "end")}
        return {**what, "t0": self.start / fps, "t1": self.end / fps}


@dataclass
class Timeline:
    """Keyframes ``(frame, q)`` of the hand in frame order, one span per cycle, ``(frame,
    postulate)`` at the end of every cycle that wrote ``keys.SHAPE``, ``(frame, verdict)`` of the
    end agent's ``keys.OUTCOME`` (or None), at ``fps`` frames per second."""

    keyframes: list[tuple[int, tuple[float, ...]]] = field(default_factory=list)
    spans: list[CycleSpan] = field(default_factory=list)
    postulates: list[tuple[int, Any]] = field(default_factory=list)
    verdict: tuple[int, Any] | None = None
    fps: int = FPS

    @property
    def frames(self) -> int:
        """The last frame."""
        last_key = self.keyframes[-1][0] if self.keyframes else 0
        last_span = self.spans[-1].end if self.spans else 0
        return max(last_key, last_span)

    @property
    def duration_s(self) -> float:
        """Length of the animation, s."""
        return self.frames / self.fps

    def span_end_s(self, seq: int) -> float:
        """Time at the end of cycle ``seq`` (s); KeyError when there is no such cycle."""
        for span in self.spans:
            if span.seq == seq:
                return span.end / self.fps
        raise KeyError(seq)


def _steps_between(a: Sequence[float], b: Sequence[float]) -> int:
    """How many keyframes a move from ``a`` to ``b`` needs (≥ 1): wrist x, y, z are the first
    three entries (m), every other entry an angle (rad). A pure wrist translation needs one
    (every body translates with the wrist: interpolating their poses is exact)."""
    if a[3:] == b[3:]:
        return 1
    travel = math.sqrt(sum((b[i] - a[i]) ** 2 for i in range(min(3, len(a)))))
    turn = max(abs(y - x) for x, y in zip(a[3:], b[3:], strict=True))
    return max(1, math.ceil(travel / MAX_STEP_M - 1e-9), math.ceil(turn / MAX_STEP_RAD - 1e-9))


def _lerp(a: Sequence[float], b: Sequence[float], s: float) -> tuple[float, ...]:
    return tuple(x + s * (y - x) for x, y in zip(a, b, strict=True))


def as_q(value: Any, nq: int) -> tuple[float, ...] | None:
    """A configuration from a board value, or None when it is not one of length ``nq``."""
    if not isinstance(value, (list, tuple)) or len(value) != nq:
        return None
    try:
        q = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        return None
    return q if all(math.isfinite(x) for x in q) else None


def changes_of(record: Mapping[str, Any]) -> dict[str, Any]:
    """The board entries a cycle record (JSON form) wrote: key -> new value."""
    return {
        c["key"]: c.get("new")
        for c in record.get("changes") or ()
        if isinstance(c, Mapping) and isinstance(c.get("key"), str)
    }


class TimelineBuilder:
    """Builds a :class:`Timeline` cycle by cycle, the hand at ``q0`` before the first."""

    def __init__(self, q0: Sequence[float] | Any, fps: int = FPS) -> None:
        self.q = tuple(float(x) for x in q0)
        self.timeline = Timeline(keyframes=[(0, self.q)], fps=fps)
        self.frame = 0

    def _move_to(self, target: tuple[float, ...], least_frames: int) -> None:
        tl = self.timeline
        if target == self.q:
            return
        if tl.keyframes[-1][0] < self.frame:  # hold until the move starts
            tl.keyframes.append((self.frame, self.q))
        steps = _steps_between(self.q, target)
        frames = max(least_frames, steps)
        for k in range(1, steps + 1):
            at = self.frame + round(k * frames / steps)
            tl.keyframes.append((at, target if k == steps else _lerp(self.q, target, k / steps)))
        self.frame += frames
        self.q = target

    def add(self, record: Mapping[str, Any]) -> CycleSpan:
        """Add one cycle (JSON form); returns its span."""
        nq = len(self.q)
        written = changes_of(record)
        start = self.frame
        path = written.get(keys.HAND_PATH)
        waypoints: list[tuple[float, ...]] = []
        if isinstance(path, list):
            waypoints.extend(q for q in (as_q(p, nq) for p in path) if q is not None)
        end_q = as_q(written.get(keys.HAND_Q), nq)
        if end_q is not None:
            waypoints.append(end_q)
        for i, q in enumerate(waypoints):
            self._move_to(q, CYCLE_FRAMES if i == 0 else PATH_FRAMES)
        self.frame = max(self.frame, start + CYCLE_FRAMES)
        outcome = record.get("outcome")
        span = CycleSpan(
            seq=int(record.get("seq", len(self.timeline.spans) + 1)),
            stage=str(record.get("stage", "")),
            chosen=record.get("chosen"),
            outcome=None if outcome is None else str(outcome),
            detail=str(record.get("detail", "")),
            start=start,
            end=self.frame,
        )
        tl = self.timeline
        tl.spans.append(span)
        if keys.SHAPE in written:  # shown once the cycle that postulated it is done
            tl.postulates.append((self.frame, written[keys.SHAPE]))
        verdict = written.get(keys.OUTCOME)
        if isinstance(verdict, Mapping):
            tl.verdict = (self.frame, verdict)
        return span


def build_timeline(
    records: Iterable[Mapping[str, Any]], q0: Sequence[float] | Any, fps: int = FPS
) -> Timeline:
    """The timeline of a plan's cycle records (JSON form), the hand starting at ``q0``."""
    builder = TimelineBuilder(q0, fps)
    for record in records:
        builder.add(record)
    return builder.timeline
