"""Print every cycle and status message of every plan served on the network.

    python clients/watch_all.py                           # peer connecting to tcp/127.0.0.1:7447
    python clients/watch_all.py -e tcp/127.0.0.1:7448 --duration 30

``main(conf, ...)`` does the work; the argument parsing below is apart (zenoh-python examples style).
"""

from __future__ import annotations

import argparse
import json
import queue
import time
from typing import Any

import zenoh

from eos_svc.service import protocol as proto


def main(
    conf: zenoh.Config,
    *,
    namespace: str | None = None,
    duration_s: float | None = None,
    max_messages: int | None = None,
) -> int:
    """Subscribe to ``eos/@v1[/ns]/goal/*/*`` and print each message; returns the number printed."""
    key = proto.goal_keys(proto.prefix(namespace))
    inbox: queue.SimpleQueue[zenoh.Sample] = queue.SimpleQueue()
    count = 0
    end = None if duration_s is None else time.monotonic() + duration_s
    with zenoh.open(conf) as session:
        sub = session.declare_subscriber(key, inbox.put)  # the callback only enqueues
        print(f"watching {key}", flush=True)
        try:
            while (end is None or time.monotonic() < end) and (max_messages is None or count < max_messages):
                try:
                    sample = inbox.get(timeout=0.2)
                except queue.Empty:
                    continue
                msg: dict[str, Any] = json.loads(sample.payload.to_bytes())
                if "seq" in msg:
                    rec = msg["record"]
                    print(
                        f"[{msg['instance']}] {msg['goal_id']} #{msg['seq']:>4} {rec['stage']:<11} "
                        f"-> {rec['chosen'] or '-'} [{rec['outcome']}]",
                        flush=True,
                    )
                else:
                    extra = (
                        f" {msg.get('status')} ({msg.get('cycles')} cycles)" if msg["state"] == "done" else ""
                    )
                    print(f"[{msg['instance']}] {msg['goal_id']} {msg['state']}{extra}", flush=True)
                count += 1
        except KeyboardInterrupt:
            pass
        finally:
            sub.undeclare()
    return count


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="watch_all", description=__doc__.splitlines()[0])
    parser.add_argument("--config", "-c", help="Zenoh JSON5 configuration file")
    parser.add_argument(
        "--connect", "-e", action="append", help="endpoint to connect to (tcp/127.0.0.1:7447)"
    )
    parser.add_argument("--namespace", help="service namespace")
    parser.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    args = parser.parse_args()
    from eos_svc.service.session import DEFAULT_LISTEN, make_config

    conf = make_config(base=args.config, connect=args.connect or ([] if args.config else [DEFAULT_LISTEN]))
    main(conf, namespace=args.namespace, duration_s=args.duration)
