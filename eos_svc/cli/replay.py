"""``eos replay FILE``: replay a recorded plan and check that it is deterministic.

eos plan --record run.jsonl               # record a run
eos replay run.jsonl                      # print its trace and result, re-run it, compare
eos replay run.jsonl --no-verify          # only print what was recorded
eos replay run.jsonl --picture grasp.png  # and draw the final grasp
eos replay run.jsonl --html plan.html     # and write the plan animated in 3-D (one HTML page)

Record file (JSON lines, written by ``eos plan --record``):

- line 1, the header: ``{"eos_record": "header", "schema": 1, "request": {...}, "hand": "hand3x3"}``
  — the plan request in its JSON form (:meth:`PlanRequest.to_dict`) and the hand's name
  (``hand3x3``, the default, or a ``<name>_hand()`` factory of :mod:`eos_svc.kinematics`);
- one line per cycle: exactly :meth:`CycleRecord.to_dict` (no ``eos_record`` key);
- last line, the result: ``{"eos_record": "result", "result": {...}}`` —
  :meth:`PlanResult.to_dict` without the trace (absent when the run was interrupted).

Verification re-runs the recorded request (same seed) and compares cycle by cycle and then
the result, ignoring only wall-clock fields (``elapsed_s``, ``wall_time_s``). The first
divergence is reported with the cycle, the field path and both values. Exit status: 0 when
identical (or not verified), 1 on a divergence, 2 on a bad file.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from eos_svc.agent import Outcome
from eos_svc.board import BoardChange
from eos_svc.cli.common import fail
from eos_svc.ratings import Weights
from eos_svc.records import AgentRating, CycleRecord

#: version of the record file layout (header / cycles / result)
RECORD_SCHEMA = 1
#: the key marking the header and result lines (cycle lines never have it)
MARK = "eos_record"
#: fields that measure wall-clock time: never compared
TIMING_FIELDS = frozenset({"elapsed_s", "wall_time_s"})
#: the planner's default hand
DEFAULT_HAND = "hand3x3"


# --- writing (used by ``eos plan --record``) ---------------------------------------------
def header_line(request: Any, hand: str = DEFAULT_HAND) -> str:
    """The header line of a record file for ``request`` (a PlanRequest) planned with ``hand``."""
    return json.dumps(
        {MARK: "header", "schema": RECORD_SCHEMA, "request": request.to_dict(), "hand": hand},
        allow_nan=False,
    )


def cycle_line(record: CycleRecord) -> str:
    """One cycle line: :meth:`CycleRecord.to_dict` as JSON."""
    return json.dumps(record.to_dict(), allow_nan=False)


def result_line(result: Any) -> str:
    """The final line: the plan result (a PlanResult) without its trace."""
    return json.dumps({MARK: "result", "result": result.to_dict()}, allow_nan=False)


# --- reading -------------------------------------------------------------------------------
class RecordFileError(ValueError):
    """A record file that cannot be replayed (the message says where and why)."""


class Recording:
    """A parsed record file: the request, the cycle dicts, the result dict (or None), the hand."""

    def __init__(
        self,
        request: dict[str, Any],
        cycles: list[dict[str, Any]],
        result: dict[str, Any] | None,
        hand: str = DEFAULT_HAND,
    ):
        self.request = request
        self.cycles = cycles
        self.result = result
        self.hand = hand


def read_recording(path: str | Path) -> Recording:
    """Parse a record file.

    Raises:
        RecordFileError: unreadable, not JSON lines, no header, unknown schema, cycles out
            of order.
        OSError: the file cannot be opened.
    """
    text = Path(path).read_text(encoding="utf-8")
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]
    if not lines:
        raise RecordFileError("empty file: no header line")
    parsed: list[tuple[int, dict[str, Any]]] = []
    for number, line in lines:
        try:
            value = json.loads(line)
        except json.JSONDecodeError as exc:
            raise RecordFileError(f"line {number}: not JSON ({exc.msg})") from None
        if not isinstance(value, dict):
            raise RecordFileError(f"line {number}: not a JSON object")
        parsed.append((number, value))
    number, header = parsed[0]
    if header.get(MARK) != "header" or not isinstance(header.get("request"), dict):
        raise RecordFileError(
            f"line {number}: no header with the request (record with `eos plan --record FILE`)"
        )
    if header.get("schema") != RECORD_SCHEMA:
        raise RecordFileError(
            f"line {number}: record schema {header.get('schema')!r}, expected {RECORD_SCHEMA}"
        )
    cycles: list[dict[str, Any]] = []
    result = None
    for number, value in parsed[1:]:
        if result is not None:
            raise RecordFileError(f"line {number}: data after the result line")
        if value.get(MARK) == "result":
            result = value.get("result")
            if not isinstance(result, dict):
                raise RecordFileError(f"line {number}: result line without a result object")
            continue
        if MARK in value or "seq" not in value:
            raise RecordFileError(f"line {number}: neither a cycle record nor the result")
        if value["seq"] != len(cycles) + 1:
            raise RecordFileError(
                f"line {number}: cycle {value['seq']!r} out of order (expected {len(cycles) + 1})"
            )
        cycles.append(value)
    hand = header.get("hand", DEFAULT_HAND)
    if not isinstance(hand, str):
        raise RecordFileError(f"line {parsed[0][0]}: hand must be a name, got {hand!r}")
    return Recording(header["request"], cycles, result, hand)


def resolve_hand(name: str) -> Any:
    """The hand model called ``name``: ``None`` (the planner's default) for ``hand3x3``, else
    the result of :mod:`eos_svc.kinematics`' ``<name>_hand()``.

    Raises:
        RecordFileError: no such hand.
    """
    if name == DEFAULT_HAND:
        return None
    import eos_svc.kinematics as kinematics

    factory = getattr(kinematics, f"{name}_hand", None) if name.isidentifier() else None
    if not callable(factory):
        raise RecordFileError(f"unknown hand {name!r}")
    return factory()


def record_from_dict(data: dict[str, Any]) -> CycleRecord:
    """A :class:`CycleRecord` back from its JSON form (board values stay JSON values)."""
    return CycleRecord(
        seq=data["seq"],
        stage=data["stage"],
        stage_cycle=data["stage_cycle"],
        ratings=tuple(
            AgentRating(
                r["agent"],
                r["default"],
                r["opportunistic"],
                r["learned"],
                r["total"],
                r.get("eligible", True),
            )
            for r in data["ratings"]
        ),
        weights=Weights.from_dict(data["weights"]),
        chosen=data["chosen"],
        outcome=None if data["outcome"] is None else Outcome(data["outcome"]),
        detail=data["detail"],
        changes=tuple(BoardChange(c["key"], c["old"], c["new"]) for c in data["changes"]),
        elapsed_s=data["elapsed_s"],
    )


# --- comparing -----------------------------------------------------------------------------
def normalise(value: Any) -> Any:
    """The JSON value as it would be read back from a record file (tuples become lists)."""
    return json.loads(json.dumps(value, allow_nan=False))


def first_difference(recorded: Any, replayed: Any, path: str = "") -> tuple[str, Any, Any] | None:
    """The first differing field between two JSON values, as (dotted path, recorded, replayed),
    ignoring :data:`TIMING_FIELDS`; ``None`` when they agree exactly."""
    if isinstance(recorded, dict) and isinstance(replayed, dict):
        for key in list(recorded) + [k for k in replayed if k not in recorded]:
            if key in TIMING_FIELDS:
                continue
            where = f"{path}.{key}" if path else str(key)
            if key not in recorded or key not in replayed:
                return where, recorded.get(key, "<absent>"), replayed.get(key, "<absent>")
            diff = first_difference(recorded[key], replayed[key], where)
            if diff is not None:
                return diff
        return None
    if isinstance(recorded, list) and isinstance(replayed, list):
        if len(recorded) != len(replayed):
            return f"{path} (length)", len(recorded), len(replayed)
        for i, (a, b) in enumerate(zip(recorded, replayed, strict=True)):
            diff = first_difference(a, b, f"{path}[{i}]")
            if diff is not None:
                return diff
        return None
    if type(recorded) is not type(replayed) or recorded != replayed:
        return path, recorded, replayed
    return None


class Verification:
    """Outcome of a re-run: ``divergences`` lists (where, path, recorded, replayed)."""

    def __init__(self) -> None:
        self.divergences: list[tuple[str, str, Any, Any]] = []
        self.cycles_compared = 0
        self.replayed_result: dict[str, Any] | None = None

    @property
    def identical(self) -> bool:
        return not self.divergences


def verify(recording: Recording) -> Verification:
    """Re-run the recorded request (with the recorded hand) and compare it cycle by cycle,
    then the result.

    Raises:
        RecordFileError: the recorded hand is unknown.
        ValidationError: the recorded request is not valid (any more).
    """
    from eos_svc.agents import PlanRequest, plan  # heavy imports only when verifying
    from eos_svc.agents.pose_board import view_entries_as_recorded

    request = PlanRequest.from_dict(recording.request)
    hand = resolve_hand(recording.hand)
    replayed: list[dict[str, Any]] = []
    result = plan(request, on_cycle=lambda r: replayed.append(normalise(r.to_dict())), hand=hand)
    replayed = view_entries_as_recorded(recording.cycles, replayed)  # older recordings lack hand_q
    out = Verification()
    out.replayed_result = normalise(result.to_dict())
    for recorded, again in zip(recording.cycles, replayed, strict=False):
        out.cycles_compared += 1
        diff = first_difference(recorded, again)
        if diff is not None:
            out.divergences.append((f"cycle {recorded['seq']}", *diff))
    if len(recording.cycles) != len(replayed):
        out.divergences.append(("cycles", "count", len(recording.cycles), len(replayed)))
    if recording.result is not None:
        diff = first_difference(recording.result, out.replayed_result)
        if diff is not None:
            out.divergences.append(("result", *diff))
    return out


def _short(value: Any, limit: int = 160) -> str:
    text = json.dumps(value, ensure_ascii=False) if not isinstance(value, str) else value
    return text if len(text) <= limit else text[: limit - 1] + "…"


def describe(verification: Verification, recording: Recording) -> Iterable[str]:
    """Human lines about a verification."""
    if verification.identical:
        yield (
            f"replay: deterministic — {verification.cycles_compared} cycles and the result are identical "
            f"(timing fields ignored)"
        )
        return
    first = verification.divergences[0]
    yield f"replay: DIVERGED — first at {first[0]}: {first[1]}"
    for where, path, recorded, replayed in verification.divergences[:10]:
        yield f"  {where}: {path}\n    recorded: {_short(recorded)}\n    replayed: {_short(replayed)}"
    if len(verification.divergences) > 10:
        yield f"  … and {len(verification.divergences) - 10} more"
    cycles = [d for d in verification.divergences if d[0].startswith("cycle ")]
    yield f"  {len(cycles)} of {verification.cycles_compared} compared cycles differ"


# --- the command -----------------------------------------------------------------------------
def add_arguments(parser: argparse.ArgumentParser) -> None:
    from eos_svc.cli.view import add_html_argument

    parser.add_argument("file", metavar="FILE", help="a record file written by `eos plan --record FILE`")
    parser.add_argument("--no-verify", action="store_true", help="print the recording without re-running it")
    parser.add_argument("--quiet", action="store_true", help="no trace, only the result and the verdict")
    parser.add_argument("--picture", metavar="PNG", help="draw the final grasp to PNG")
    add_html_argument(parser)  # --html (3-D page of the plan)


def run(args: argparse.Namespace) -> int:
    from eos_svc.cli.plan import format_cycle, format_result

    try:
        recording = read_recording(args.file)
    except OSError as exc:
        fail(f"FILE: cannot read {args.file!r}: {exc.strerror}")
    except RecordFileError as exc:
        fail(f"FILE: {args.file}: {exc}")
    if not args.quiet:
        for data in recording.cycles:
            print(format_cycle(record_from_dict(data)))
    if recording.result is not None:
        print(format_result(SimpleNamespace(**recording.result)))
    else:
        print(f"no result line: the recorded run was interrupted after {len(recording.cycles)} cycles")
    code = 0
    final = recording.result
    if not args.no_verify:
        from eos_svc.errors import ValidationError

        try:
            verification = verify(recording)
        except ValidationError as exc:
            fail(f"FILE: the recorded request is not valid here: {exc}")
        except RecordFileError as exc:
            fail(f"FILE: {args.file}: {exc}")
        for line in describe(verification, recording):
            print(line)
        code = 0 if verification.identical else 1
        final = final or verification.replayed_result
    if args.picture:
        from eos_svc.agents.picture import draw_result

        if final is None or final.get("q_final") is None:
            fail("--picture: no final hand configuration in the recording (the end agent never acted)")
        try:
            hand = resolve_hand(recording.hand)
        except RecordFileError as exc:
            fail(f"FILE: {args.file}: {exc}")
        draw_result(final, args.picture, hand=hand)
        print(f"picture: {args.picture}")
    if getattr(args, "html", None):  # --html FILE: the recorded plan in 3-D
        from eos_svc.cli.view import write_recording_html

        try:
            hand = resolve_hand(recording.hand)
        except RecordFileError as exc:
            fail(f"FILE: {args.file}: {exc}")
        write_recording_html(args.html, recording, final, hand)
        print(f"html: {args.html}")
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(run(argparse.Namespace()))
