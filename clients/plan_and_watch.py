"""Request one grasp plan from an EOS service, print its cycles live, then the result.

    python clients/plan_and_watch.py                      # peer connecting to tcp/127.0.0.1:7447
    python clients/plan_and_watch.py -e tcp/127.0.0.1:7448 --seed 7 --radius 0.02
    python clients/plan_and_watch.py --config client.json5

``main(conf, ...)`` does the work; the argument parsing below is apart (zenoh-python examples style).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import zenoh

from eos_svc.schema.request import PlanRequest
from eos_svc.service import EosClient, RequestError, ServiceUnavailableError


def main(
    conf: zenoh.Config,
    request: PlanRequest,
    *,
    namespace: str | None = None,
    goal_id: str | None = None,
    wait_s: float = 5.0,
) -> int:
    """Plan once; print one line per cycle as it arrives, then the result as JSON. Returns an exit
    code: 0 only when the plan's status is ``success`` (a good grasp)."""

    def show(msg: dict[str, Any]) -> None:
        rec = msg["record"]
        print(
            f"[{msg['instance']}] {msg['goal_id']} #{msg['seq']:>4} {rec['stage']:<11} "
            f"-> {rec['chosen'] or '-'}: {rec['detail']}",
            flush=True,
        )

    with EosClient.open(conf, namespace=namespace) as client:
        try:
            client.wait_for_instances(1, timeout=wait_s)
            outcome = client.plan(request, goal_id=goal_id, on_cycle=show)
        except RequestError as err:
            print(f"refused: {err.code}: {err.field}: {err.reason}", file=sys.stderr)
            return 1
        except ServiceUnavailableError as exc:
            print(f"no service: {exc}", file=sys.stderr)
            return 1
    print(
        json.dumps(
            {
                "goal_id": outcome.goal_id,
                "instance": outcome.instance,
                "cycles_received": len(outcome.cycles),
                "complete": outcome.complete,
                "result": outcome.result,
            },
            indent=2,
        )
    )
    return 0 if outcome.status == "success" else 1


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="plan_and_watch", description=__doc__.splitlines()[0])
    parser.add_argument("--config", "-c", help="Zenoh JSON5 configuration file")
    parser.add_argument(
        "--connect", "-e", action="append", help="endpoint to connect to (tcp/127.0.0.1:7447)"
    )
    parser.add_argument("--namespace", help="service namespace")
    parser.add_argument("--goal-id", help="goal id (default: random)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--radius", type=float, default=0.03, help="sphere radius, m")
    parser.add_argument("--max-cycles", type=int, default=2000)
    parser.add_argument("--deadline", type=float, default=10.0, help="s")
    args = parser.parse_args()
    from eos_svc.service.session import DEFAULT_LISTEN, make_config

    conf = make_config(base=args.config, connect=args.connect or ([] if args.config else [DEFAULT_LISTEN]))
    try:
        req = PlanRequest.from_dict(
            {
                "object": {"shape": "sphere", "radius": args.radius},
                "seed": args.seed,
                "max_cycles": args.max_cycles,
                "deadline_s": args.deadline,
            }
        )
    except ValueError as exc:
        parser.error(str(exc))
    sys.exit(main(conf, req, namespace=args.namespace, goal_id=args.goal_id))
