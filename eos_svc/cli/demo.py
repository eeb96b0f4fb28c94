"""``eos demo``: the domain-free controller on a small root-finding problem."""

from __future__ import annotations

import argparse
import json

from eos_svc.cli.common import add_weight_arguments, weights_from_args
from eos_svc.demo import default_problem, solve_root
from eos_svc.records import CycleRecord


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_weight_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def run(args: argparse.Namespace) -> int:
    weights = weights_from_args(args)

    def show(record: CycleRecord) -> None:
        ratings = " ".join(f"{r.name}={r.total:.2f}" for r in record.ratings)
        print(f"#{record.seq:3d} {record.stage:8s} [{ratings}] -> {record.chosen}: {record.detail}")

    result, board = solve_root(default_problem(), weights, callbacks=() if args.json else (show,))
    if args.json:
        print(json.dumps({**result.to_dict(), "root": board.get("root")}))
    else:
        print(f"{result.status.value}: {result.reason} ({result.cycles} cycles)")
    return 0
