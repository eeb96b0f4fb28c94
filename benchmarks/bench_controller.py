"""Arbitration cost per cycle: the EOS controller vs a py_trees Selector, same run.

    .venv/bin/python benchmarks/bench_controller.py

EOS: 8 agents, 2 sub-ratings (default + opportunistic, learned weight 0), every
agent's precondition test returns its stored opportunistic value, the chosen
action is a no-op reporting progress; per cycle the controller rates all 8,
chooses, runs the action, records the cycle (trace kept). py_trees: a Selector
over 8 behaviours, the first 7 FAILURE and the last SUCCESS (a full scan, as
rating all 8), ticked with ``tick_once``. Goal: EOS ≤ 0.15× the py_trees tick.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _harness import median_of, table

from eos_svc import ActionResult, Agent, Board, Controller, CycleContext, Outcome, Weights

N_AGENTS = 8
CYCLES = 2000
REPEATS = 15


class Bench(Agent):
    """Precondition returns a fixed value; action is a no-op."""

    def __init__(self, i: int) -> None:
        super().__init__(f"agent{i}", ["s"], default=0.1 + 0.1 * i)
        self.value = 0.05 * i
        self._result = ActionResult(Outcome.PROGRESS, "noop")

    def opportunistic(self, board: Board, ctx: CycleContext) -> float | None:
        return self.value

    def act(self, board: Board, ctx: CycleContext) -> ActionResult:
        return self._result


def eos_per_cycle() -> float:
    controller = Controller([Bench(i) for i in range(N_AGENTS)], ["s"], Weights(0.5, 0.5), max_cycles=CYCLES)
    samples = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        result = controller.run(Board())
        samples.append((time.perf_counter() - t0) / result.cycles)
    return median_of(samples)


def py_trees_per_tick() -> float | None:
    try:
        import py_trees
    except ImportError:
        return None
    children = [
        py_trees.behaviours.Failure(name=f"b{i}")
        if i < N_AGENTS - 1
        else py_trees.behaviours.Success(name="b7")
        for i in range(N_AGENTS)
    ]
    root = py_trees.composites.Selector(name="sel", memory=False, children=children)
    root.setup_with_descendants()
    samples = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        for _ in range(CYCLES):
            root.tick_once()
        samples.append((time.perf_counter() - t0) / CYCLES)
    return median_of(samples)


def main() -> int:
    eos_per_cycle()  # warm-up
    eos = eos_per_cycle()
    bt = py_trees_per_tick()
    print(f"arbitration per cycle, {N_AGENTS} agents, median of {REPEATS} runs x {CYCLES} cycles")
    if bt is None:
        print(table([("EOS controller cycle", eos, None)], "py_trees (not installed)"))
        return 0
    print(table([("py_trees Selector tick", bt, 1.0), ("EOS controller cycle", eos, eos / bt)], "py_trees"))
    goal = 0.15
    print(f"goal: EOS <= {goal}x py_trees -> {'met' if eos / bt <= goal else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
