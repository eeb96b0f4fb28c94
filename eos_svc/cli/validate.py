"""``eos validate FILE``: simulate a planned grasp in Drake and say whether it holds (FILE: what
``eos plan --json`` prints, or a record file). Exit status: 0 held, 1 dropped, 2 bad input.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from eos_svc.cli.common import fail, int_at_least, positive_float
from eos_svc.errors import ValidationError

#: validate_grasp argument -> command-line option, for error messages
OPTION_NAMES = {"seconds": "--seconds", "mass": "--mass", "directions": "--directions"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "file", metavar="FILE", help="an `eos plan --json` result or an `eos plan --record` file"
    )
    parser.add_argument(
        "--seconds", type=positive_float, default=1.5, help="load time per direction, s (1.5)"
    )
    parser.add_argument("--mass", type=positive_float, default=0.1, help="object mass, kg (0.1)")
    parser.add_argument(
        "--directions", type=int_at_least(1), default=6, help="how many of +x -x +y -y +z -z (6)"
    )
    parser.add_argument("--json", action="store_true", help="print the result with its validation as JSON")
    parser.add_argument(
        "--hand",
        default=None,
        metavar="NAME|FILE",
        help="the hand that planned it: a registered name (eos hands) or a description file "
        "(a record file's own hand, else hand3x3)",
    )


def read_result(path: str) -> tuple[dict[str, Any], str | None]:
    """The plan result in ``path`` (a JSON object, or a record file's result line) and the hand a
    record file names (None for a plain result); exit 2 naming the problem when it is unusable."""
    from eos_svc.recording import MARK, RecordFileError, read_recording

    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        fail(f"FILE: cannot read {path!r}: {getattr(exc, 'strerror', None) or exc}")
    try:
        data = json.loads(text)
    except json.JSONDecodeError:
        data = None  # not one JSON document: a record file (JSON lines)?
    if isinstance(data, dict) and MARK not in data:
        return data, None
    if data is not None and not isinstance(data, dict):
        fail(f"FILE: {path!r} holds a JSON {type(data).__name__}, not a plan result object")
    try:
        recording = read_recording(path)
    except RecordFileError as exc:
        fail(f"FILE: {path!r} is neither a plan result (eos plan --json) nor a record file: {exc}")
    if recording.result is None:
        fail(f"FILE: {path!r} has no result line (the recorded run was interrupted)")
    return recording.result, recording.hand


def format_validation(validation: dict[str, Any]) -> str:
    """A readable summary of a validation dict (:meth:`GraspValidation.to_dict`)."""
    verdict = "HELD" if validation["held"] else "DROPPED"
    lines = [
        f"validation (Drake): {verdict} — {validation['reason']}",
        f"  {validation['mass_kg']:g} kg object, μ = {validation['friction']:g}, squeeze "
        f"{validation['squeeze_rad']:g} rad at kp {validation['kp']:g} N·m/rad; "
        f"{validation['seconds']:g} s per direction; the squeeze moved it "
        f"{validation['settle_displacement_m'] * 1000:.1f} mm; {validation['wall_time_s']:.1f} s",
    ]
    for o in validation["outcomes"]:
        mark = "held" if o["held"] else "DROPPED"
        touching = ", ".join(o["touching"]) or "nothing"
        lines.append(
            f"  {o['direction']}: {o['displacement_m'] * 1000:7.2f} mm  {mark:<7}  touching {touching}"
        )
    return "\n".join(lines)


def validate_or_fail(result: Any, **options: Any) -> Any:
    """:func:`validate_grasp` of a result; a bad field exits with status 2 naming it, a Drake
    failure with status 1."""
    from eos_svc.validation import SimulationError, validate_grasp

    try:
        return validate_grasp(result, **options)
    except ValidationError as exc:
        fail(f"{OPTION_NAMES.get(exc.field, exc.field)}: {exc.reason}")
    except SimulationError as exc:
        fail(f"validation: {exc}", code=1)


def run(args: argparse.Namespace) -> int:
    from eos_svc.cli.hands import DEFAULT_HAND, load_or_fail

    result, recorded_hand = read_result(args.file)
    name = args.hand or recorded_hand or DEFAULT_HAND
    hand = None if name == DEFAULT_HAND else load_or_fail(name)
    check = validate_or_fail(
        result, seconds=args.seconds, mass=args.mass, directions=args.directions, hand=hand
    )
    if args.json:
        print(json.dumps({**result, "validation": check.to_dict()}, allow_nan=False))
    else:
        print(format_validation(check.to_dict()))
    return 0 if check.held else 1
