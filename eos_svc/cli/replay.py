"""``eos replay FILE``: print a recorded plan (:mod:`eos_svc.recording`), re-run it (same request,
seed and hand) and compare cycle by cycle, then the result, wall-clock fields ignored. Exit status:
0 identical (or not verified), 1 a divergence (the first reported with its cycle, path, values), 2 a bad file.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterable
from types import SimpleNamespace
from typing import Any

from eos_svc.cli.common import fail
from eos_svc.cli.plan import format_cycle, format_result
from eos_svc.recording import (
    DEFAULT_HAND,
    RecordFileError,
    Recording,
    Verification,
    compare_run,
    normalise,
    read_recording,
    record_from_dict,
)


def resolve_hand(name: str) -> Any:
    """The hand called ``name`` (``eos hands``; None for the default hand3x3); RecordFileError
    when there is no such hand or its description is bad."""
    if name == DEFAULT_HAND:
        return None
    from eos_svc.errors import ValidationError
    from eos_svc.hands import HandRegistry

    try:
        return HandRegistry().build(name)
    except ValidationError as exc:
        raise RecordFileError(f"unknown hand {name!r}: {exc}") from None


def verify(recording: Recording, hand: Any = DEFAULT_HAND) -> Verification:
    """Re-run the recorded request (with ``hand``, by default the recorded one) and compare it
    cycle by cycle, then the result (:func:`eos_svc.recording.compare_run`). Raises
    RecordFileError (an unknown hand) or ValidationError (a request not valid any more)."""
    from eos_svc.agents import PlanRequest, plan  # heavy imports only when verifying
    from eos_svc.world.pose_board import view_entries_as_recorded

    request = PlanRequest.from_dict(recording.request)
    if hand == DEFAULT_HAND:
        hand = resolve_hand(recording.hand)
    replayed: list[dict[str, Any]] = []
    result = plan(request, on_cycle=lambda r: replayed.append(normalise(r.to_dict())), hand=hand)
    replayed = view_entries_as_recorded(recording.cycles, replayed)  # older recordings lack hand_q
    return compare_run(recording, replayed, normalise(result.to_dict()))


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
        try:
            text = format_result(SimpleNamespace(**recording.result))
        except (KeyError, TypeError, ValueError, AttributeError) as exc:  # a hand-edited result line
            fail(f"FILE: {args.file}: the result line is not a plan result ({type(exc).__name__}: {exc})")
        print(text)
    else:
        print(f"no result line: the recorded run was interrupted after {len(recording.cycles)} cycles")
    code = 0
    final = recording.result
    hand = None
    if not args.no_verify or args.picture or args.html:
        try:
            hand = resolve_hand(recording.hand)
        except RecordFileError as exc:
            fail(f"FILE: {args.file}: {exc}")
    if not args.no_verify:
        from eos_svc.errors import ValidationError

        try:
            verification = verify(recording, hand)
        except ValidationError as exc:
            fail(f"FILE: the recorded request is not valid here: {exc}")
        for line in describe(verification, recording):
            print(line)
        code = 0 if verification.identical else 1
        final = final or verification.replayed_result
    if args.picture:
        from eos_svc.view.picture import draw_result

        if final is None or final.get("q_final") is None:
            fail("--picture: no final hand configuration in the recording (the end agent never acted)")
        draw_result(final, args.picture, hand=hand)
        print(f"picture: {args.picture}")
    if args.html:  # the recorded plan in 3-D
        from eos_svc.cli.view import write_recording_html

        write_recording_html(args.html, recording, final, hand)
        print(f"html: {args.html}")
    return code
