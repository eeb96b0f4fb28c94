"""Whole plans: median plan time, cycles and time per cycle.

    .venv/bin/python benchmarks/bench_plan.py

Default scene (3 cm sphere, seed 1) repeated, then the ratio sweep (spheres over d/h,
a few seeds each). Baseline measured in the same run: the same plans with the
controller's per-cycle recording only (the trace) vs with a live per-cycle callback
that formats the trace line as `eos plan` does, to show what observation costs.
Goals: ≤ 60 µs per cycle and ≤ 20 ms per plan (median, default scene).

The information stage's cost per plan (cycles and ms: EP1, EP2's probes, post_shape's fits)
is reported for every class, and the default plan's median time is compared with the same
plan at a baseline revision (``--baseline REV``, default the commit before EP2 and the
fitting: ``256976e``), run from a ``git archive`` of it: this tree and the baseline each in
child processes, in alternating rounds (the machine's load changes within a run).
``--cold-memo``: both sides forget a memo of grasp qualities kept across plans before each
timed plan (a69a74f kept one: its repeated default plan skipped the end agent's 6-D hull,
which a new request computes).

    .venv/bin/python benchmarks/bench_plan.py --suite [--baseline REV] [--numpy-fit]

compares instead the median plan time over the grasp experiment's fixed suite (29 objects,
seed 1: spheres d/h 0.2–0.95, ellipsoids, cylinders and capsules in four poses, boxes of three
aspect ratios at three yaws) with the default plan at the baseline revision: two long-lived
child processes, this tree planning the suite and the baseline its default plan, alternating
plan by plan (the machine's speed swings within seconds here), two rounds over the suite; it
prints the ratio of the medians and the median of the pairs' ratios. ``--numpy-fit`` keeps
this tree's fit on its numpy reference throughout (a one-shot process's state).

    .venv/bin/python benchmarks/bench_plan.py --short

times a 1-cycle plan (the shape of a service's small request) back to back and after 4 ms
asleep (a process between requests: cold caches), on the default hand's kept context (what
``plan(request)`` uses) and on a context built for every plan (``plan(request,
context=HandContext.build(hand))``: what a caller pays that does not keep one), in alternating
blocks in this process; medians and the ratio.

Every process that times plans loads the fit's compiled kernels first where its tree has them
(``eos_svc.shape.kernels.load()``): the state of a long-lived process — the service, the
experiments. A one-shot ``eos plan`` fits in numpy (the same results to rounding, ≈ 3× the
fit's time).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _harness import ScriptChild, export_revision, table

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.agents.planner import ratio_sphere_request
from eos_svc.cli.plan import format_cycle
from eos_svc.shape import kernels
from eos_svc.world.hand_context import HandContext, default_context

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


#: objects of every class for the information-stage cost (cylinder and capsule across the approach)
CLASS_OBJECTS = {
    "sphere": ObjectSpec(),
    "ellipsoid": ObjectSpec("ellipsoid", {"radii": [0.035, 0.03, 0.025]}),
    "cylinder": ObjectSpec("cylinder", {"radius": 0.02, "length": 0.08}, rpy=(math.pi / 2, 0.0, 0.0)),
    "capsule": ObjectSpec("capsule", {"radius": 0.02, "length": 0.06}, rpy=(math.pi / 2, 0.0, 0.0)),
    "box": ObjectSpec("box", {"size": [0.05, 0.06, 0.04]}),
}
#: the fit's compiled kernels loaded first where the tree has them (a long-lived process's state,
#: as in the service and the experiments; a one-shot ``eos plan`` fits in numpy, see
#: eos_svc.shape.kernels)
LOAD_KERNELS = """
try:
    from eos_svc.shape import kernels
except ImportError:  # a revision before the compiled fit
    kernels = None
if kernels is not None:
    kernels.load()
"""
#: ``--numpy-fit``: this tree's fit on its numpy reference throughout (a one-shot process's state)
NUMPY_FIT = """
from eos_svc.shape import kernels  # kernels.load() not called: the fit stays in numpy
"""
BASELINE_SCRIPT = (
    LOAD_KERNELS
    + """
