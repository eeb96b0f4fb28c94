"""Shared plumbing of the experiments: running many plans with progress, writing files."""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

from eos_svc.agents import PlanRequest, PlanResult, plan

T = TypeVar("T")


def with_progress(items: Sequence[T], label: str, quiet: bool = False) -> Iterator[T]:
    """Yield every item, printing after each how many are done and the time left to stderr
    (one line, updated; nothing when ``quiet``)."""
    t0, n = time.perf_counter(), len(items)
    for i, item in enumerate(items, 1):
        yield item
        if not quiet:
            elapsed = time.perf_counter() - t0
            eta = elapsed / i * (n - i)
            print(f"\r{label}: {i}/{n}, {elapsed:.1f} s, ~{eta:.0f} s left   ", end="", file=sys.stderr)
    if not quiet:
        print(file=sys.stderr)


def run_plans(
    requests: Sequence[PlanRequest], label: str, quiet: bool = False, **options: Any
) -> list[PlanResult]:
    """Plan every request in order (``options`` go to :func:`plan`), with progress."""
    return [plan(request, keep_trace=True, **options) for request in with_progress(requests, label, quiet)]


def write_json(path: Path, data: Any) -> Path:
    """Write ``data`` as indented strict JSON."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return path


def write_csv(path: Path, rows: Iterable[dict[str, Any]]) -> Path:
    """Write dict rows as CSV (the header: every key, in the order first seen; a row without a
    key leaves its cell empty)."""
    rows = list(rows)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as f:
        if rows:
            writer = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for row in rows for k in row)))
            writer.writeheader()
            writer.writerows(rows)
    return path


def experiment_parser(name: str, doc: str | None, out: str) -> argparse.ArgumentParser:
    """The parser every experiment starts from: its program name, summary and ``--out``."""
    parser = argparse.ArgumentParser(prog=f"eos experiment {name}", description=(doc or "").split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path(out), help=f"output folder ({out})")
    return parser


def save_figure(fig: Any, path: Path) -> Path:
    """Lay out, write (creating the folder) and close a matplotlib figure."""
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    pyplot().close(fig)
    return path


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
