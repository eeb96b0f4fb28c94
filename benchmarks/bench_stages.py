"""Where a plan's time goes, stage by stage, against a baseline revision measured in the same run.

    .venv/bin/python benchmarks/bench_stages.py --baseline main
    .venv/bin/python benchmarks/bench_stages.py --baseline main --suite   # + the quick grasp suite

For each request (the default plan; with ``--suite`` also every object of the quick grasp suite,
seed 1) the plan's CPU time per part — the search stage, each information agent (ep1,
post_shape, ep2, grasp_points), the grasping stage — and in total, for this tree and for the
package at git revision ``--baseline`` (``git archive``d into a temporary folder). Both run in
child processes, in alternating rounds (the machine is shared: its load changes within a run,
and only ratios measured in one run mean much). The children time with the process's CPU
clock (``time.process_time`` stands in for the controller's clock there), which another
process's load disturbs far less than the wall clock. Reported per part: the median and the
lower quartile of this tree and of the baseline over every plan, and their ratios.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import json, sys, time
time.perf_counter = time.process_time  # CPU time: the controller's and the planner's clock
time.monotonic = time.process_time
from eos_svc.agents import PlanRequest, plan
requests = [PlanRequest.from_dict(r) for r in json.loads(sys.argv[1])]
for request in requests:
    plan(request)  # warm-up
out = []
for request in requests:
    rows = []
    for _ in range(int(sys.argv[2])):
        t0 = time.process_time()
        result = plan(request)
        parts = {"total": time.process_time() - t0}
        previous = 0.0
        for record in result.trace:
            key = record.chosen if record.stage == "information" else record.stage
            parts[key] = parts.get(key, 0.0) + record.elapsed_s - previous
            previous = record.elapsed_s
        rows.append(parts)
    out.append(rows)
print(json.dumps(out))
"""


def run_child(tree: str, requests: list[dict], plans: int) -> list[list[dict[str, float]]]:
    """Per request, per plan: CPU seconds per part, from a fresh interpreter importing ``tree``."""
    done = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(requests), str(plans)],
        capture_output=True,
        text=True,
        cwd=tree,
        env={"PYTHONPATH": tree, "PATH": "/usr/bin:/bin"},
    )
    if done.returncode != 0:
        raise RuntimeError(f"child on {tree} failed:\n{done.stderr[-2000:]}")
    out: list[list[dict[str, float]]] = json.loads(done.stdout)
    return out


def export(rev: str, folder: str) -> None:
    """``eos_svc`` and ``urdf`` of git revision ``rev`` into ``folder``."""
    archive = Path(folder) / "rev.tar"
    subprocess.run(
        ["git", "-C", str(ROOT), "archive", "-o", str(archive), rev, "eos_svc", "urdf"], check=True
    )
    with tarfile.open(archive) as tar:
        tar.extractall(folder, filter="data")


def quartile(values: list[float]) -> float:
    """Lower quartile (the median when there are too few values)."""
    return statistics.quantiles(values, n=4)[0] if len(values) >= 4 else statistics.median(values)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="per-stage plan time vs a baseline revision")
    parser.add_argument("--baseline", default="main", help="git revision to compare with (main)")
    parser.add_argument("--rounds", type=int, default=6, help="alternating rounds (6)")
    parser.add_argument("--plans", type=int, default=5, help="plans per request, side and round (5)")
    parser.add_argument("--suite", action="store_true", help="also the quick grasp suite's objects")
    args = parser.parse_args(argv)
    labels = ["default plan"]
    requests: list[dict] = [{}]
    if args.suite:
        from eos_svc.experiments.grasp_suite import quick_suite

        for obj in quick_suite():
            labels.append(obj.label)
            requests.append({"object": obj.spec.to_dict(), "seed": 1})
    with tempfile.TemporaryDirectory(prefix="eos_stages_") as tmp:
        export(args.baseline, tmp)
        sides = {"this tree": str(ROOT), args.baseline: tmp}
        samples: dict[str, list[list[dict[str, float]]]] = {s: [[] for _ in requests] for s in sides}
        for r in range(args.rounds):
            order = list(sides.items()) if r % 2 == 0 else list(sides.items())[::-1]
            for side, tree in order:
                for i, rows in enumerate(run_child(tree, requests, args.plans)):
                    samples[side][i] += rows
    ours, theirs = samples["this tree"], samples[args.baseline]
    print(
        f"CPU ms per part: this tree vs {args.baseline}, {args.rounds} alternating rounds x "
        f"{args.plans} plans per side (median, lower quartile; ratio = this tree / baseline)"
    )
    for label, mine, base in zip(labels, ours, theirs, strict=True):
        print(f"\n{label}")
        print(f"  {'part':<13} {'median':>8} {'base':>8} {'ratio':>6}   {'q1':>8} {'base':>8} {'ratio':>6}")
        for part in base[0]:
            a = [row.get(part, 0.0) * 1e3 for row in mine]
            b = [row.get(part, 0.0) * 1e3 for row in base]
            ma, mb, qa, qb = statistics.median(a), statistics.median(b), quartile(a), quartile(b)
            print(f"  {part:<13} {ma:8.2f} {mb:8.2f} {ma / mb:6.2f}   {qa:8.2f} {qb:8.2f} {qa / qb:6.2f}")
    if args.suite:
        mine_totals = [statistics.median([row["total"] for row in rows]) for rows in ours]
        base_totals = [statistics.median([row["total"] for row in rows]) for rows in theirs]
        m, b = statistics.median(mine_totals) * 1e3, statistics.median(base_totals) * 1e3
        print(f"\nmedian over the requests of each one's median plan CPU time: {m:.1f} ms vs {b:.1f} ms")
        print(f"  = {m / b:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