import statistics, time
from eos_svc.agents import PlanRequest, plan
plan(PlanRequest())
forget = lambda: None
samples = []
for _ in range({repeats}):
    forget()
    t0 = time.perf_counter(); plan(PlanRequest()); samples.append(time.perf_counter() - t0)
print(*samples)
"""
)
#: ``--cold-memo``: a revision that memoised grasp qualities across plans (a69a74f's lru_cache
#: of ``contacts_quality``) forgets them before each timed plan, as for a new request
COLD_MEMO = """
try:
    from eos_svc.agents.quality import _contacts_quality
    forget = _contacts_quality.cache_clear
except ImportError:
    pass
"""
SUITE_SCRIPT = (
    LOAD_KERNELS
    + """
import time
from eos_svc.agents import PlanRequest, plan
from eos_svc.experiments.grasp_suite import fixed_suite
plan(PlanRequest())
samples = []
for seed in {seeds}:
    for item in fixed_suite():
        t0 = time.perf_counter()
        plan(PlanRequest(obj=item.spec, seed=seed))
        samples.append(time.perf_counter() - t0)
print(*samples)
"""
)
#: a long-lived child planning on command (``--suite``): request index in, wall seconds out
PAIRED_CHILD = """
import json, sys, time
from eos_svc.agents import PlanRequest, plan
requests = [PlanRequest.from_dict(r) for r in json.loads(sys.argv[1])]
plan(PlanRequest())  # load the hand, warm caches
for request in requests:
    plan(request)  # every request once
print("ready", flush=True)
for line in sys.stdin:
    t0 = time.perf_counter()
    plan(requests[int(line)])
    print(time.perf_counter() - t0, flush=True)
"""


class PlanningChild(ScriptChild):
    """A fresh interpreter importing ``eos_svc`` from ``tree`` (with ``prelude`` run first) that
    plans ``requests[i]`` for every index ``i`` sent and answers the plan's wall time (s)."""

    def __init__(self, tree: str, requests: list[dict], prelude: str) -> None:
        super().__init__(tree, prelude + PAIRED_CHILD, json.dumps(requests))

    def plan(self, index: int) -> float:
        """Wall seconds of one plan of request ``index``."""
        return float(self.ask(str(index)))


#: rounds of the interleaved comparison with the baseline revision, plans per round and side
ROUNDS, ROUND_PLANS = 4, 8


def information_cost(request: PlanRequest, repeats: int = 3) -> tuple[int, float, float, str, float]:
    """(information cycles, median ms of the stage, median ms of EP2's and post_shape's fitting
    cycles, postulated class, confidence) of ``request``."""
    stage_ms, touch_ms = [], []
    cycles, kind, conf = 0, "", 0.0
    for _ in range(repeats):
        result = plan(request)
        previous, total, touch = 0.0, 0.0, 0.0
        for record in result.trace:
            dt = record.elapsed_s - previous
            previous = record.elapsed_s
            if record.stage == "information":
                total += dt
                if record.chosen == "ep2" or (record.chosen == "post_shape" and "fitted" in record.detail):
                    touch += dt
        stage_ms.append(total * 1e3)
        touch_ms.append(touch * 1e3)
        cycles = result.cycles_per_stage.get("information", 0)
        kind, conf = (result.shape or {}).get("class", "none"), (result.shape or {}).get("confidence", 0.0)
    return cycles, statistics.median(stage_ms), statistics.median(touch_ms), kind, conf


def _child_samples(pythonpath: str, cwd: str, repeats: int, script: str = BASELINE_SCRIPT) -> list[float]:
    """Plan times (s) printed by ``script`` (default: ``repeats`` default plans) in a fresh
    interpreter importing eos_svc from ``pythonpath`` (after one warm-up plan); empty when it
    fails."""
    out = subprocess.run(
        [sys.executable, "-c", script.format(repeats=repeats, seeds=(1,))],
        capture_output=True,
        text=True,
        cwd=cwd,
        env={"PYTHONPATH": pythonpath, "PATH": "/usr/bin:/bin"},
    )
    return [float(v) for v in out.stdout.split()] if out.returncode == 0 else []


def this_tree() -> str:
    """The folder this process imports ``eos_svc`` from."""
    import eos_svc

    return str(Path(eos_svc.__file__).resolve().parents[1])


