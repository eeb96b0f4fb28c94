"""The Drake world's plant step: does a longer step keep the lift test's verdicts, and how much
faster is it?

    .venv/bin/python benchmarks/bench_drake_step.py [--steps 0.001 0.002] [--quick]

For every object of the fixed suite (``--quick``: one per class), the kinematic world's plan
(seed 1) gives a grip; the Drake world with each plant step places the hand there and judges
the grip as a plan's end does (:meth:`DrakeDriver.judge_grip`: the squeeze, the lift test).
Prints, per object and step, the verdict and the object's largest displacement under the
loads; then, per step, the verdicts that differ from the first step's and the CPU seconds per
simulated second (process time: less sensitive than wall time to the other processes on the
machine), median over the objects, with their ratio against the first step in the same run.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from eos_svc.agents import PlanRequest, build_world, plan
from eos_svc.drivers.drake_plant import PlantSettings
from eos_svc.drivers.drake_world import DrakeDriver
from eos_svc.experiments.grasp_suite import fixed_suite, quick_suite


def lift_with_step(request: PlanRequest, q_grip: np.ndarray, step: float) -> tuple[bool, float, float]:
    """The lift test of the grip ``q_grip`` in a Drake world stepping ``step`` s: (held, the
    largest load displacement in m, CPU seconds per simulated second)."""
    settings = PlantSettings(time_step=step)
    driver = DrakeDriver(build_world(request), request.obj, request.friction, None, settings)
    plant = driver._plant
    plant.set_hand_q(q_grip)
    simulated, cpu = plant.simulated_s, time.process_time()
    lift = driver.judge_grip(request.friction)["lift"]  # the driver's squeeze, then the lift test
    cpu = time.process_time() - cpu
    worst = max(lift.get("load_displacement_m", {"none": np.inf}).values())
    return bool(lift["held"]), float(worst), cpu / (plant.simulated_s - simulated)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[0.001, 0.002], help="plant steps, s")
    parser.add_argument("--quick", action="store_true", help="one object per class")
    args = parser.parse_args(argv)
    objects = quick_suite() if args.quick else fixed_suite()
    verdicts: dict[float, list[bool]] = {s: [] for s in args.steps}
    costs: dict[float, list[float]] = {s: [] for s in args.steps}
    print(f"{'object':28s}" + "".join(f"  {f'{s * 1000:g} ms: held, worst mm':>24s}" for s in args.steps))
    for obj in objects:
        request = PlanRequest(obj=obj.spec, seed=1)
        result = plan(request, keep_trace=False)
        cells = []
        for step in args.steps:
            held, worst, cost = lift_with_step(request, np.asarray(result.q_final), step)
            verdicts[step].append(held)
            costs[step].append(cost)
            cells.append(f"  {held!s:>15s}, {1000 * worst:6.2f}")
        print(f"{obj.label:28s}" + "".join(cells), flush=True)
    first = args.steps[0]
    base = statistics.median(costs[first])
    for step in args.steps:
        differ = sum(a != b for a, b in zip(verdicts[first], verdicts[step], strict=True))
        cost = statistics.median(costs[step])
        print(
            f"step {step * 1000:g} ms: held {sum(verdicts[step])}/{len(objects)}, verdicts differing from "
            f"{first * 1000:g} ms: {differ}; CPU s per simulated s {cost:.2f} ({base / cost:.2f}x faster)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
