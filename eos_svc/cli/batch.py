"""``eos batch``: a dataset of plans run as Ray tasks, the rows streamed to Parquet.

eos batch docs/batch-example.toml                    # a local Ray on every CPU; rows in ./NAME.batch/
eos batch SPEC --out data/run1 --workers 2           # two local workers, rows in data/run1/
eos batch SPEC --address HEAD:6379 --out /shared/x   # join a Ray cluster (ray start --head on HEAD)
eos batch SPEC --out data/run1                       # again: resumes, skipping the rows written

The spec's fields are in docs/batch.md. Exit 0 when every plan has its row (whatever the plans'
statuses), 1 when some were lost to failed workers after every retry (run again), 2 on a bad spec
or a missing batch extra.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys

from eos_svc.cli.common import fail, int_at_least
from eos_svc.errors import ValidationError

#: what ``eos batch`` needs beyond the planner (pip install 'eos_svc[batch]')
EXTRA_MODULES = ("ray", "pyarrow")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", metavar="SPEC", help="the batch spec (TOML; see docs/batch.md)")
    parser.add_argument(
        "--address", metavar="ADDR", help="join this Ray cluster (HEAD:6379, or auto) instead of a local Ray"
    )
    parser.add_argument("--out", metavar="DIR", help="output directory (./NAME.batch with the spec's name)")
    parser.add_argument(
        "--workers",
        type=int_at_least(1),
        metavar="N",
        help="CPUs of the local Ray (every CPU); with --address, the most tasks at once",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def missing_extra() -> list[str]:
    """The modules of the batch extra that are not installed."""
    return [name for name in EXTRA_MODULES if importlib.util.find_spec(name) is None]


def run(args: argparse.Namespace) -> int:
    from eos_svc.batch import load_spec

    try:
        spec = load_spec(args.spec)
    except ValidationError as exc:
        fail(f"{args.spec}: {exc.field}: {exc.reason}")
    missing = missing_extra()
    if missing:
        fail(
            f"eos batch needs the batch extra ({', '.join(missing)} not installed): "
            "pip install 'eos_svc[batch]'"
        )
    from eos_svc.batch.runner import run_batch

    out = args.out or f"{spec.name}.batch"
    try:
        summary = run_batch(
            spec, out, address=args.address, workers=args.workers, progress=not args.no_progress
        )
    except RuntimeError as exc:  # the directory is in use, or Ray could not start / connect
        fail(str(exc))
        raise  # unreachable: fail() exits
    if args.json:
        print(json.dumps({"out": out, **summary.to_dict()}))
    else:
        print(summary.format())
        print(f"rows in {out}/ (eos_svc.batch.store.read_rows)")
    return 1 if summary.lost else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(run(argparse.Namespace()))
