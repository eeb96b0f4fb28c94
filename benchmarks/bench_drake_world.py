"""The Drake world's real-time factor: simulated seconds per wall-clock second.

    .venv/bin/python benchmarks/bench_drake_world.py [--seeds 1 2 3]

Plans the default scene (a 3 cm sphere on the table) in the Drake world for a few seeds and
prints, per plan, the simulated time, the wall time spent simulating, their ratio (the
real-time factor; >= 1 is faster than real time), the whole plan's wall time, the status and
how far the object moved; then the medians. The baseline measured in the same run: the
Drake world with nothing moving (the object resting, 2 s simulated), the cheapest second the
plant can simulate.
"""

from __future__ import annotations

import argparse
import statistics
import time

from eos_svc.agents import PlanRequest, build_world, plan
from eos_svc.drivers.drake_world import DrakeDriver


def idle_rtf() -> float:
    """Real-time factor of the Drake world at rest (2 s simulated)."""
    request = PlanRequest(seed=1)
    driver = DrakeDriver(build_world(request), request.obj, request.friction)
    plant = driver._plant
    t0 = time.perf_counter()
    plant.advance(2.0)
    return 2.0 / (time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3], help="plan seeds (1 2 3)")
    args = parser.parse_args(argv)
    rtfs, walls = [], []
    print(f"{'seed':>4} {'simulated s':>12} {'sim wall s':>11} {'RTF':>6} {'plan wall s':>12}  status, moved")
    for seed in args.seeds:
        t0 = time.perf_counter()
        result = plan(PlanRequest(seed=seed, deadline_s=600), world="drake")
        wall = time.perf_counter() - t0
        world = result.world or {}
        rtf = float(world["real_time_factor"])
        rtfs.append(rtf)
        walls.append(wall)
        print(
            f"{seed:>4} {world['simulated_s']:>12.2f} {world['simulation_wall_s']:>11.2f} {rtf:>6.2f} "
            f"{wall:>12.2f}  {result.status}, object moved {world['object_moved_mm']:.1f} mm"
        )
    rest = idle_rtf()
    print(f"median real-time factor over plans: {statistics.median(rtfs):.2f}")
    print(f"median plan wall time: {statistics.median(walls):.1f} s")
    ratio = statistics.median(rtfs) / rest
    print(f"baseline, the world at rest: real-time factor {rest:.2f} (plans / rest: {ratio:.2f}x)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
