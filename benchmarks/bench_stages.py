"""Where a plan's time goes, stage by stage, against a baseline revision measured in the same run.

    .venv/bin/python benchmarks/bench_stages.py --baseline ddccb46
    .venv/bin/python benchmarks/bench_stages.py --baseline ddccb46 --suite   # + the quick grasp suite
    .venv/bin/python benchmarks/bench_stages.py --baseline a69a74f --suite --cold-memo

For each request (the default plan; with ``--suite`` also every object of the quick grasp suite,
seed 1) the plan's CPU time per part — the search stage, each information agent (ep1,
post_shape, ep2, grasp_points), the grasping stage — and in total, for this tree and for the
package at git revision ``--baseline`` (``git archive``d into a temporary folder). Each side
lives in its own child process; they plan alternately, plan by plan (the machine is shared:
its load changes within a run, and only ratios measured side by side mean much). The children
time with the process's CPU clock (``time.process_time`` stands in for the controller's clock
there), which another process's load disturbs far less than the wall clock. Reported per
part: the median and the lower quartile of each side and their ratios, and the median of the
plan-by-plan ratios (``paired``). Each child plans the same requests over and over: a
baseline that memoised results across plans (a69a74f's grasp-quality ``lru_cache``) answers
the grasping stage's 6-D hull from its memo there, which a new request never does;
``--cold-memo`` forgets that memo before each plan. The fit's compiled residuals are loaded
in both children (:func:`eos_svc.shape.kernels.load`), as a long-lived process has them.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile

from _harness import ROOT, ScriptChild, export_revision

CHILD = """
import json, sys, time
time.perf_counter = time.process_time  # CPU time: the controller's and the planner's clock
time.monotonic = time.process_time
try:  # the fit's compiled kernels, as a long-lived process has them (where the tree has them)
    from eos_svc.shape import kernels
    kernels.load()
except ImportError:
    pass
from eos_svc.agents import PlanRequest, plan
given = json.loads(sys.argv[1])
requests = [PlanRequest.from_dict(r) for r in given["requests"]]
forget = lambda: None
if given["cold_memo"]:
    try:  # a revision that memoised grasp qualities across plans (a69a74f: an lru_cache)
        from eos_svc.agents.quality import _contacts_quality
        forget = _contacts_quality.cache_clear
    except ImportError:
        pass
for request in requests:
    plan(request)  # warm-up
print("ready", flush=True)
for line in sys.stdin:  # one plan per line: the index of its request
    forget()
    t0 = time.process_time()
    result = plan(requests[int(line)])
    parts = {"total": time.process_time() - t0}
    previous = 0.0
    for record in result.trace:
        key = record.chosen if record.stage == "information" else record.stage
        parts[key] = parts.get(key, 0.0) + record.elapsed_s - previous
        previous = record.elapsed_s
    print(json.dumps(parts), flush=True)
"""


class Child(ScriptChild):
    """A fresh interpreter importing ``eos_svc`` from ``tree`` that plans one of ``requests`` per
    :meth:`plan` call and answers its CPU seconds per part."""

    def __init__(self, tree: str, requests: list[dict], cold_memo: bool = False) -> None:
        super().__init__(tree, CHILD, json.dumps({"requests": requests, "cold_memo": cold_memo}))

    def plan(self, index: int) -> dict[str, float]:
        """CPU seconds per part of one plan of request ``index``."""
        parts: dict[str, float] = json.loads(self.ask(str(index)))
        return parts


def quartile(values: list[float]) -> float:
    """Lower quartile (the median when there are too few values)."""
    return statistics.quantiles(values, n=4)[0] if len(values) >= 4 else statistics.median(values)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="per-stage plan time vs a baseline revision")
    parser.add_argument(
        "--baseline", default="ddccb46", help="git revision to compare with (ddccb46, before the speed-ups)"
    )
    parser.add_argument("--plans", type=int, default=20, help="plans per request and side (20)")
    parser.add_argument("--suite", action="store_true", help="also the quick grasp suite's objects")
    parser.add_argument(
        "--cold-memo",
        action="store_true",
        help="forget a baseline's memo of grasp qualities before each plan (a69a74f kept one across "
        "plans: repeating the same request hit it, a new request does not)",
    )
    args = parser.parse_args(argv)
    labels = ["default plan"]
    requests: list[dict] = [{}]
    if args.suite:
        from eos_svc.experiments.grasp_suite import quick_suite

        for obj in quick_suite():
            labels.append(obj.label)
            requests.append({"object": obj.spec.to_dict(), "seed": 1})
    with tempfile.TemporaryDirectory(prefix="eos_stages_") as tmp:
        if not export_revision(args.baseline, tmp):
            raise RuntimeError(f"git archive of {args.baseline} failed")
        mine, base = Child(str(ROOT), requests, args.cold_memo), Child(tmp, requests, args.cold_memo)
        samples: dict[str, list[list[dict[str, float]]]] = {
            side: [[] for _ in requests] for side in ("this tree", args.baseline)
        }
        try:  # plan by plan, alternating which side goes first: both see the same load
            for n in range(args.plans):
                for i in range(len(requests)):
                    pair = (mine, base) if n % 2 == 0 else (base, mine)
                    first, second = pair[0].plan(i), pair[1].plan(i)
                    ours_i, theirs_i = (first, second) if n % 2 == 0 else (second, first)
                    samples["this tree"][i].append(ours_i)
                    samples[args.baseline][i].append(theirs_i)
        finally:
            mine.close()
            base.close()
    ours, theirs = samples["this tree"], samples[args.baseline]
    print(
        f"CPU ms per part: this tree vs {args.baseline}, {args.plans} plans per request and side, "
        "alternating plan by plan (median, lower quartile, ratio = this tree / baseline; paired: "
        "the median of the plan-by-plan ratios)"
    )
    for label, mine, base in zip(labels, ours, theirs, strict=True):
        print(f"\n{label}")
        print(
            f"  {'part':<13} {'median':>8} {'base':>8} {'ratio':>6}   {'q1':>8} {'base':>8} {'ratio':>6}"
            f"   {'paired':>6}"
        )
        for part in base[0]:
            a = [row.get(part, 0.0) * 1e3 for row in mine]
            b = [row.get(part, 0.0) * 1e3 for row in base]
            ma, mb, qa, qb = statistics.median(a), statistics.median(b), quartile(a), quartile(b)
            paired = statistics.median(x / y for x, y in zip(a, b, strict=True) if y > 0.0)
            print(
                f"  {part:<13} {ma:8.2f} {mb:8.2f} {ma / mb:6.2f}   {qa:8.2f} {qb:8.2f} {qa / qb:6.2f}"
                f"   {paired:6.2f}"
            )
    if args.suite:
        mine_totals = [statistics.median([row["total"] for row in rows]) for rows in ours]
        base_totals = [statistics.median([row["total"] for row in rows]) for rows in theirs]
        m, b = statistics.median(mine_totals) * 1e3, statistics.median(base_totals) * 1e3
        print(f"\nmedian over the requests of each one's median plan CPU time: {m:.1f} ms vs {b:.1f} ms")
        print(f"  = {m / b:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
