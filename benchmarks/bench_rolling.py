"""Per-step time of EP1's rolling step and the time of one EP1 run, with every backend side by
side and, with ``--baseline REV``, the code of an earlier git revision measured in the same run.

One step = kinematics (Pinocchio), contact (coal), tactile reading, the QP, integration.
Run: ``.venv/bin/python benchmarks/bench_rolling.py [--baseline a69a74f] [--steps N]``.

Rows (timed in interleaved rounds: the machine is shared, drift hits every row alike):
``as used`` — the default: the closed form when no bound is active, else OSQP through qpsolvers;
``<backend> every step`` — ``closed_form=False``, each installed qpsolvers backend on every
step's Problem; ``baseline REV`` — the default step of that revision. Then one EP1 run as the
planner calls it (omega 2 rad/s, dt 10 ms, 16 steps per direction, directions 0° and 90°: 64
steps), timed by the process's CPU clock: as used, with OSQP at every step (what the closed form
buys), and at the baseline.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import qpsolvers

import eos_svc.kinematics as kin_now
import eos_svc.kinematics.ep1
import eos_svc.kinematics.rolling  # noqa: F401  (kin_now.rolling)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _baseline import load_kinematics

EP1_KW: dict[str, Any] = {"omega": 2.0, "dt": 0.01, "steps_per_direction": 16, "directions": (0.0, 90.0)}


class Stepper:
    """Back-and-forth rolls of finger1 on a 4 cm sphere; ``run(n)`` times ``n`` more steps."""

    def __init__(self, kin: ModuleType, solver: str = "osqp", leg: int = 50, **options: Any) -> None:
        self.kin, self.solver, self.leg, self.options = kin, solver, leg, options
        self.sc = kin.ep1.ep1_scene("sphere", 0.04)
        self.st = self.sc.hand.state(kin.ep1.place_hand_for_ep1(self.sc, "finger1"))
        self.F = kin.ep1.contact_frame(self.sc.contact(self.st, "finger1").normal)
        self.sensor = kin.TactileSensor(2e-4, rng=0)
        self.sign, self.k = 1.0, leg
        self.rq: Any = None
        self.worst = 0.0

    def _new_leg(self) -> None:
        if self.rq is not None:
            self.st.update(self.rq.q)
        self.rq = self.kin.rolling.RollingQP(
            self.st, "finger1", self.F[:, 0], self.sign * 0.5, 0.01, self.solver,
            scene=self.sc, tactile=self.sensor, project_axis=False, **self.options,
        )  # fmt: skip
        self.sign, self.k = -self.sign, 0

    def run(self, n: int) -> list[float]:
        times = []
        for _ in range(n):
            if self.k >= self.leg:
                self._new_leg()
            step = self.rq.step
            t0 = time.perf_counter()
            s = step()
            times.append(time.perf_counter() - t0)
            self.k += 1
            self.worst = max(self.worst, s.slip_speed)
        return times


def ep1_runner(kin: ModuleType) -> Callable[[], Any]:
    """One EP1 run on a 4 cm sphere from the same start, as the planner calls it."""
    sc = kin.ep1.ep1_scene("sphere", 0.04)
    q0 = kin.ep1.place_hand_for_ep1(sc, "finger1")
    st = sc.hand.state(q0)
    sensor = kin.TactileSensor(2e-4, rng=0)

    def run() -> Any:
        st.update(q0)
        return kin.ep1.run_ep1(sc, st, "finger1", sensor, **EP1_KW)

    return run


def osqp_every_step(run: Callable[[], Any]) -> Callable[[], Any]:
    """``run`` with the closed form switched off (every step through the qpsolvers backend)."""
    rolling: Any = kin_now.rolling
    solve = rolling.solve_rolling_qp

    def backend_only(qp: Any, solver: str, closed_form: bool) -> Any:
        return solve(qp, solver, False)

    def without_closed_form() -> Any:
        rolling.solve_rolling_qp = backend_only
        try:
            return run()
        finally:
            rolling.solve_rolling_qp = solve

    return without_closed_form


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    p.add_argument("--steps", type=int, default=2000, help="timed steps per row")
    p.add_argument("--runs", type=int, default=31, help="timed EP1 runs per row")
    p.add_argument("--baseline", default=None, help="git revision to time beside the current code")
    a = p.parse_args(argv)
    base = load_kinematics(a.baseline) if a.baseline else None
    rows: list[tuple[str, Stepper]] = [
        ("as used (closed form, else osqp)", Stepper(kin_now)),
        *[(f"{s} every step", Stepper(kin_now, s, closed_form=False)) for s in qpsolvers.available_solvers],
    ]
    if base is not None:
        rows.insert(1, (f"baseline {a.baseline} (as used then)", Stepper(base)))
    times: dict[str, list[float]] = {name: [] for name, _ in rows}
    rounds = 20
    for _ in range(rounds):
        for name, stepper in rows:
            times[name] += stepper.run(max(1, a.steps // rounds))
    med0 = 1e6 * statistics.median(times[rows[0][0]])
    print("EP1 rolling step (kinematics + contact + tactile + QP + integration), sphere R = 4 cm")
    print(f"{'row':<40}{'median µs':>11}{'ratio':>8}{'max no-slip residual m/s':>27}")
    for name, stepper in rows:
        med = 1e6 * statistics.median(times[name])
        print(f"{name:<40}{med:>11.1f}{med / med0:>8.2f}{stepper.worst:>27.1e}")

    current = ep1_runner(kin_now)
    runners = [("current", current), ("current, osqp every step", osqp_every_step(current))]
    if base is not None:
        runners.append((f"baseline {a.baseline}", ep1_runner(base)))
    ep1_ms: dict[str, list[float]] = {name: [] for name, _ in runners}
    for _, f in runners:
        f()  # warm up
    for _ in range(a.runs):
        for name, f in runners:
            t0 = time.process_time()  # CPU time: a run is long enough to be preempted on a loaded machine
            f()
            ep1_ms[name].append(1e3 * (time.process_time() - t0))
    print(f"\nEP1 run as the planner calls it ({EP1_KW}), CPU time, median of {a.runs} runs:")
    cur = statistics.median(ep1_ms["current"])
    for name, _ in runners:
        med = statistics.median(ep1_ms[name])
        print(f"  {name:<32}{med:8.2f} ms   ratio to current {med / cur:5.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
