"""``eos client list|plan|cancel|watch``: talk to running ``eos serve`` instances (a peer
connecting to ``tcp/127.0.0.1:7447`` by default; examples: ``docs/service.md``)."""

from __future__ import annotations

import argparse
import json
import secrets
import sys
import threading
from typing import Any

from eos_svc.cli.common import fail, int_at_least, positive_float
from eos_svc.cli.plan import add_request_arguments
from eos_svc.cli.plan import request_dict as plan_request_dict
from eos_svc.cli.serve import add_connection_arguments, session_config
from eos_svc.errors import ValidationError


def format_cycle(msg: dict[str, Any]) -> str:
    """One line per cycle message: seq, stage, chosen agent, outcome, detail."""
    rec = msg.get("record", {})
    return (
        f"{msg.get('goal_id', '?')} #{msg.get('seq', '?'):>4} {rec.get('stage', '?'):<11} "
        f"-> {rec.get('chosen') or '-'} [{rec.get('outcome')}] {rec.get('detail', '')}"
    )


def format_status(msg: dict[str, Any]) -> str:
    """One line per status message: goal, instance, state (and how the plan ended)."""
    line = f"{msg.get('goal_id', '?')} [{msg.get('instance', '?')}] {msg.get('state', '?')}"
    if msg.get("state") == "done":
        reason = (msg.get("result") or {}).get("reason", "")
        line += f": {msg.get('status')} after {msg.get('cycles')} cycles — {reason}"
    return line


