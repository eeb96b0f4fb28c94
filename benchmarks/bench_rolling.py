"""Per-step time of EP1's rolling step: OSQP as used, every other backend, naive solve_qp.

One step = kinematics (Pinocchio), contact (coal), tactile reading, QP, integration.
Run: ``.venv/bin/python benchmarks/bench_rolling.py`` (``--steps N`` for more samples).

Rows: ``osqp (as used)`` — one OSQP object per roll, updated and warm-started, eps 1e-9;
each other installed qpsolvers backend through ``qpsolvers.solve_problem`` on the same live
Problem; ``solve_qp osqp (naive)`` — ``qpsolvers.solve_qp(..., solver="osqp")`` every step
(OSQP set up from scratch, default tolerances). Also the breakdown of the OSQP step.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable

import numpy as np
import qpsolvers

from eos_svc.kinematics import TactileSensor
from eos_svc.kinematics.ep1 import contact_frame, ep1_scene, place_hand_for_ep1
from eos_svc.kinematics.rolling import RollingQP, RollingQPError


def _naive_solve(rq: RollingQP) -> Callable[[], tuple[np.ndarray, int]]:
    def solve() -> tuple[np.ndarray, int]:
        p = rq.problem
        x = qpsolvers.solve_qp(p.P, p.q, None, None, p.A, p.b, p.lb, p.ub, solver="osqp")
        if x is None:
            raise RollingQPError("no solution", rq.problem_copy(), "osqp (naive)", "None")
        return x, 0

    return solve


def time_steps(solver: str, n_steps: int, leg: int = 50, naive: bool = False) -> tuple[list[float], float]:
    """Per-step wall times (s) over back-and-forth rolls, and the largest no-slip residual."""
    sc = ep1_scene("sphere", 0.04)
    st = sc.hand.state(place_hand_for_ep1(sc, "finger1"))
    F = contact_frame(sc.contact(st, "finger1").normal)
    sensor = TactileSensor(2e-4, rng=0)
    times: list[float] = []
    worst = 0.0
    sign = 1.0
    pc = time.perf_counter
    while len(times) < n_steps:
        rq = RollingQP(
            st,
            "finger1",
            F[:, 0],
            sign * 0.5,
            0.01,
            "osqp" if naive else solver,
            scene=sc,
            tactile=sensor,
            project_axis=False,
        )
        if naive:
            rq._solve_osqp = _naive_solve(rq)  # type: ignore[method-assign]
        for _ in range(leg):
            t0 = pc()
            s = rq.step()
            times.append(pc() - t0)
            worst = max(worst, s.slip_speed)
        st.update(rq.q)
        sign = -sign
    return times[leg // 5 :], worst  # drop the first steps (setup of the first roll)


def breakdown(n: int = 2000) -> dict[str, float]:
    """Median µs of each part of the OSQP step."""
    sc = ep1_scene("sphere", 0.04)
    st = sc.hand.state(place_hand_for_ep1(sc, "finger1"))
    F = contact_frame(sc.contact(st, "finger1").normal)
    parts: dict[str, list[float]] = {k: [] for k in ("kinematics", "contact", "tactile", "build", "osqp")}
    pc = time.perf_counter
    sign = 1.0
    done = 0
    while done < n:
        rq = RollingQP(
            st,
            "finger1",
            F[:, 0],
            sign * 0.5,
            0.01,
            scene=sc,
            tactile=TactileSensor(2e-4, rng=0),
            project_axis=False,
        )
        for _ in range(50):
            t0 = pc()
            rq.kinematics()
            t1 = pc()
            c = rq.contact()
            t2 = pc()
            rq.read_tactile(c)
            t3 = pc()
            rq._build(c)
            t4 = pc()
            rq._solve_osqp()
            t5 = pc()
            rq.step()  # advance (not timed here)
            for k, a, b in (
                ("kinematics", t0, t1),
                ("contact", t1, t2),
                ("tactile", t2, t3),
                ("build", t3, t4),
                ("osqp", t4, t5),
            ):
                parts[k].append(b - a)
        done += 50
        st.update(rq.q)
        sign = -sign
    return {k: 1e6 * statistics.median(v) for k, v in parts.items()}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--steps", type=int, default=2000, help="timed steps per row")
    a = p.parse_args(argv)
    rows: list[tuple[str, float, float, float]] = []
    for name, solver, naive, n in [
        ("osqp (as used)", "osqp", False, a.steps),
        *[(f"{s} (solve_problem)", s, False, a.steps) for s in qpsolvers.available_solvers if s != "osqp"],
        ("solve_qp osqp (naive)", "osqp", True, max(200, a.steps // 10)),
    ]:
        ts, worst = time_steps(solver, n, naive=naive)
        rows.append((name, 1e6 * statistics.median(ts), 1e6 * float(np.percentile(ts, 90)), worst))
    base = rows[0][1]
    print("EP1 rolling step (kinematics + contact + tactile + QP + integration), sphere R = 4 cm")
    print(f"{'backend':<26}{'median µs':>11}{'p90 µs':>10}{'ratio':>8}{'max no-slip residual m/s':>27}")
    for name, med, p90, worst in rows:
        print(f"{name:<26}{med:>11.1f}{p90:>10.1f}{med / base:>8.2f}{worst:>27.1e}")
    print("\nbreakdown of the osqp step (median µs):")
    for k, v in breakdown(min(a.steps, 2000)).items():
        print(f"  {k:<12}{v:8.1f}")
    # machine calibration against DESIGN §7 (np.cross on 3-vectors ≈ 16 µs there)
    import timeit

    x, y = np.ones(3), np.ones(3)
    cross = min(timeit.repeat(lambda: np.cross(x, y), number=2000, repeat=5)) / 2000 * 1e6
    scale = 16.0 / cross
    print(f"\ncalibration: np.cross on 3-vectors {cross:.1f} µs here vs ≈16 µs on the DESIGN §7 machine")
    print(f"osqp step scaled to that machine ≈ {rows[0][1] * scale:.0f} µs (goal: <= 60 µs median)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
