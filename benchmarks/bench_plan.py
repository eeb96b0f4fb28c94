"""Whole plans: median plan time, cycles and time per cycle.

    .venv/bin/python benchmarks/bench_plan.py

Default scene (3 cm sphere, seed 1) repeated, then the ratio sweep (spheres over d/h,
a few seeds each). Baseline measured in the same run: the same plans with the
controller's per-cycle recording only (the trace) vs with a live per-cycle callback
that formats the trace line as `eos plan` does, to show what observation costs.
Goals: ≤ 60 µs per cycle and ≤ 20 ms per plan (median, default scene).

    .venv/bin/python benchmarks/bench_plan.py --baseline 256976e

also times the default plan of another git revision (its tree exported to a temporary
folder, planned in a child process) interleaved with this tree's, rounds of 10 plans each,
and prints the ratio of the medians (the grasp-synthesis goal: within 2× of the revision
before it).
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _harness import table

from eos_svc.agents import PlanRequest, plan
from eos_svc.agents.planner import ratio_sphere_request
from eos_svc.cli.plan import format_cycle

REPEATS = 15


def time_plans(
    request: PlanRequest, repeats: int, on_cycle=None, per_agent: dict | None = None
) -> tuple[float, int]:
    """(median seconds per plan, cycles of the plan). With ``per_agent``, also collects each
    plan's mean cycle time per (stage, chosen agent), from the records' timestamps."""
    samples = []
    cycles = 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = plan(request, on_cycle=on_cycle)
        samples.append(time.perf_counter() - t0)
        cycles = result.cycles
        if per_agent is not None:
            spent: dict[tuple[str, str | None], list[float]] = {}
            previous = 0.0
            for record in result.trace:
                spent.setdefault((record.stage, record.chosen), []).append(record.elapsed_s - previous)
                previous = record.elapsed_s
            for key, times in spent.items():
                per_agent.setdefault(key, (len(times), []))[1].append(sum(times) / len(times))
    return statistics.median(samples), cycles


#: a child process that times ``n`` default plans and prints their times (s), one per line
_CHILD = """
import sys, time
from eos_svc.agents import PlanRequest, plan
plan(PlanRequest())
for _ in range(int(sys.argv[1])):
    t0 = time.perf_counter(); plan(PlanRequest()); print(time.perf_counter() - t0)
"""


def _child_times(tree: Path, n: int) -> list[float]:
    """Times of ``n`` default plans by the package in ``tree`` (a child process)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, str(n)], env=env, capture_output=True, text=True, check=True
    ).stdout
    return [float(x) for x in out.split()]


def baseline_ratio(rev: str, rounds: int = 4, per_round: int = 10) -> None:
    """Median default-plan time of this tree and of git revision ``rev``, interleaved rounds."""
    root = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="eos_plan_baseline_") as tmp:
        archive = subprocess.run(
            ["git", "-C", str(root), "archive", rev, "eos_svc", "urdf"], capture_output=True, check=True
        )
        subprocess.run(["tar", "-x", "-C", tmp], input=archive.stdout, check=True)
        ours: list[float] = []
        theirs: list[float] = []
        for _ in range(rounds):
            ours += _child_times(root, per_round)
            theirs += _child_times(Path(tmp), per_round)
    a, b = statistics.median(ours), statistics.median(theirs)
    print(f"\ndefault plan, {rounds} interleaved rounds of {per_round} plans each (child processes)")
    print(f"  this tree {a * 1e3:.1f} ms, {rev} {b * 1e3:.1f} ms: ratio {a / b:.2f}")


def main() -> int:
    if "--baseline" in sys.argv:
        baseline_ratio(sys.argv[sys.argv.index("--baseline") + 1])
        return 0
    plan(PlanRequest())  # load the hand, warm caches
    default = PlanRequest()
    per_agent: dict = {}
    t_plan, cycles = time_plans(default, REPEATS, per_agent=per_agent)
    sink: list[str] = []
    t_cb, _ = time_plans(default, REPEATS, on_cycle=lambda r: sink.append(format_cycle(r)))
    per_cycle = t_plan / cycles
    print(f"default scene (seed 1, {cycles} cycles), median of {REPEATS} plans")
    print(
        table(
            [
                ("plan, trace kept", t_plan, 1.0),
                ("plan + live trace formatting", t_cb, t_cb / t_plan),
                ("per cycle", per_cycle, None),
            ],
            "plan",
        )
    )
    print(
        f"goals: per cycle <= 60 µs -> {'met' if per_cycle <= 60e-6 else 'NOT met'}; "
        f"per plan <= 20 ms -> {'met' if t_plan <= 20e-3 else 'NOT met'}"
    )
    print("\nper chosen agent (default scene): cycles, median cycle time (rating + action + record)")
    for (stage, agent), (n, times) in per_agent.items():
        t = statistics.median(times)
        print(f"  {stage:<12} {agent or '-':<13} {n:3d} x {t * 1e6:9.1f} µs = {n * t * 1e3:6.2f} ms")
    print("\nratio sweep (3 seeds each, 1 run per seed)")
    print("  d/h   status(es)            cycles  plan ms  µs/cycle")
    for ratio in (0.2, 0.35, 0.5, 0.65, 0.8, 0.95):
        times, cyc, statuses = [], [], []
        for seed in (1, 2, 3):
            t0 = time.perf_counter()
            r = plan(ratio_sphere_request(ratio, seed))
            times.append(time.perf_counter() - t0)
            cyc.append(r.cycles)
            statuses.append(r.status)
        t = statistics.median(times)
        c = statistics.median(cyc)
        print(f"  {ratio:.2f}  {','.join(statuses):<20}  {c:6.0f}  {t * 1e3:7.1f}  {t / c * 1e6:8.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