def request_dict(args: argparse.Namespace) -> dict[str, Any]:
    """The JSON plan request the ``eos client plan`` options describe (as ``eos plan``'s;
    an unset ``--friction`` is left to the service's default)."""
    out = plan_request_dict(args)
    if out.get("friction") is None:
        out.pop("friction", None)
    if getattr(args, "hand", None) is not None:
        out["hand"] = args.hand
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options and actions of ``eos client``."""
    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    lst = sub.add_parser("list", help="list the service instances alive")
    p = sub.add_parser("plan", help="request one plan; print its cycles live, then the result")
    c = sub.add_parser("cancel", help="cancel a goal by id")
    c.add_argument("goal_id", metavar="GOAL_ID")
    c.add_argument("--token", required=True, help="the goal's cancel token (eos client plan prints it)")
    w = sub.add_parser("watch", help="print every cycle and status message on the network (Ctrl-C to stop)")
    for sp in (lst, p, c, w):
        add_connection_arguments(sp, default_listen=False)
        sp.add_argument(
            "--timeout",
            type=positive_float,
            metavar="S",
            help="s to wait for an answer (plan: its deadline + 10, per instance asked; watch: stop after S)",
        )
    from eos_svc.cli.view import add_view_arguments

    add_view_arguments(w.add_argument_group("view"), waits=False)  # watch --view
    g = add_request_arguments(p, friction_default=None)
    g.add_argument("--hand", metavar="NAME", help="a hand the service has (eos hands; eos serve --hand)")
    g.add_argument("--goal-id", metavar="ID", help="goal id (default: random)")
    g.add_argument("--instance", metavar="ID", help="ask this instance only")
    g.add_argument(
        "--cancel-token", metavar="TOKEN", help="the goal's secret (16-128 of A-Z a-z 0-9 _ -; random)"
    )
    g.add_argument("--request", metavar="FILE", help="send this JSON request file instead of the options")
    g.add_argument(
        "--repeat",
        type=int_at_least(1),
        default=1,
        metavar="N",
        help="send the request N times in turn (goal ids ID-1 .. ID-N); with --json one line per plan",
    )
    g.add_argument("--json", action="store_true", help="print the result as JSON")
    g.add_argument("--quiet", action="store_true", help="do not print the cycles")


def run(args: argparse.Namespace) -> int:
    """Run the chosen action; exit 0 on success (a plan: only status ``success``, a good grasp; with
    --repeat, every plan), 1 on any other plan status, a refused request or no service."""
    if args.action is None:
        fail("ACTION: choose one of list, plan, cancel, watch")
    conf = session_config(args, serving=False)
    from eos_svc.service import protocol as proto
    from eos_svc.service.client import EosClient
    from eos_svc.service.instances import ServiceUnavailableError
    from eos_svc.service.wire_json import loads_strict

    if getattr(args, "goal_id", None) is not None:
        try:
            proto.check_id(args.goal_id, "goal_id")
        except ValidationError as exc:
            fail(f"{'GOAL_ID' if args.action == 'cancel' else '--goal-id'}: {exc.reason}")
    request: Any = None
    if args.action == "plan":
        from eos_svc.cli.plan import fail_field
        from eos_svc.schema.request import PlanRequest

        if args.request is not None:
            try:
                with open(args.request, encoding="utf-8") as fh:
                    request = loads_strict(fh.read())
            except OSError as exc:
                fail(f"--request: cannot read {args.request!r}: {exc.strerror}")
            except ValueError as exc:
                fail(f"--request: not JSON: {exc}")
        else:
            try:
                request = PlanRequest.from_dict(request_dict(args))
            except ValidationError as exc:
                fail_field(exc)
    token = getattr(args, "cancel_token", None) or getattr(args, "token", None)
    if token is not None and not proto.is_token(token):
        fail(
            f"{'--token' if args.action == 'cancel' else '--cancel-token'}: must be 16-128 of A-Z a-z 0-9 _ -"
        )
    try:
        client = EosClient.open(conf, namespace=args.namespace)
    except ValidationError as exc:
        fail(f"--namespace: {exc.reason}")
    except Exception as exc:
        fail(f"cannot open the Zenoh session: {exc}", code=1)
    with client:
        if args.action == "list":
            found = client.discover(timeout=args.timeout or 1.0)
            for iid in found:
                print(iid)
            if not found:
                print("no instance found")
            return 0 if found else 1
        if args.action == "cancel":
            try:
                had_it = client.cancel(args.goal_id, timeout=args.timeout or 2.0, cancel_token=args.token)
            except proto.RequestError as err:
                print(f"eos client: refused: {err}")
                return 1
            print(f"goal {args.goal_id}: {'cancelled' if had_it else 'not found on any instance'}")
            return 0 if had_it else 1
        if args.action == "watch":
            from eos_svc.cli.view import open_view, watch_until

            stop = threading.Event()
            view, stream = open_view(args), None  # --view: a live page of the plans watched
            if view is not None:
                from eos_svc.view.live import StreamView

                stream = StreamView(view)

            def on_message(kind: str, msg: dict[str, Any]) -> None:
                print(format_cycle(msg) if kind == "cycle" else format_status(msg), flush=True)
                if stream is not None:
                    stream.on_message(kind, msg)  # queued; drawn by watch_until, in this thread

            sub = client.watch(on_message)
            try:
                watch_until(stop, stream, args.timeout)
            except KeyboardInterrupt:
                pass
            finally:
                sub.undeclare()
            return 0
        client.discover(timeout=1.0)
        goal_id = args.goal_id or f"g-{secrets.token_hex(6)}"
        cancel_token = args.cancel_token or proto.new_cancel_token()
        print(
            f"goal {goal_id}; cancel with: eos client cancel {goal_id} --token {cancel_token}",
            file=sys.stderr,
        )
        show = None if args.quiet or args.json else (lambda msg: print(format_cycle(msg), flush=True))
        code = 0
        for k in range(1, args.repeat + 1):
            goal = goal_id if args.repeat == 1 else f"{goal_id}-{k}"
            try:
                outcome = client.plan(
                    request,
                    goal_id=goal,
                    on_cycle=show,
                    instance=args.instance,
                    timeout=args.timeout,
                    cancel_token=cancel_token,
                )
            except (
                proto.RequestError,
                ServiceUnavailableError,
            ) as exc:  # RequestError: "code: field: reason"
                why = "refused" if isinstance(exc, proto.RequestError) else "no service"
                print(f"eos client: {why}: {exc}", flush=True)
                code = 1
                continue
            print_outcome(outcome, args.json)
            if outcome.status != "success":  # exit 0 only when every plan was a good grasp
                code = 1
        return code


def print_outcome(outcome: Any, as_json: bool) -> None:
    """One plan's outcome: a JSON line, or a short sentence."""
    if as_json:
        line = {
            "goal_id": outcome.goal_id,
            "instance": outcome.instance,
            "attempts": outcome.attempts,
            "complete": outcome.complete,
            "result": outcome.result,
        }
        print(json.dumps(line, allow_nan=False), flush=True)
    else:
        r = outcome.result
        print(
            f"goal {outcome.goal_id} on {outcome.instance}: {r.get('status')} — {r.get('reason')} "
            f"({r.get('cycles')} cycles, {len(outcome.cycles)} received, "
            f"{outcome.round_trip_s * 1000:.1f} ms)",
            flush=True,
        )