def paired_suite(rev: str, rounds: int = 2, numpy_fit: bool = False) -> tuple[float, float, float] | None:
    """(median suite plan of this tree, median default plan of revision ``rev``, median of the
    pairs' ratios) in s: two long-lived child processes — this tree planning the grasp
    experiment's fixed suite (seed 1), ``rev`` (``git archive``d) planning its default plan —
    alternating plan by plan, ``rounds`` times over the suite, so that the machine's speed,
    which swings within seconds on a shared VM, hits both sides alike. None when the revision
    or a child fails."""
    from eos_svc.experiments.grasp_suite import fixed_suite

    suite = [PlanRequest(obj=item.spec, seed=1).to_dict() for item in fixed_suite()]
    with tempfile.TemporaryDirectory(prefix="eos_bench_") as tmp:
        if not export_revision(rev, tmp):
            return None
        here = this_tree()
        try:
            ours_child = PlanningChild(here, suite, NUMPY_FIT if numpy_fit else LOAD_KERNELS)
            theirs_child = PlanningChild(tmp, [{}], LOAD_KERNELS)  # its own default request
        except RuntimeError:
            return None
        ours: list[float] = []
        theirs: list[float] = []
        try:
            for _ in range(rounds):
                for i in range(len(suite)):
                    ours.append(ours_child.plan(i))
                    theirs.append(theirs_child.plan(0))
        finally:
            ours_child.close()
            theirs_child.close()
        pairs = [a / b for a, b in zip(ours, theirs, strict=True)]
        return statistics.median(ours), statistics.median(theirs), statistics.median(pairs)


def interleaved_baseline(
    rev: str,
    rounds: int = ROUNDS,
    plans: int = ROUND_PLANS,
    suite: bool = False,
    numpy_fit: bool = False,
    cold_memo: bool = False,
) -> tuple[float, float] | None:
    """(median default-plan time of this tree, of revision ``rev``) in s: both in child processes,
    alternating rounds of ``plans`` plans, so that a change of the machine's load hits both
    (``rev`` is ``git archive``d into a temporary folder). With ``suite``, this tree's side is
    the grasp experiment's fixed suite instead (every object once, seed 1 — the median over
    the suite). ``cold_memo``: each side forgets a memo of grasp qualities kept across plans
    before each default plan (:data:`COLD_MEMO`). None when the revision or a child fails."""
    with tempfile.TemporaryDirectory(prefix="eos_bench_") as tmp:
        if not export_revision(rev, tmp):
            return None
        here = this_tree()
        ours: list[float] = []
        theirs: list[float] = []
        for _ in range(rounds):
            script = SUITE_SCRIPT if suite else BASELINE_SCRIPT
            if numpy_fit:
                script = script.replace(LOAD_KERNELS, NUMPY_FIT)
            base_script = BASELINE_SCRIPT
            if cold_memo:
                script = script.replace("forget = lambda: None\n", "forget = lambda: None\n" + COLD_MEMO)
                base_script = base_script.replace(
                    "forget = lambda: None\n", "forget = lambda: None\n" + COLD_MEMO
                )
            ours += _child_samples(here, here, plans, script)
            theirs += _child_samples(tmp, tmp, plans, base_script)
        if len(ours) < (1 if suite else rounds * plans) or len(theirs) < rounds * plans:
            return None
        return statistics.median(ours), statistics.median(theirs)


SHORT_ROUNDS = 6
SHORT_BLOCK = 40


