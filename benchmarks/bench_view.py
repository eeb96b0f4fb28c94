"""The 3-D view's costs: the HTML page, its size, the live view nobody watches, the hand's record.

    .venv/bin/python benchmarks/bench_view.py

Baselines measured in the same run:

- the page: writing the HTML of the default plan (3 cm sphere, seed 1) against planning it;
  goal: < 1 s beyond the plan;
- its size for the default plan, a 149-cycle plan (sphere d/h 0.2, seed 6) and a 1371-cycle one
  (d/h 0.2, seed 3, a long search); goal: < 5 MB for a plan of 100 cycles or more;
- the live view with no browser connected (``plan(on_cycle=view.cycle)``) against the same plan
  without it, interleaved; goal: ≤ 10 % more;
- what every plan now pays for the hand's configuration in its records (the planner's
  PoseBoard against a plain Board, same agents, interleaved).
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _harness import table

from eos_svc.agents import PlanRequest, keys, plan
from eos_svc.agents.base import STAGES
from eos_svc.agents.planner import build_agents, build_world, ratio_sphere_request
from eos_svc.agents.pose_board import PoseBoard
from eos_svc.board import Board
from eos_svc.controller import Controller
from eos_svc.view import write_result_html
from eos_svc.view.live import LiveView

REPEATS = 15
PAGES = 5


def interleaved(a, b, repeats: int) -> tuple[float, float]:
    """Median seconds of ``a()`` and of ``b()``, run alternately ``repeats`` times each."""
    ta, tb = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        a()
        ta.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        b()
        tb.append(time.perf_counter() - t0)
    return statistics.median(ta), statistics.median(tb)


def controller_run(request: PlanRequest, pose_board: bool) -> None:
    world = build_world(request)
    board = PoseBoard(world, {keys.FRICTION: 0.5}) if pose_board else Board({keys.FRICTION: 0.5})
    Controller(build_agents(world), STAGES, request.weights, max_cycles=request.max_cycles).run(board)


def main() -> int:
    default = PlanRequest()
    result = plan(default)  # load the hand, warm caches
    out = Path(tempfile.mkdtemp(prefix="bench-view-"))
    write_result_html(result, out / "warm.html")  # first MeshCat and Drake import

    t_plan = statistics.median([_timed(lambda: plan(default)) for _ in range(REPEATS)])
    page = out / "plan.html"
    t_page = statistics.median([_timed(lambda: write_result_html(result, page)) for _ in range(PAGES)])
    print(f"HTML page of the default plan ({result.cycles} cycles), medians ({REPEATS} plans, {PAGES} pages)")
    print(table([("plan", t_plan, 1.0), ("write the page", t_page, t_page / t_plan)], "plan"))
    print(f"goal: page < 1 s beyond the plan -> {'met' if t_page < 1.0 else 'NOT met'} ({t_page:.3f} s)")

    print("\npage size")
    sizes = []
    for name, request in (
        ("default", default),
        ("d/h 0.2 seed 6", ratio_sphere_request(0.2, 6)),
        ("d/h 0.2 seed 3", ratio_sphere_request(0.2, 3)),
    ):
        planned = plan(request)
        size = write_result_html(planned, out / "size.html").stat().st_size
        sizes.append((planned.cycles, size))
        print(f"  {name:<15} {planned.cycles:5d} cycles  {size / 1e6:6.2f} MB")
    hundred = [size for cycles, size in sizes if cycles >= 100]
    print(f"goal: < 5 MB for >= 100 cycles -> {'met' if max(hundred) < 5e6 else 'NOT met'}")

    view = LiveView()
    view.start(default)

    def with_view() -> None:
        view.start(default)
        plan(default, on_cycle=view.cycle)

    t_bare, t_view = interleaved(lambda: plan(default), with_view, REPEATS)
    assert view.meshcat.GetNumActiveConnections() == 0
    print(f"\nlive view, no browser connected (default plan, {REPEATS} interleaved pairs)")
    print(table([("plan", t_bare, 1.0), ("plan + live view", t_view, t_view / t_bare)], "plan"))
    print(f"goal: <= 10 % more -> {'met' if t_view <= 1.10 * t_bare else 'NOT met'}")

    t_board, t_pose = interleaved(
        lambda: controller_run(default, False), lambda: controller_run(default, True), REPEATS
    )
    print(f"\nthe hand's configuration in the records (controller run, {REPEATS} interleaved pairs)")
    print(table([("plain Board", t_board, 1.0), ("PoseBoard (hand_q)", t_pose, t_pose / t_board)], "Board"))
    return 0


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    sys.exit(main())
