"""Drake validation: its cost per plan against the plan itself (ratio measured in the same run).

    .venv/bin/python benchmarks/bench_validation.py

For a few scenes: the median plan time, the median time of ``validate_grasp`` on that plan
(6 directions × 1.5 s of load after 0.3 s of squeeze, 1 ms steps) and their ratio; then the
validation split into building the Drake model, the squeeze and one load direction, and the
real-time factor of the simulation (simulated seconds per wall-clock second).
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from eos_svc.agents import ObjectSpec, PlanRequest, plan
from eos_svc.kinematics.hand import HAND3X3_URDF, HandDescription
from eos_svc.validation import grasp_setup, validate_grasp
from eos_svc.validation.simulation import GraspSimulation

PLAN_REPEATS = 7
VALIDATION_REPEATS = 3
SCENES = {
    "sphere r30 (default)": PlanRequest(seed=1),
    "sphere r18": PlanRequest(obj=ObjectSpec("sphere", {"radius": 0.018}), seed=2),
    "box 50x60x40": PlanRequest(obj=ObjectSpec("box", {"size": (0.05, 0.06, 0.04)}), seed=1),
}


def median_seconds(fn, repeats: int) -> float:
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return statistics.median(samples)


def parts(result) -> tuple[float, float, float]:
    """Median (build, squeeze 0.3 s, one 1.5 s load along +z) seconds for ``result``'s grasp."""
    setup = grasp_setup(result, 15)
    build, settle, load = [], [], []
    for _ in range(VALIDATION_REPEATS):
        t0 = time.perf_counter()
        sim = GraspSimulation(
            HAND3X3_URDF,
            HandDescription.hand3x3(),
            setup.q_final,
            setup.obj,
            friction=setup.friction,
        )
        t1 = time.perf_counter()
        sim.settle(0.3)
        t2 = time.perf_counter()
        sim.load(np.array([0.0, 0.0, 1.0]), 0.981, 1.5, 0.1, 0.05)
        t3 = time.perf_counter()
        build.append(t1 - t0)
        settle.append(t2 - t1)
        load.append(t3 - t2)
    return statistics.median(build), statistics.median(settle), statistics.median(load)


def main() -> int:
    validate_grasp(plan(PlanRequest()), directions=1, seconds=0.1)  # import and warm everything
    print(f"median of {PLAN_REPEATS} plans and {VALIDATION_REPEATS} validations per scene")
    print(f"{'scene':<22} {'plan ms':>8} {'validate s':>11} {'ratio':>8}  held")
    for name, request in SCENES.items():
        result = plan(request)
        t_plan = median_seconds(lambda request=request: plan(request), PLAN_REPEATS)
        checks: list = []
        t_val = median_seconds(
            lambda result=result, out=checks: out.append(validate_grasp(result)), VALIDATION_REPEATS
        )
        print(f"{name:<22} {t_plan * 1e3:8.1f} {t_val:11.2f} {t_val / t_plan:7.0f}x  {checks[-1].held}")
    build, settle, load = parts(plan(PlanRequest()))
    print("\nvalidation of the default grasp, by part (median)")
    print(f"  build the Drake model      {build * 1e3:8.1f} ms")
    print(f"  squeeze, 0.3 s simulated   {settle * 1e3:8.1f} ms  (real-time factor {0.3 / settle:.2f})")
    print(f"  one load, 1.5 s simulated  {load * 1e3:8.1f} ms  (real-time factor {1.5 / load:.2f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
