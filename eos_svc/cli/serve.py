"""``eos serve`` — run the grasp planner as a Zenoh service instance (options: ``docs/service.md``)."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from eos_svc.cli.common import fail, float_in, int_at_least, positive_float
from eos_svc.errors import ValidationError

_positive_int = int_at_least(1)
_natural = int_at_least(0)


def add_connection_arguments(parser: argparse.ArgumentParser, *, default_listen: bool) -> None:
    """Zenoh session options shared by ``eos serve`` and ``eos client``."""
    g = parser.add_argument_group("Zenoh session")
    g.add_argument(
        "--config", type=Path, metavar="FILE", help="Zenoh JSON5 configuration (mode, endpoints, TLS, ACL)"
    )
    g.add_argument("--mode", choices=("peer", "client", "router"), help="without --config (default: peer)")
    default = "default: tcp/127.0.0.1:7447 without --config"
    if default_listen:
        g.add_argument("--listen", action="append", metavar="ENDPOINT", help=f"repeatable ({default})")
    g.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help="repeatable" + ("" if default_listen else f" ({default})"),
    )
    g.add_argument(
        "--lease-ms",
        type=_positive_int,
        metavar="MS",
        help="transport lease: a silent peer is dropped after it (Zenoh default 10000)",
    )
    g.add_argument("--namespace", metavar="NS", help="namespace under eos/@v1")


def session_config(args: argparse.Namespace, *, serving: bool) -> Any:
    """Build the Zenoh configuration from the options (exit 2 naming the option on error)."""
    from eos_svc.service.session import DEFAULT_LISTEN, make_config

    if args.config is not None and not args.config.is_file():
        fail(f"--config: no such file: {args.config}")
    if args.config is not None and args.mode is not None:
        fail("--mode: give the mode in the --config file instead")
    listen = list(getattr(args, "listen", None) or [])
    connect = list(args.connect or [])
    if args.config is None:
        if serving and not listen and args.mode != "client":  # a Zenoh client does not listen
            listen = [DEFAULT_LISTEN]
        if not serving and not connect:
            connect = [DEFAULT_LISTEN]
    for opt, endpoints in (("--listen", listen), ("--connect", connect)):
        for ep in endpoints:
            if "/" not in ep:
                fail(f"{opt}: {ep!r} is not a Zenoh endpoint like tcp/127.0.0.1:7447")
    try:
        return make_config(
            mode=args.mode or "peer", listen=listen, connect=connect, lease_ms=args.lease_ms, base=args.config
        )
    except Exception as exc:  # zenoh.ZError on a bad file
        fail(f"--config: {exc}")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eos serve``."""
    add_connection_arguments(parser, default_listen=True)
    s = parser.add_argument_group("service")
    s.add_argument("--instance", metavar="ID", help="instance id (default: <pid>-<random>)")
    s.add_argument("--workers", type=_positive_int, default=2, metavar="N", help="plans run at once (2)")
    s.add_argument("--queue", type=_natural, default=16, metavar="N", help="plans waiting before 'busy' (16)")
    s.add_argument(
        "--max-request-bytes",
        type=_positive_int,
        default=64 * 1024,
        metavar="B",
        help="largest request (65536)",
    )
    s.add_argument(
        "--max-deadline",
        type=float_in(0.0, 3600.0, above=True),
        default=600.0,
        metavar="S",
        help="deadline of a plan whose request gives none or a longer one (s; 600, at most 3600)",
    )
    s.add_argument(
        "--planner",
        choices=("grasp", "root"),
        default="grasp",
        help="grasp (default) or root: the core's root-finding demo (transport tests, no Pinocchio)",
    )
    s.add_argument(
        "--cycle-delay",
        type=positive_float,
        metavar="S",
        help="sleep S s in every cycle (tests of cancellation)",
    )
    s.add_argument(
        "--hand",
        action="append",
        default=[],
        metavar="FILE",
        help="register a hand description file, repeatable (requests name any registered hand)",
    )
    s.add_argument(
        "--agent",
        action="append",
        default=[],
        metavar="SPEC",
        help="offer a plug-in agent, repeatable: NAME=module:attr, module:attr or an entry point",
    )
    s.add_argument("--log-level", choices=("debug", "info", "warning", "error"), default="info")


def run(args: argparse.Namespace) -> int:
    """Serve until SIGINT/SIGTERM; returns the exit code."""
    logging.basicConfig(
        level=args.log_level.upper(), format="%(asctime)s %(levelname)s %(name)s: %(message)s"
    )
    conf = session_config(args, serving=True)
    from eos_svc.service import protocol as proto
    from eos_svc.service.demo_planner import root_plan, slowed
    from eos_svc.service.server import PlanService

    try:
        if args.namespace is not None:
            proto.prefix(args.namespace)
        if args.instance is not None:
            proto.check_id(args.instance, "instance")
    except ValidationError as exc:
        fail(f"--{exc.field}: {exc.reason}")
    admission = None
    served = ""
    planner: Callable[..., Any]
    if args.planner == "grasp":
        from eos_svc.service.hands import ServedHands
        from eos_svc.shape import kernels

        try:
            hands = ServedHands(args.hand)
        except ValidationError as exc:
            fail(f"--hand: {exc.field}: {exc.reason}")
        planner, admission = hands.plan, hands.admit
        kernels.load_in_background()  # the shape fit's compiled kernels (as for the default planner)
        served = f"; hands {', '.join(hands.names)}"
    else:
        if args.hand:
            fail("--hand: only the grasp planner has hands (--planner grasp)")
        planner = root_plan
    plugins: dict[str, Any] = {}
    if args.agent:
        if args.planner != "grasp":
            fail("--agent: plug-in agents join the grasp planner only (--planner grasp)")
        from eos_svc.service.plugins import offered_plugins

        try:
            plugins = offered_plugins(args.agent)
        except ValidationError as exc:
            fail(f"{exc.field}: {exc.reason}")
    if args.cycle_delay is not None:
        planner = slowed(planner, args.cycle_delay)
    sys.setswitchinterval(0.001)  # hand the GIL to Zenoh's callback threads sooner while a plan runs
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    try:
        service = PlanService.open(
            conf,
            namespace=args.namespace,
            instance=args.instance,
            planner=planner,
            workers=args.workers,
            queue_size=args.queue,
            max_request_bytes=args.max_request_bytes,
            max_deadline_s=args.max_deadline,
            admission=admission,
            plugins=plugins,
        )
    except Exception as exc:  # zenoh.ZError: cannot listen/connect, bad config
        fail(f"cannot start the Zenoh session: {exc}", code=1)
    print(
        f"eos serve: instance {service.instance} serving under {service.prefix} "
        f"({args.workers} worker(s), queue {args.queue}{served})"
        + (f"; plug-ins offered: {', '.join(plugins)}" if plugins else "")
        + "; Ctrl-C to stop",
        flush=True,
    )
    try:
        while not stop.wait(0.5):
            pass
    finally:
        service.stop()
        print(f"eos serve: stopped; {service.stats.to_dict()}", flush=True)
    return 0
