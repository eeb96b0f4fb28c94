"""Serve an agent over Zenoh, for plans in other processes to use (a remote agent).

    python clients/remote_agent.py            # remote_post_shape, connecting to tcp/127.0.0.1:7447
    python clients/remote_agent.py --agent my_pkg.agents:MyAgent --name mine -e tcp/127.0.0.1:7448

A planner then adds it to a plan::

    from eos_svc.remote_agents import RemoteAgent
    proxy = RemoteAgent.connect(session, "remote_post_shape")
    plan(request, agents=[proxy])

By default it serves post_shape (the planner's own shape postulator) under the name
``remote_post_shape`` with the default sub-rating 0.75 (above the local post_shape's 0.7, so it is
chosen while it answers, and the local one carries on when it does not). ``--agent`` names any
plug-in factory (``module:attr``, called with the kinematic driver of the default hand and the default
request's tactile noise; the agent acts on the board entries it is sent, never on the
planner's hand). ``main(conf, ...)`` does the work; the argument parsing below is apart
(zenoh-python examples style).
"""

from __future__ import annotations

import argparse
import signal
import threading
import time
from collections.abc import Callable

import zenoh

from eos_svc.agent import Agent
from eos_svc.service.session import make_config


def remote_post_shape(world) -> Agent:  # type: ignore[no-untyped-def]
    """post_shape, as the example serves it (rated 0.75)."""
    from eos_svc.agents.post_shape import PostShapeAgent

    return PostShapeAgent(0.75, world)


def main(
    conf: zenoh.Config,
    factory: Callable[..., Agent] = remote_post_shape,
    *,
    name: str = "remote_post_shape",
    namespace: str | None = None,
    duration_s: float | None = None,
) -> int:
    """Serve ``factory(driver)`` (the default scene's kinematic driver) as ``name`` until
    SIGINT/SIGTERM (or ``duration_s``)."""
    from eos_svc.agents.planner import build_world
    from eos_svc.drivers.kinematic import KinematicDriver
    from eos_svc.remote_agents import AgentServer
    from eos_svc.schema.request import PlanRequest

    # agents act through a hand driver, never on the world itself (docs/drivers.md)
    agent = factory(KinematicDriver(build_world(PlanRequest())))
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    with zenoh.open(conf) as session, AgentServer(session, agent, name=name, namespace=namespace) as server:
        print(f"serving agent {server.name} under {server.prefix}/agent/{server.name}", flush=True)
        end = None if duration_s is None else time.monotonic() + duration_s
        # short waits: a signal the kernel hands to one of Zenoh's threads must not leave the
        # main thread asleep in one long wait
        while not stop.wait(0.2) and (end is None or time.monotonic() < end):
            pass
        print(f"stopped after {server.served} queries", flush=True)
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "-e", "--connect", action="append", help="endpoint to connect to (tcp/127.0.0.1:7447)"
    )
    parser.add_argument("-l", "--listen", action="append", help="endpoint to listen on")
    parser.add_argument(
        "--agent", help="plug-in factory module:attr (default: post_shape as remote_post_shape)"
    )
    parser.add_argument("--name", default="remote_post_shape", help="the name it is served under")
    parser.add_argument("--namespace", help="namespace under eos/@v1")
    parser.add_argument("--duration", type=float, help="serve this many seconds, then exit")
    args = parser.parse_args()
    factory: Callable[..., Agent] = remote_post_shape
    if args.agent:
        from eos_svc.agents.plugins.loading import resolve

        factory = resolve(args.agent, "--agent")
    config = make_config(connect=args.connect or ["tcp/127.0.0.1:7447"], listen=args.listen or [])
    raise SystemExit(
        main(config, factory, name=args.name, namespace=args.namespace, duration_s=args.duration)
    )
