"""EP2's guarded probes: the default plan's probes replayed with today's ``guarded_probe`` (its
shortcut: the other geometries' exact gaps skipped while a lower bound fixes the step) and with
the plain conservative advancement (every other geometry queried at every sub-step: the reference
of ``tests/agents/test_guarded_probe.py``), interleaved in the same run.

    .venv/bin/python benchmarks/bench_probes.py [--rounds 40]

The default plan (``PlanRequest()``) is planned once and every ``probe_motion.guarded_probe`` call
it makes is recorded (world and arguments; a probe sets the whole configuration it moves from, so
a replay does the same work). Each round replays all probes with one version, then the other (the
machine is shared: only same-run ratios mean much); the outcomes of both are compared. Prints the
median time per replay (all probes), the ratio, and the exact gap queries of the other geometries
(``min_gap`` calls) per replay.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import eos_svc.world.world as world_module
from eos_svc.agents import PlanRequest, plan
from eos_svc.world import probe_motion

ROOT = Path(__file__).resolve().parents[1]


def plain_probe() -> Callable[..., Any]:
    """The plain conservative advancement of ``tests/agents/test_guarded_probe.py``."""
    sys.path.insert(0, str(ROOT / "tests" / "agents"))
    from test_guarded_probe import plain_guarded_probe

    probe: Callable[..., Any] = plain_guarded_probe
    return probe


def recorded_probes() -> tuple[list[tuple[Any, tuple[Any, ...]]], np.ndarray]:
    """(world, arguments) of every guarded probe of the default plan, and the hand's
    configuration before the first (a probe's start depends on where the hand was, to the bit)."""
    calls: list[tuple[Any, tuple[Any, ...]]] = []
    first: list[np.ndarray] = []
    current = probe_motion.guarded_probe

    def record(self: Any, *args: Any) -> Any:
        if not calls:
            first.append(self.state.q)
        calls.append((self, args))
        return current(self, *args)

    probe_motion.guarded_probe = record
    try:
        plan(PlanRequest())
    finally:
        probe_motion.guarded_probe = current
    return calls, first[0]


def _bits(out: Any) -> tuple[Any, ...]:
    def h(x: Any) -> Any:
        return None if x is None else np.asarray(x, dtype=float).tobytes()

    return out.event, out.why, h(out.centre), h(out.normal), h(out.free), float(out.travelled)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=40, help="interleaved rounds (each replays all probes)")
    args = parser.parse_args(argv)
    calls, q0 = recorded_probes()
    versions = {
        "current": probe_motion.guarded_probe,
        "plain": plain_probe(),
    }
    # each version's checked replay starts from the same hand configuration and the same state of
    # the sensor's generator (a touch draws its tactile noise)
    sensors = {id(w.sensor): w.sensor for w, _ in calls}
    start = {k: sensor.rng.bit_generator.state for k, sensor in sensors.items()}
    queries = {name: 0 for name in versions}
    outcomes: dict[str, list[Any]] = {}
    min_gap = world_module.GraspWorld.min_gap
    for name, probe in versions.items():  # untimed: outcomes and the gap queries they take
        count = [0]

        def counted(self: Any, ids: Any, best: float, count: list[int] = count) -> float:
            count[0] += 1
            return min_gap(self, ids, best)

        world_module.GraspWorld.min_gap = counted  # type: ignore[method-assign]
        for k, sensor in sensors.items():
            sensor.rng.bit_generator.state = start[k]
        for w in {id(w): w for w, _ in calls}.values():
            w.set_q(q0)
        try:
            outcomes[name] = [_bits(probe(w, *a)) for w, a in calls]
        finally:
            world_module.GraspWorld.min_gap = min_gap  # type: ignore[method-assign]
        queries[name] = count[0]
    names = list(versions)
    same = outcomes[names[0]] == outcomes[names[1]]
    times: dict[str, list[float]] = {name: [] for name in versions}
    for _ in range(args.rounds):
        for name, probe in versions.items():
            t0 = time.perf_counter()
            for w, a in calls:
                probe(w, *a)
            times[name].append(time.perf_counter() - t0)
    cur = statistics.median(times["current"])
    print(f"the default plan's {len(calls)} guarded probes replayed, {args.rounds} rounds, median:")
    for name in versions:
        med = statistics.median(times[name])
        calls_text = f"{queries[name]:4d} exact min-gap calls"
        print(f"  {name:<24}{med * 1e3:8.2f} ms   ratio {med / cur:5.2f}   {calls_text}")
    print(f"outcomes identical bit for bit: {same}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
