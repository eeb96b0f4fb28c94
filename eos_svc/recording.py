"""The record file of a plan (JSON lines: a header, one :meth:`CycleRecord.to_dict` per cycle, the
result; ``docs/planner.md``), written by ``eos plan --record`` and read by ``eos replay``;
:func:`compare_run` compares two runs, ignoring wall-clock fields and :data:`ADDED_FIELDS`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from eos_svc.agent import Outcome
from eos_svc.board import BoardChange
from eos_svc.errors import EosError
from eos_svc.ratings import Weights
from eos_svc.records import AgentRating, CycleRecord

#: version of the record file layout (header / cycles / result)
RECORD_SCHEMA = 1
#: the key marking the header and result lines (cycle lines never have it)
MARK = "eos_record"
#: fields that measure wall-clock time: never compared (a simulated world's own wall time and
#: real-time factor among them)
TIMING_FIELDS = frozenset({"elapsed_s", "wall_time_s", "latency_s", "simulation_wall_s", "real_time_factor"})
#: fields added to the cycle record since its first form: a record written before them lacks
#: them, and a replay that has them does not diverge for that alone
ADDED_FIELDS = frozenset({"where", "skipped"})
#: the planner's default hand
DEFAULT_HAND = "hand3x3"


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


class RecordFileError(EosError, ValueError):
    """A record file that cannot be replayed (the message says where and why)."""


@dataclass
class Recording:
    """A parsed record file: the request, the cycle dicts, the result dict (or None), the hand."""

    request: dict[str, Any]
    cycles: list[dict[str, Any]]
    result: dict[str, Any] | None
    hand: str = DEFAULT_HAND


def read_recording(path: str | Path) -> Recording:
    """Parse a record file (RecordFileError naming the line at fault; OSError)."""
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


def record_from_dict(data: dict[str, Any]) -> CycleRecord:
    """A :class:`CycleRecord` back from its JSON form (board values stay JSON values)."""
    return CycleRecord(
        seq=data["seq"],
        stage=data["stage"],
        stage_cycle=data["stage_cycle"],
        ratings=tuple(  # the fields added since a record was written take their defaults
            AgentRating(r["agent"], **{k: r[k] for k in AgentRating._fields[1:] if k in r})
            for r in data["ratings"]
        ),
        weights=Weights.from_dict(data["weights"]),
        chosen=data["chosen"],
        outcome=None if data["outcome"] is None else Outcome(data["outcome"]),
        detail=data["detail"],
        changes=tuple(BoardChange(c["key"], c["old"], c["new"]) for c in data["changes"]),
        elapsed_s=data["elapsed_s"],
    )


def normalise(value: Any) -> Any:
    """The JSON value as it would be read back from a record file (tuples become lists)."""
    return json.loads(json.dumps(value, allow_nan=False))


def first_difference(recorded: Any, replayed: Any, path: str = "") -> tuple[str, Any, Any] | None:
    """The first differing field between two JSON values, as (dotted path, recorded, replayed),
    ignoring :data:`TIMING_FIELDS` (and :data:`ADDED_FIELDS` a recorded value lacks); ``None``
    when they agree exactly."""
    if isinstance(recorded, dict) and isinstance(replayed, dict):
        for key in list(recorded) + [k for k in replayed if k not in recorded]:
            if key in TIMING_FIELDS or (key in ADDED_FIELDS and key not in recorded):
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


@dataclass
class Verification:
    """Outcome of a comparison: ``divergences`` lists (where, path, recorded, replayed)."""

    replayed_result: dict[str, Any]
    divergences: list[tuple[str, str, Any, Any]] = field(default_factory=list)
    cycles_compared: int = 0

    @property
    def identical(self) -> bool:
        """Whether the runs agree (timing fields aside)."""
        return not self.divergences


def compare_run(
    recording: Recording, replayed_cycles: Sequence[dict[str, Any]], replayed_result: dict[str, Any]
) -> Verification:
    """Compare a re-run (its cycle dicts and result dict, as :func:`normalise` gives them) with
    ``recording``, cycle by cycle and then the result."""
    out = Verification(replayed_result)
    for recorded, again in zip(recording.cycles, replayed_cycles, strict=False):
        out.cycles_compared += 1
        diff = first_difference(recorded, again)
        if diff is not None:
            out.divergences.append((f"cycle {recorded['seq']}", *diff))
    if len(recording.cycles) != len(replayed_cycles):
        out.divergences.append(("cycles", "count", len(recording.cycles), len(replayed_cycles)))
    if recording.result is not None:
        diff = first_difference(recording.result, replayed_result)
        if diff is not None:
            out.divergences.append(("result", *diff))
    return out
