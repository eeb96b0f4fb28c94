"""Batch throughput on a local Ray: the same plans through 1 worker and 2 workers in one run.

    .venv/bin/python benchmarks/bench_batch.py [--seeds 8] [--validated 6]

Reports, for plans only (the quick suite × seeds) and for validated plans (Drake, 0.5 s per
direction): plans/s and validations/s per core for 1 and 2 workers and their ratio (goal ≥ 1.8×
on two free cores), and the batch machinery's own cost per plan with 1 worker — the run's wall
time less the time spent planning and validating inside the tasks, over the plans — against a
median plan (goal ≤ 10 %), for one plan per task and for the default chunk. Each worker is warmed
up (imports, hand model) before it is timed. The load average is printed: the cores may be shared.
"""

from __future__ import annotations

import argparse
import logging
import os
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import ray

from eos_svc.batch import spec_from_dict
from eos_svc.batch.runner import run_batch
from eos_svc.batch.store import read_rows


def spec(seeds: list[int], validated: bool, per_task: int | None) -> dict:
    """The quick suite × ``seeds``, plan only or validated."""
    data: dict = {"name": "bench", "objects": {"suite": "quick"}, "seeds": seeds}
    if validated:
        data["validate"] = {"enabled": True, "seconds": 0.5}
    if per_task is not None:
        data["run"] = {"plans_per_task": per_task}
    return data


def timed(data: dict) -> tuple[float, list[dict]]:
    """Run a spec into a fresh directory on the running Ray: (wall s, rows)."""
    with tempfile.TemporaryDirectory() as out:
        summary = run_batch(spec_from_dict(data), out, progress=False)
        return summary.wall_s, read_rows(out).to_pylist()


def measure(workers: int, seeds: list[int], validated_seeds: list[int]) -> dict:
    """Every figure for one local Ray of ``workers`` CPUs."""
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False, logging_level=logging.ERROR)
    try:
        timed(spec([1000 + i for i in range(2 * workers)], False, 1))  # warm every worker up
        out = {}
        for name, data in (
            ("plans, 1 per task", spec(seeds, False, 1)),
            ("plans, default chunk", spec(seeds, False, None)),
            ("validated", spec(validated_seeds, True, None)),
        ):
            wall, rows = timed(data)
            inside = sum(r["plan_s"] + r["validation_s"] for r in rows)
            out[name] = {
                "n": len(rows),
                "wall": wall,
                "per_core": len(rows) / wall / workers,
                "machinery": (wall * workers - inside) / len(rows),
                "median_plan": statistics.median(r["plan_s"] for r in rows),
                "median_validation": statistics.median(r["validation_s"] for r in rows)
                if validated_seeds
                else 0,
            }
        return out
    finally:
        ray.shutdown()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="seeds per quick-suite object, plan only (8)")
    parser.add_argument("--validated", type=int, default=2, help="seeds per object, validated (2)")
    args = parser.parse_args()
    seeds = list(range(1, args.seeds + 1))
    validated = list(range(1, args.validated + 1))
    print(f"load average before: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} (cores {os.cpu_count()})")
    one, two = measure(1, seeds, validated), measure(2, seeds, validated)
    print(f"load average after:  {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}")
    unit = {"validated": "validations/s"}
    print(f"{'':22} {'n':>4} {'1 worker /core':>15} {'2 workers /core':>16} {'2w/1w':>7}")
    for name in one:
        a, b = one[name], two[name]
        ratio = b["per_core"] * 2 / a["per_core"]
        label = unit.get(name, "plans/s")
        print(f"{name:22} {a['n']:4d} {a['per_core']:10.2f} {label:<4} {b['per_core']:11.2f} {ratio:8.2f}x")
    print("machinery cost per plan (1 worker: wall - time inside plan/validation, over plans):")
    for name, a in one.items():
        per = a["median_plan"] + a["median_validation"]  # a median task's own work
        share = a["machinery"] / per
        print(
            f"  {name:22} {a['machinery'] * 1000:7.2f} ms vs median plan {per * 1000:7.2f} ms"
            f" = {share:6.1%}" + (" (plan + validation)" if name == "validated" else "")
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
