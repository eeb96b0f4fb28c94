"""The board contract's debug mode: what ``plan(..., check_board=True)`` costs, same run.

    .venv/bin/python benchmarks/bench_board_contract.py [--rounds 5]

Plans the default scene (seeds 1-3) and a box (seed 4), alternately unchecked and checked
(every board access through a ``BoardClient``, every value written checked against its
``TypedDict``), and prints the median plan time of each and their ratio. The unchecked plan is
the planner's default; the checked one is a debugging aid, so only its ratio matters.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _harness import median_of, table

from eos_svc.agents import PlanRequest, plan

REQUESTS = [
    *(PlanRequest(seed=s) for s in (1, 2, 3)),
    PlanRequest.from_dict({"seed": 4, "object": {"shape": "box", "size": [0.045, 0.05, 0.04]}}),
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="rounds over the requests (5)")
    rounds = parser.parse_args().rounds
    for request in REQUESTS:  # warm-up: hand, sweeps, imports
        plan(request)
    plain: list[float] = []
    checked: list[float] = []
    cycles = 0
    for _ in range(rounds):
        for request in REQUESTS:
            for check, samples in ((False, plain), (True, checked)):
                t0 = time.perf_counter()
                result = plan(request, check_board=check)
                samples.append(time.perf_counter() - t0)
                cycles += result.cycles if check else 0
    per_round = cycles // rounds
    print(f"{len(REQUESTS)} plans x {rounds} rounds, unchecked then checked ({per_round} cycles a round)")
    a, b = median_of(plain), median_of(checked)
    print(table([("plan, unchecked (default)", a, 1.0), ("plan, check_board=True", b, b / a)], "unchecked"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
