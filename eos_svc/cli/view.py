"""The 3-D view options of ``eos plan``, ``eos replay`` and ``eos client watch`` (:mod:`eos_svc.view`)."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Mapping, Sequence
from typing import Any

from eos_svc.cli.common import fail, non_negative_float, positive_float


def add_html_argument(group: argparse._ArgumentGroup | argparse.ArgumentParser) -> None:
    """``--html FILE``."""
    group.add_argument(
        "--html",
        metavar="FILE",
        help="write the plan as one self-contained HTML page (3-D animation of every cycle, opens offline)",
    )


def add_view_arguments(group: argparse._ArgumentGroup, waits: bool = True) -> None:
    """``--view`` and its options (``--view-wait`` only where a plan starts here)."""
    group.add_argument(
        "--view", action="store_true", help="serve a live 3-D view on localhost (URL printed on stderr)"
    )
    group.add_argument(
        "--view-port", type=int, default=None, metavar="PORT", help="port of the view (default: 7000-7099)"
    )
    if waits:
        group.add_argument(
            "--view-wait",
            type=positive_float,
            default=None,
            metavar="S",
            help="with --view: wait up to S s for a browser to connect before planning",
        )
        group.add_argument(
            "--view-hold",
            type=non_negative_float,
            default=None,
            metavar="S",
            help="with --view: keep serving S s after the plan (default: until Ctrl-C)",
        )


def open_view(args: argparse.Namespace, hand: Any = None) -> Any:
    """The :class:`~eos_svc.view.live.LiveView` ``--view`` asks for (its URL printed), or None."""
    if not getattr(args, "view", False):
        for name in ("view_port", "view_wait", "view_hold"):  # a view option without --view
            if getattr(args, name, None) is not None:
                fail(f"--{name.replace('_', '-')}: needs --view")
        return None
    port = args.view_port
    if port is not None and not 1024 <= port <= 65535:
        fail(f"--view-port: must be a port in [1024, 65535] (MeshCat refuses privileged ports), got {port}")
    from eos_svc.view.live import LiveView

    try:
        view = LiveView(hand=hand, port=port)
    except RuntimeError as exc:  # Drake: the port is taken
        fail(f"--view-port: cannot serve the view: {exc}")
    print(f"view: {view.url}", file=sys.stderr, flush=True)
    return view


def watch_until(stop: Any, stream: Any, seconds: float | None) -> None:
    """``eos client watch``: wait until ``stop`` is set or ``seconds`` pass (None: until Ctrl-C),
    drawing the watched messages meanwhile when there is a view (``stream``)."""
    end = None if seconds is None else time.monotonic() + seconds
    while not stop.is_set() and (end is None or time.monotonic() < end):
        if stream is not None:
            stream.pump(0.1)
        else:
            stop.wait(0.1)


def wait_for_browser(view: Any, seconds: float | None) -> None:
    """``--view-wait``: wait until a browser shows the view (or ``seconds`` pass)."""
    if view is None or not seconds:
        return
    print(f"view: waiting up to {seconds:g} s for a browser at {view.url}", file=sys.stderr, flush=True)
    end = time.monotonic() + seconds
    while view.meshcat.GetNumActiveConnections() == 0 and time.monotonic() < end:
        time.sleep(0.05)


def hold_view(view: Any, seconds: float | None) -> None:
    """Keep serving the view ``seconds`` (None: until Ctrl-C)."""
    if view is None or (seconds is not None and seconds <= 0):
        return
    what = "until Ctrl-C" if seconds is None else f"for {seconds:g} s"
    print(f"view: {view.url} — serving {what}", file=sys.stderr, flush=True)
    end = None if seconds is None else time.monotonic() + seconds
    try:
        while end is None or time.monotonic() < end:
            time.sleep(0.1 if end is None else max(0.0, min(0.1, end - time.monotonic())))
    except KeyboardInterrupt:
        print("", file=sys.stderr)


def write_html(
    path: str,
    request: Mapping[str, Any] | Any,
    records: Sequence[Mapping[str, Any]],
    result: Mapping[str, Any] | None,
    hand: Any = None,
) -> None:
    """``--html FILE``: write the page (exit 2 naming the option when it cannot be written)."""
    from eos_svc.errors import ValidationError
    from eos_svc.view import write_plan_html

    try:
        write_plan_html(path, request, records, result, hand)
    except OSError as exc:
        fail(f"--html: cannot write {path!r}: {exc.strerror}")
    except ValidationError as exc:  # a recorded request this version does not accept
        fail(f"--html: the plan's request is not valid: {exc}")


def write_recording_html(
    path: str, recording: Any, result: Mapping[str, Any] | None, hand: Any = None
) -> None:
    """``eos replay FILE --html``: the recorded cycles; a recording made before the hand's
    configuration was recorded is planned again (same request, seed and hand) for it."""
    from eos_svc.world.pose_board import has_hand_q

    cycles = recording.cycles
    if cycles and not has_hand_q(cycles):
        from eos_svc.agents import PlanRequest, plan
        from eos_svc.errors import ValidationError

        try:
            again = plan(PlanRequest.from_dict(recording.request), hand=hand)
        except ValidationError as exc:
            fail(f"--html: the plan's request is not valid: {exc}")
        cycles = [r.to_dict() for r in again.trace]
    write_html(path, recording.request, cycles, result, hand)
