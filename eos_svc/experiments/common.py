"""Shared plumbing of the experiments: running many plans with progress, writing files."""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from eos_svc.agents import PlanRequest, PlanResult, plan


def run_plans(
    requests: Sequence[PlanRequest], label: str, quiet: bool = False, **options: Any
) -> list[PlanResult]:
    """Plan every request in order (``options`` go to :func:`plan`), printing progress to
    stderr (one line, updated)."""
    results = []
    t0 = time.perf_counter()
    n = len(requests)
    for i, request in enumerate(requests, 1):
        results.append(plan(request, keep_trace=True, **options))
        if not quiet:
            elapsed = time.perf_counter() - t0
            eta = elapsed / i * (n - i)
            print(f"\r{label}: {i}/{n} plans, {elapsed:.1f} s, ~{eta:.0f} s left   ", end="", file=sys.stderr)
    if not quiet:
        print(file=sys.stderr)
    return results


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
