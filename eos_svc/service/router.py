"""A Zenoh router in a Python process, for setups without the ``zenohd`` binary
(``python -m eos_svc.service.router --config FILE | --listen ENDPOINT``; ``mode`` forced to router).
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading

import zenoh

from eos_svc.service.session import DEFAULT_LISTEN, make_config


def main(argv: list[str] | None = None) -> int:
    """Run a router until SIGINT/SIGTERM."""
    parser = argparse.ArgumentParser(
        prog="python -m eos_svc.service.router", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--config", help="Zenoh JSON5 configuration file")
    parser.add_argument("--listen", action="append", help=f"endpoint, repeatable (default {DEFAULT_LISTEN})")
    args = parser.parse_args(argv)
    try:
        conf = make_config(
            mode="router", base=args.config, listen=args.listen or ([] if args.config else [DEFAULT_LISTEN])
        )
        conf.insert_json5("mode", json.dumps("router"))
        session = zenoh.open(conf)
    except Exception as exc:  # zenoh.ZError: bad file, port in use
        print(f"router: error: {exc}", file=sys.stderr)
        return 1
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    print(f"router {session.zid()} running; Ctrl-C to stop", flush=True)
    while not stop.wait(0.5):
        pass
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