def short_plans(rounds: int = SHORT_ROUNDS, block: int = SHORT_BLOCK) -> dict[tuple[str, str], float]:
    """Median 1-cycle plan time (s) by (context, timing): context ``kept`` (the default one) or
    ``built`` (a new one per plan), timing ``back to back`` or ``after 4 ms asleep``; alternating
    blocks of ``block`` plans."""
    hand = default_context().hand
    request = PlanRequest(seed=3, max_cycles=1)
    samples: dict[tuple[str, str], list[float]] = {}
    for _ in range(rounds):
        for mode in ("built", "kept"):
            for timing, nap in (("back to back", 0.0), ("after 4 ms asleep", 0.004)):
                times = samples.setdefault((mode, timing), [])
                for _ in range(block if mode == "kept" else max(1, block // 8)):
                    if nap:
                        time.sleep(nap)
                    t0 = time.perf_counter()
                    context = default_context() if mode == "kept" else HandContext.build(hand)
                    plan(request, keep_trace=False, check=False, context=context)
                    times.append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in samples.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="whole plans: time, cycles, information-stage cost")
    parser.add_argument("--baseline", default="256976e", help="git revision to compare the default plan with")
    parser.add_argument(
        "--suite",
        action="store_true",
        help="only compare the grasp suite's median plan time (eos experiment grasps' fixed suite, "
        "seed 1) with the baseline's default plan, interleaved in child processes",
    )
    parser.add_argument(
        "--numpy-fit",
        action="store_true",
        help="with --suite: this tree's fit on its numpy reference throughout (a one-shot process, "
        "e.g. eos plan), not the compiled kernels a long-lived process loads",
    )
    parser.add_argument(
        "--cold-memo",
        action="store_true",
        help="the default plan against --baseline: forget a baseline's memo of grasp qualities before "
        "each plan (a69a74f kept one across plans: the same request again hit it, a new one does not)",
    )
    parser.add_argument(
        "--short",
        action="store_true",
        help="only time a 1-cycle plan back to back and after idling, on the default hand's kept "
        "context vs a context built for every plan (alternating, this process)",
    )
    args = parser.parse_args(argv)
    if args.short:
        plan(PlanRequest(seed=3, max_cycles=1))  # load the hand
        medians = short_plans()
        print(
            f"1-cycle plan (seed 3), medians of {SHORT_ROUNDS} alternating blocks of {SHORT_BLOCK} plans "
            "each: the default hand's kept context vs a context built for every plan"
        )
        for timing in ("back to back", "after 4 ms asleep"):
            kept, built = medians[("kept", timing)], medians[("built", timing)]
            print(
                f"  {timing:<18} kept {kept * 1e3:6.3f} ms   built {built * 1e3:6.3f} ms   "
                f"built - kept {(built - kept) * 1e3:.2f} ms"
            )
        return 0
    if args.suite:
        rounds = 2
        paired = paired_suite(args.baseline, rounds=rounds, numpy_fit=args.numpy_fit)
        if paired is None:
            print(f"could not run the suite or revision {args.baseline}")
            return 1
        ours, base, pair_ratio = paired
        print(
            f"grasp suite (fixed, seed 1{', fit in numpy' if args.numpy_fit else ''}) median plan vs the "
            f"default plan at {args.baseline} (same run, two long-lived child processes alternating plan "
            f"by plan, {rounds} rounds over the suite): {ours * 1e3:.1f} ms vs {base * 1e3:.1f} ms "
            f"= {ours / base:.2f}x (median of the pairs' ratios {pair_ratio:.2f}x; goal: within 2x -> "
            f"{'met' if ours <= 2.0 * base else 'NOT met'})"
        )
        return 0
    kernels.load()  # the fit's compiled kernels, as a long-lived process has them
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
    pair = interleaved_baseline(args.baseline, cold_memo=args.cold_memo)
    if pair is not None:
        ours, base = pair
        print(
            f"\ndefault plan vs {args.baseline} (same run, {ROUNDS} alternating rounds of "
            f"{ROUND_PLANS} plans each in child processes{', memo forgotten' if args.cold_memo else ''}): "
            f"{ours * 1e3:.1f} ms vs {base * 1e3:.1f} ms = {ours / base:.2f}x (goal: within 1.3x -> "
            f"{'met' if ours <= 1.3 * base else 'NOT met'})"
        )
    print("\ninformation stage per plan (seed 1, median of 3): cycles, ms, of which EP2 + fitting")
    print("  object      cycles  stage ms  EP2+fit ms  postulate (confidence)")
    for name, spec in CLASS_OBJECTS.items():
        cycles_i, ms, touch, kind, conf = information_cost(PlanRequest(obj=spec))
        print(f"  {name:<10} {cycles_i:6d}  {ms:8.1f}  {touch:10.1f}  {kind} ({conf:.0%})")
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
